//! The hot path: the dynamic volumetric term of a per-axis superquadric in 2-D or 3-D, on fixed-size arrays.
//!
//! Same formula as [`crate::avoidance::dynamic_volumetric::add_force`] (ERRATA.md, term 5), evaluated in the
//! obstacle's frame where the Hessian of a per-axis superquadric is diagonal, then rotated back; the general path
//! and this one agree to rounding (tested below).

use crate::avoidance::{DynamicVolumetric, Exponent};
use crate::isopotential::Superquadric;

use super::C_FLOOR;

/// A dynamic volumetric parameter set with its exponents classified once.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct DynamicVolumetricKernel {
    lambda: f64,
    beta: f64,
    eta: f64,
    beta_minus_one: Exponent,
    minus_eta: Exponent,
}

impl DynamicVolumetricKernel {
    pub(crate) fn new(p: &DynamicVolumetric) -> Self {
        Self {
            lambda: p.lambda,
            beta: p.beta,
            eta: p.eta,
            beta_minus_one: Exponent::new(p.beta - 1.0),
            minus_eta: Exponent::new(-p.eta),
        }
    }

    /// Adds the term of the obstacle `sq` (centre `center`, rotation `rotation`) at `x` with relative velocity `u`
    /// to `phi`. `D` must equal the slices' length.
    #[inline]
    pub(crate) fn add<const D: usize>(
        &self,
        sq: &Superquadric,
        rotation: Option<&[f64]>,
        center: &[f64],
        x: &[f64],
        u: &[f64],
        phi: &mut [f64],
    ) {
        let mut diff = [0.0; D];
        let mut uw = [0.0; D];
        for i in 0..D {
            diff[i] = x[i] - center[i];
            uw[i] = u[i];
        }
        let (y, ul) = match rotation {
            None => (diff, uw),
            Some(r) => (mul_t::<D>(r, &diff), mul_t::<D>(r, &uw)),
        };
        let mut g = [0.0; D];
        let mut h = [0.0; D];
        let mut c = -1.0;
        for i in 0..D {
            let (cq, gq, hq) = sq.axis_terms(i, y[i]);
            c += cq;
            g[i] = gq;
            h[i] = hq;
        }
        let c = c.max(C_FLOOR);
        let mut gu = 0.0;
        let mut gg = 0.0;
        let mut uu = 0.0;
        for i in 0..D {
            gu += g[i] * ul[i];
            gg += g[i] * g[i];
            uu += ul[i] * ul[i];
        }
        if gu >= 0.0 || gg == 0.0 || uu == 0.0 {
            return;
        }
        let (gn, un) = (gg.sqrt(), uu.sqrt());
        let cos = gu / (gn * un);
        let k = self.lambda * un * self.beta_minus_one.pow(-cos) * self.minus_eta.pow(c);
        let inv = 1.0 / (un * gg);
        let mut f = [0.0; D];
        for i in 0..D {
            let grad_cos = (h[i] * ul[i] * gn - gu * h[i] * g[i] / gn) * inv;
            f[i] = k * (self.beta * grad_cos - self.eta * cos * g[i] / c);
        }
        match rotation {
            None => (0..D).for_each(|i| phi[i] += f[i]),
            Some(r) => {
                for i in 0..D {
                    let mut acc = 0.0;
                    for j in 0..D {
                        acc += r[i * D + j] * f[j];
                    }
                    phi[i] += acc;
                }
            }
        }
    }
}

