//! Isopotentials: functions `C` that vanish on an obstacle's surface and grow away from it (ERRATA.md, properties
//! I1 and I2). The volumetric potentials only see an obstacle through its `C`, its gradient and its Hessian.

mod nested;
mod superquadric;

pub(crate) use superquadric::ipow;

pub use nested::NestedSuperquadric;
pub use superquadric::Superquadric;

/// An isopotential in the obstacle's own frame.
pub trait Isopotential {
    /// Dimension of the space.
    fn dim(&self) -> usize;

    /// `C(y)`.
    fn value(&self, y: &[f64]) -> f64;

    /// `C(y)`, with its gradient written into `grad` (length `d`) and its Hessian into `hess` (row-major `d x d`).
    fn eval(&self, y: &[f64], grad: &mut [f64], hess: &mut [f64]) -> f64;

    /// A point of the surface `C = 0` in the direction of the unit vector `w` (the SPEC's boundary sampling: in
    /// 2-D, `w = (cos theta, sin theta)` gives `(a_1 sgn(cos) |cos|^(1/n_1), a_2 sgn(sin) |sin|^(1/n_2))`).
    fn surface_point(&self, w: &[f64], out: &mut [f64]);
}

/// The two families of superquadric isopotentials of the paper.
#[derive(Debug, Clone, PartialEq)]
pub enum Shape {
    /// `sum_i (y_i / a_i)^(2 n_i) - 1`, any dimension.
    Superquadric(Superquadric),
    /// The paper's nested 3-D form (`eq:isopot_gen_ell`).
    Nested(NestedSuperquadric),
}

impl Shape {
    /// The semi-axes.
    pub fn semi_axes(&self) -> &[f64] {
        match self {
            Shape::Superquadric(s) => s.semi_axes(),
            Shape::Nested(s) => s.semi_axes(),
        }
    }

    /// The squared radius of a ball about the centre that holds the whole shape (`C <= 0`): `sum_i a_i^2`.
    ///
    /// Both families lie in the box `|y_i| <= a_i`: outside it some `|q_i| = |y_i / a_i| > 1`, so a term of `C + 1`
    /// (`q_i^(2 n_i)`, or `P^(m/n)` with `P > 1`, or `q_3^(2m)`) exceeds 1 on its own. A point farther than this
    /// from the centre is outside, whatever the rotation: contact checks skip the evaluation of `C` there.
    pub(crate) fn bounding_radius_sq(&self) -> f64 {
        self.semi_axes().iter().map(|a| a * a).sum()
    }

    /// The same shape with every semi-axis enlarged by `margin` (a robot's or a held object's size).
    pub fn inflated(&self, margin: f64) -> crate::Result<Shape> {
        Ok(match self {
            Shape::Superquadric(s) => Shape::Superquadric(s.inflated(margin)?),
            Shape::Nested(s) => Shape::Nested(s.inflated(margin)?),
        })
    }
}

impl Isopotential for Shape {
    fn dim(&self) -> usize {
        match self {
            Shape::Superquadric(s) => s.dim(),
            Shape::Nested(s) => s.dim(),
        }
    }

    fn value(&self, y: &[f64]) -> f64 {
        match self {
            Shape::Superquadric(s) => s.value(y),
            Shape::Nested(s) => s.value(y),
        }
    }

    fn eval(&self, y: &[f64], grad: &mut [f64], hess: &mut [f64]) -> f64 {
        match self {
            Shape::Superquadric(s) => s.eval(y, grad, hess),
            Shape::Nested(s) => s.eval(y, grad, hess),
        }
    }

    fn surface_point(&self, w: &[f64], out: &mut [f64]) {
        match self {
            Shape::Superquadric(s) => s.surface_point(w, out),
            Shape::Nested(s) => s.surface_point(w, out),
        }
    }
}

/// `sgn(x) |x|^p`, with integer powers computed exactly.
pub(crate) fn signed_pow(x: f64, p: f64) -> f64 {
    x.signum() * abs_pow(x, p)
}

/// `|x|^p` for `p >= 0`, with `0^0 = 1` and integer powers computed with `powi`.
pub(crate) fn abs_pow(x: f64, p: f64) -> f64 {
    if p == 0.0 {
        1.0
    } else if p.fract() == 0.0 && p < 64.0 {
        x.abs().powi(p as i32)
    } else {
        x.abs().powf(p)
    }
}

#[cfg(test)]
pub(crate) mod test_support {
    use super::Isopotential;

    /// Checks value, gradient and Hessian of `iso` at `y` against central finite differences.
    pub(crate) fn check_derivatives(iso: &dyn Isopotential, y: &[f64]) {
        let d = iso.dim();
        let mut g = vec![0.0; d];
        let mut h = vec![0.0; d * d];
        let c = iso.eval(y, &mut g, &mut h);
        assert!((c - iso.value(y)).abs() <= 1e-12 * (1.0 + c.abs()));
        let eps = 1e-6;
        let mut gp = vec![0.0; d];
        let mut gm = vec![0.0; d];
        let mut hh = vec![0.0; d * d];
        for j in 0..d {
            let mut yp = y.to_vec();
            let mut ym = y.to_vec();
            yp[j] += eps;
            ym[j] -= eps;
            let fd = (iso.value(&yp) - iso.value(&ym)) / (2.0 * eps);
            let scale = 1.0 + g[j].abs();
            assert!((fd - g[j]).abs() < 1e-5 * scale, "grad[{j}] {} vs fd {} at {y:?}", g[j], fd);
            iso.eval(&yp, &mut gp, &mut hh);
            iso.eval(&ym, &mut gm, &mut hh);
            for i in 0..d {
                let fd = (gp[i] - gm[i]) / (2.0 * eps);
                let scale = 1.0 + h[i * d + j].abs();
                assert!(
                    (fd - h[i * d + j]).abs() < 1e-4 * scale,
                    "hess[{i}][{j}] {} vs fd {fd}",
                    h[i * d + j]
                );
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Every point inside a shape (`C <= 0`) lies in its bounding ball, and points just inside the box's
        /// corners along the axes are the tightest case.
        #[test]
        fn the_bounding_ball_holds_the_shape(
            a in prop::array::uniform3(0.05f64..2.0),
            n in prop::array::uniform3(1.0f64..4.0),
            q in prop::array::uniform3(-1.5f64..1.5),
            nested in any::<bool>(),
        ) {
            let shape = if nested {
                Shape::Nested(NestedSuperquadric::new(a, n[0], n[1]).unwrap())
            } else {
                Shape::Superquadric(Superquadric::new(a.to_vec(), n.to_vec()).unwrap())
            };
            let y: Vec<f64> = q.iter().zip(&a).map(|(q, a)| q * a).collect();
            let r2: f64 = y.iter().map(|v| v * v).sum();
            if shape.value(&y) <= 0.0 {
                prop_assert!(r2 <= shape.bounding_radius_sq());
            }
            if r2 > shape.bounding_radius_sq() {
                prop_assert!(shape.value(&y) > 0.0);
            }
        }
    }
}
