//! The per-axis superquadric isopotential, in any dimension.

use super::{Isopotential, abs_pow, signed_pow};
use crate::error::{InvalidInput, Result};

/// A superquadric with one exponent per axis: `n_i = 1` everywhere is an ellipsoid, `n_i = 2` a rounded box,
/// exponents `(1, 1, 2)` a rounded cylinder.
///
/// # Formula
/// `C(y) = sum_i (y_i / a_i)^(2 n_i) - 1` (ERRATA.md, "Isopotentials"), with
/// `dC/dy_i = (2 n_i / a_i) (y_i / a_i)^(2 n_i - 1)` and a diagonal Hessian
/// `d2C/dy_i2 = (2 n_i (2 n_i - 1) / a_i^2) (y_i / a_i)^(2 n_i - 2)`.
///
/// ```
/// use dmp::isopotential::{Isopotential, Superquadric};
/// let ellipse = Superquadric::new(vec![0.3, 0.2], vec![1.0, 1.0]).unwrap();
/// assert!(ellipse.value(&[0.3, 0.0]).abs() < 1e-15);
/// assert!((ellipse.value(&[0.0, 0.0]) + 1.0).abs() < 1e-15);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Superquadric {
    semi_axes: Vec<f64>,
    exponents: Vec<f64>,
    /// Per axis: `1 / a_i`, `2 n_i`, and `n_i - 1` when `n_i` is an integer (the fast path).
    axes: Vec<Axis>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct Axis {
    inv_a: f64,
    two_n: f64,
    int_n1: Option<u32>,
}

impl Axis {
    /// `|q|^(2n - 2)`.
    #[inline]
    fn q_2n2(&self, q: f64) -> f64 {
        match self.int_n1 {
            Some(k) => ipow(q * q, k),
            None => abs_pow(q, self.two_n - 2.0),
        }
    }
}

/// `x^k` by repeated squaring, inlined (no libm or compiler-runtime call for the small integer powers of
/// superquadrics and avoidance exponents). The same products, in the same order, as a runtime `powi`.
#[inline]
pub(crate) fn ipow(mut x: f64, mut k: u32) -> f64 {
    let mut acc = 1.0;
    while k > 0 {
        if k & 1 == 1 {
            acc *= x;
        }
        x *= x;
        k >>= 1;
    }
    acc
}

impl Superquadric {
    /// Semi-axes `a_i > 0` and exponents `n_i >= 1` (real values allowed; integers are the usual case).
    pub fn new(semi_axes: Vec<f64>, exponents: Vec<f64>) -> Result<Self> {
        if semi_axes.is_empty() {
            return Err(InvalidInput::new("semi_axes", "must have at least one entry").into());
        }
        if exponents.len() != semi_axes.len() {
            return Err(InvalidInput::new(
                "exponents",
                format!("must have one entry per semi-axis ({}), found {}", semi_axes.len(), exponents.len()),
            )
            .into());
        }
        for (i, a) in semi_axes.iter().enumerate() {
            if !(a.is_finite() && *a > 0.0) {
                return Err(InvalidInput::new(
                    format!("semi_axes[{i}]"),
                    "must be a finite number greater than zero",
                )
                .into());
            }
        }
        for (i, n) in exponents.iter().enumerate() {
            if !(n.is_finite() && *n >= 1.0) {
                return Err(
                    InvalidInput::new(format!("exponents[{i}]"), "must be a finite number >= 1").into()
                );
            }
        }
        let axes = semi_axes
            .iter()
            .zip(&exponents)
            .map(|(a, n)| Axis {
                inv_a: 1.0 / a,
                two_n: 2.0 * n,
                int_n1: (n.fract() == 0.0 && *n <= 64.0).then_some(*n as u32 - 1),
            })
            .collect();
        Ok(Self { semi_axes, exponents, axes })
    }

    /// An ellipsoid (all exponents 1).
    pub fn ellipsoid(semi_axes: Vec<f64>) -> Result<Self> {
        let n = vec![1.0; semi_axes.len()];
        Self::new(semi_axes, n)
    }

    /// The semi-axes `a_i`.
    pub fn semi_axes(&self) -> &[f64] {
        &self.semi_axes
    }

    /// The exponents `n_i`.
    pub fn exponents(&self) -> &[f64] {
        &self.exponents
    }

