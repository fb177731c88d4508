//! The paper's nested superquadric, in 3-D.

use super::{Isopotential, abs_pow, signed_pow};
use crate::error::{InvalidInput, Result};

/// Below this value of `P` the first two axes are treated as being on the symmetry axis.
const P_TINY: f64 = 1e-250;

/// The generalized ellipsoid of `eq:isopot_gen_ell` (with the `- 1` that the paper's example omits).
///
/// # Formula
/// With `q_i = y_i / a_i` and `P = q_1^(2n) + q_2^(2n)`:
/// `C = P^(m/n) + q_3^(2m) - 1`,
/// `dC/dy_j = (2m / a_j) P^(m/n - 1) q_j^(2n - 1)` for `j = 1, 2`, `dC/dy_3 = (2m / a_3) q_3^(2m - 1)`,
/// `d2C/dy_j dy_k = (4m (m - n) / (a_j a_k)) P^(m/n - 2) q_j^(2n-1) q_k^(2n-1)
///                 + [j = k] (2m (2n - 1) / a_j^2) P^(m/n - 1) q_j^(2n - 2)`,
/// `d2C/dy_3^2 = (2m (2m - 1) / a_3^2) q_3^(2m - 2)`. It equals the per-axis form only for `m = n = 1`.
#[derive(Debug, Clone, PartialEq)]
pub struct NestedSuperquadric {
    semi_axes: [f64; 3],
    n: f64,
    m: f64,
}

impl NestedSuperquadric {
    /// Semi-axes `a_i > 0` and exponents `n, m >= 1`.
    pub fn new(semi_axes: [f64; 3], n: f64, m: f64) -> Result<Self> {
        for (i, a) in semi_axes.iter().enumerate() {
            if !(a.is_finite() && *a > 0.0) {
                return Err(InvalidInput::new(
                    format!("semi_axes[{i}]"),
                    "must be a finite number greater than zero",
                )
                .into());
            }
        }
        for (name, v) in [("nested.n", n), ("nested.m", m)] {
            if !(v.is_finite() && v >= 1.0) {
                return Err(InvalidInput::new(name, "must be a finite number >= 1").into());
            }
        }
        Ok(Self { semi_axes, n, m })
    }

    /// The semi-axes.
    pub fn semi_axes(&self) -> &[f64] {
        &self.semi_axes
    }

    /// The exponents `(n, m)`.
    pub fn exponents(&self) -> (f64, f64) {
        (self.n, self.m)
    }

    /// Every semi-axis enlarged by `margin`.
    pub fn inflated(&self, margin: f64) -> Result<Self> {
        Self::new(self.semi_axes.map(|a| a + margin), self.n, self.m)
    }
}

impl Isopotential for NestedSuperquadric {
    fn dim(&self) -> usize {
        3
    }

    fn value(&self, y: &[f64]) -> f64 {
        let [a1, a2, a3] = self.semi_axes;
        let p = abs_pow(y[0] / a1, 2.0 * self.n) + abs_pow(y[1] / a2, 2.0 * self.n);
        p.powf(self.m / self.n) + abs_pow(y[2] / a3, 2.0 * self.m) - 1.0
    }