/// `R^T v` for a row-major `D x D` matrix.
#[inline]
fn mul_t<const D: usize>(r: &[f64], v: &[f64; D]) -> [f64; D] {
    let r = &r[..D * D];
    let mut out = [0.0; D];
    for (k, vk) in v.iter().enumerate() {
        for i in 0..D {
            out[i] += r[k * D + i] * vk;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Obstacle;
    use crate::avoidance::dynamic_volumetric;
    use crate::isopotential::Shape;
    use crate::obstacle::{WorldEval, mat_vec, rotate, rotate_transposed};

    fn general(o: &Obstacle, x: &[f64], u: &[f64], p: &DynamicVolumetric) -> Vec<f64> {
        let d = x.len();
        let mut e = WorldEval::new(d);
        let c = e.eval_local(o.shape(), o.rotation(), o.center(), x).max(C_FLOOR);
        let mut ul = vec![0.0; d];
        rotate_transposed(o.rotation(), u, &mut ul);
        let (mut hu, mut hg, mut f, mut out) = (vec![0.0; d], vec![0.0; d], vec![0.0; d], vec![0.0; d]);
        mat_vec(&e.hy, &ul, &mut hu);
        mat_vec(&e.hy, &e.gy, &mut hg);
        dynamic_volumetric::add_force(c, &e.gy, &hu, &hg, &ul, p, &mut f);
        rotate(o.rotation(), &f, &mut out);
        out
    }

    #[test]
    fn matches_the_general_path() {
        let a = 0.7f64;
        let rot3 = vec![vec![a.cos(), -a.sin(), 0.0], vec![a.sin(), a.cos(), 0.0], vec![0.0, 0.0, 1.0]];
        let sq = Superquadric::new(vec![0.3, 0.2, 0.4], vec![1.0, 2.0, 1.5]).unwrap();
        let o = Obstacle::new("o", Shape::Superquadric(sq.clone()), vec![0.1, 0.2, -0.1], Some(rot3), None)
            .unwrap();
        for (p, eta) in [(2.0, 0.5), (1.0, 1.0), (3.3, 0.7)] {
            let params = DynamicVolumetric { lambda: 10.0, beta: p, eta };
            let kern = DynamicVolumetricKernel::new(&params);
            for k in 0..50 {
                let x: Vec<f64> = (0..3).map(|i| ((k * 3 + i) as f64 * 0.77).sin()).collect();
                let u: Vec<f64> = (0..3).map(|i| ((k * 5 + i) as f64 * 1.31).cos()).collect();
                let want = general(&o, &x, &u, &params);
                let mut got = vec![0.0; 3];
                kern.add::<3>(&sq, o.rotation(), o.center(), &x, &u, &mut got);
                for (g, w) in got.iter().zip(&want) {
                    assert!((g - w).abs() <= 1e-12 * (1.0 + w.abs()), "{got:?} vs {want:?}");
                }
            }
        }
    }

    /// The field (which takes this kernel for superquadrics in 3-D) gives the sum of the general path's terms,
    /// each at the obstacle's centre at time `t` and with the relative velocity `v - tau v_obstacle`.
    #[test]
    fn the_field_sums_the_general_terms_of_moving_obstacles() {
        use crate::field::{RepulsiveField, Scene};
        use crate::integrate::Perturbation;
        use crate::{Avoidance, Method};
        let params = DynamicVolumetric { lambda: 10.0, beta: 2.0, eta: 0.5 };
        let a = 0.4f64;
        let rot = vec![vec![a.cos(), -a.sin(), 0.0], vec![a.sin(), a.cos(), 0.0], vec![0.0, 0.0, 1.0]];
        let obstacles = vec![
            Obstacle::new(
                "box",
                Shape::Superquadric(Superquadric::new(vec![0.3, 0.2, 0.4], vec![2.0, 2.0, 1.0]).unwrap()),
                vec![0.5, 0.1, 0.0],
                Some(rot),
                Some(vec![0.2, -0.1, 0.05]),
            )
            .unwrap(),
            Obstacle::new(
                "ball",
                Shape::Superquadric(Superquadric::ellipsoid(vec![0.1; 3]).unwrap()),
                vec![-0.2, 0.6, 0.1],
                None,
                Some(vec![-0.3, 0.0, 0.1]),
            )
            .unwrap(),
            Obstacle::new(
                "still",
                Shape::Superquadric(Superquadric::ellipsoid(vec![0.2, 0.1, 0.3]).unwrap()),
                vec![0.9, 0.9, 0.9],
                None,
                None,
            )
            .unwrap(),
        ];
        let scene =
            Scene::with_obstacles(obstacles.clone(), Avoidance::new(Method::DynamicVolumetric(params)), 0);
        let mut field = RepulsiveField::new(scene, 3).unwrap();
        let tau = 1.5;
        let mut active = 0;
        for k in 0..30 {
            let t = 0.1 * k as f64;
            let x: Vec<f64> = (0..3).map(|i| ((k * 3 + i) as f64 * 0.61).sin()).collect();
            let v: Vec<f64> = (0..3).map(|i| ((k * 7 + i) as f64 * 0.93).cos()).collect();
            let mut got = vec![0.0; 3];
            field.add(t, &x, &v, tau, &mut got);
            let mut want = vec![0.0; 3];
            for o in &obstacles {
                let mut c = vec![0.0; 3];
                o.center_at(t, &mut c);
                let moved = o.with_center(c);
                let u: Vec<f64> = (0..3).map(|i| v[i] - tau * o.velocity()[i]).collect();
                for (w, f) in want.iter_mut().zip(general(&moved, &x, &u, &params)) {
                    *w += f;
                }
            }
            let norm = want.iter().map(|w| w * w).sum::<f64>().sqrt();
            assert!(norm < crate::field::DEFAULT_MAX_PERTURBATION, "the cap would change the sum");
            active += usize::from(norm > 0.0);
            for (g, w) in got.iter().zip(&want) {
                assert!((g - w).abs() <= 1e-10 * (1.0 + w.abs()), "t {t}: {got:?} vs {want:?}");
            }
        }
        assert!(active >= 10, "only {active} points where a term is active");
    }
}