    /// One axis' share of the isopotential at the local coordinate `y_i`: its term of `C` (without the `- 1`),
    /// of the gradient, and of the diagonal Hessian.
    #[inline]
    pub(crate) fn axis_terms(&self, i: usize, y_i: f64) -> (f64, f64, f64) {
        let ax = self.axes[i];
        let q = y_i * ax.inv_a;
        let q_2n2 = ax.q_2n2(q);
        let q_2n1 = q * q_2n2;
        (q_2n1 * q, ax.two_n * ax.inv_a * q_2n1, ax.two_n * (ax.two_n - 1.0) * ax.inv_a * ax.inv_a * q_2n2)
    }

    /// Every semi-axis enlarged by `margin`.
    pub fn inflated(&self, margin: f64) -> Result<Self> {
        Self::new(self.semi_axes.iter().map(|a| a + margin).collect(), self.exponents.clone())
    }
}

impl Isopotential for Superquadric {
    fn dim(&self) -> usize {
        self.semi_axes.len()
    }

    fn value(&self, y: &[f64]) -> f64 {
        let mut c = -1.0;
        for (yi, ax) in y.iter().zip(&self.axes) {
            let q = yi * ax.inv_a;
            c += ax.q_2n2(q) * q * q;
        }
        c
    }

    fn eval(&self, y: &[f64], grad: &mut [f64], hess: &mut [f64]) -> f64 {
        let d = self.dim();
        hess[..d * d].fill(0.0);
        let mut c = -1.0;
        for (i, ax) in self.axes.iter().enumerate() {
            let q = y[i] * ax.inv_a;
            let q_2n2 = ax.q_2n2(q);
            let q_2n1 = q * q_2n2;
            c += q_2n1 * q;
            grad[i] = ax.two_n * ax.inv_a * q_2n1;
            hess[i * d + i] = ax.two_n * (ax.two_n - 1.0) * ax.inv_a * ax.inv_a * q_2n2;
        }
        c
    }

    fn surface_point(&self, w: &[f64], out: &mut [f64]) {
        for i in 0..self.dim() {
            out[i] = self.semi_axes[i] * signed_pow(w[i], 1.0 / self.exponents[i]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_support::check_derivatives;
    use super::*;

    #[test]
    fn derivatives_match_finite_differences() {
        let shapes = [
            Superquadric::new(vec![0.3, 0.2], vec![1.0, 1.0]).unwrap(),
            Superquadric::new(vec![0.3, 0.2, 0.5], vec![2.0, 2.0, 2.0]).unwrap(),
            Superquadric::new(vec![0.05, 0.05, 0.2], vec![1.0, 1.0, 2.0]).unwrap(),
            Superquadric::new(vec![1.0, 0.4, 0.7, 0.2], vec![1.5, 3.0, 1.0, 2.0]).unwrap(),
        ];
        for s in &shapes {
            let d = s.dim();
            for k in 0..10 {
                let y: Vec<f64> = (0..d).map(|i| 0.37 * ((k * 7 + i * 3) as f64).sin() - 0.05).collect();
                check_derivatives(s, &y);
            }
        }
    }

    #[test]
    fn surface_points_lie_on_the_surface() {
        let s = Superquadric::new(vec![0.3, 0.2, 0.5], vec![1.0, 2.0, 3.0]).unwrap();
        let mut p = [0.0; 3];
        for k in 0..20 {
            let (th, ph) = (k as f64 * 0.7, k as f64 * 0.3 - 1.0);
            let w = [th.cos() * ph.cos(), th.sin() * ph.cos(), ph.sin()];
            s.surface_point(&w, &mut p);
            assert!(s.value(&p).abs() < 1e-12);
        }
    }

    #[test]
    fn bad_shapes_are_refused() {
        assert!(Superquadric::new(vec![0.3, -0.2], vec![1.0, 1.0]).is_err());
        assert!(Superquadric::new(vec![0.3, 0.2], vec![1.0, 0.5]).is_err());
        assert!(Superquadric::new(vec![0.3, 0.2], vec![1.0]).is_err());
        let e = Superquadric::new(vec![0.3, 0.2], vec![1.0, 0.5]).unwrap_err();
        assert!(e.to_string().contains("exponents[1]"));
    }
}