    fn eval(&self, y: &[f64], grad: &mut [f64], hess: &mut [f64]) -> f64 {
        let (n, m) = (self.n, self.m);
        let a = self.semi_axes;
        let q = [y[0] / a[0], y[1] / a[1], y[2] / a[2]];
        hess[..9].fill(0.0);
        let q2n2 = [abs_pow(q[0], 2.0 * n - 2.0), abs_pow(q[1], 2.0 * n - 2.0)];
        let q2n1 = [q[0] * q2n2[0], q[1] * q2n2[1]];
        let p = q2n1[0] * q[0] + q2n1[1] * q[1];
        let q3_2m2 = abs_pow(q[2], 2.0 * m - 2.0);
        let q3_2m1 = q[2] * q3_2m2;
        let mut c = q3_2m1 * q[2] - 1.0;
        grad[2] = 2.0 * m / a[2] * q3_2m1;
        hess[8] = 2.0 * m * (2.0 * m - 1.0) / (a[2] * a[2]) * q3_2m2;
        if p > P_TINY {
            let p_mn = p.powf(m / n);
            let p_mn1 = p_mn / p;
            let p_mn2 = p_mn1 / p;
            c += p_mn;
            for j in 0..2 {
                grad[j] = 2.0 * m / a[j] * p_mn1 * q2n1[j];
                for k in 0..2 {
                    // `P^(m/n - 2)` alone overflows near the symmetry axis when `m < n`; the product with
                    // `q_j^(2n-1) q_k^(2n-1) <= P^(2 - 1/n)` does not, so it is then formed in another order.
                    let cross = if p_mn2.is_finite() {
                        p_mn2 * q2n1[j] * q2n1[k]
                    } else {
                        p_mn1 * q2n1[j] / p * q2n1[k]
                    };
                    let mut h = 4.0 * m * (m - n) / (a[j] * a[k]) * cross;
                    if j == k {
                        h += 2.0 * m * (2.0 * n - 1.0) / (a[j] * a[j]) * p_mn1 * q2n2[j];
                    }
                    hess[j * 3 + k] = h;
                }
            }
        } else {
            grad[0] = 0.0;
            grad[1] = 0.0;
        }
        c
    }

    fn surface_point(&self, w: &[f64], out: &mut [f64]) {
        // Split the unit vector as rho^2 = w1^2 + w2^2 and w3^2, then solve each level of the nesting.
        let (n, m) = (self.n, self.m);
        let a = self.semi_axes;
        let rho2 = w[0] * w[0] + w[1] * w[1];
        for j in 0..2 {
            // (q_j)^(2n) = rho^(2n/m) * w_j^2 / rho^2.
            let t = if rho2 > 0.0 { rho2.powf(n / m) * w[j] * w[j] / rho2 } else { 0.0 };
            out[j] = a[j] * w[j].signum() * t.powf(1.0 / (2.0 * n));
        }
        out[2] = a[2] * signed_pow(w[2], 1.0 / m);
    }
}

#[cfg(test)]
mod tests {
    use super::super::Superquadric;
    use super::super::test_support::check_derivatives;
    use super::*;

    #[test]
    fn derivatives_match_finite_differences() {
        for (n, m) in [(1.0, 1.0), (2.0, 1.0), (1.0, 2.0), (2.0, 3.0), (3.0, 2.0)] {
            let s = NestedSuperquadric::new([0.3, 0.2, 0.5], n, m).unwrap();
            for k in 0..10 {
                let y: Vec<f64> = (0..3).map(|i| 0.41 * ((k * 5 + i * 2 + 1) as f64).cos() + 0.03).collect();
                check_derivatives(&s, &y);
            }
        }
    }

    #[test]
    fn equals_the_per_axis_form_for_unit_exponents() {
        let a = NestedSuperquadric::new([0.3, 0.2, 0.5], 1.0, 1.0).unwrap();
        let b = Superquadric::ellipsoid(vec![0.3, 0.2, 0.5]).unwrap();
        for y in [[0.1, 0.2, 0.3], [-0.4, 0.0, 0.1], [0.0, 0.0, 0.0]] {
            assert!((a.value(&y) - b.value(&y)).abs() < 1e-14);
        }
    }

    #[test]
    fn surface_points_lie_on_the_surface_and_the_axis_is_finite() {
        let s = NestedSuperquadric::new([0.3, 0.2, 0.5], 2.0, 3.0).unwrap();
        let mut p = [0.0; 3];
        for k in 0..20 {
            let (th, ph) = (k as f64 * 0.7, k as f64 * 0.3 - 1.0);
            let w = [th.cos() * ph.cos(), th.sin() * ph.cos(), ph.sin()];
            s.surface_point(&w, &mut p);
            assert!(s.value(&p).abs() < 1e-12, "{p:?}");
        }
        let (mut g, mut h) = ([0.0; 3], [0.0; 9]);
        let c = s.eval(&[0.0, 0.0, 0.7], &mut g, &mut h);
        assert!(c.is_finite() && g.iter().chain(&h).all(|v| v.is_finite()));
    }
}
