//! Obstacles: an isopotential placed in the world with a rotation, moving with a constant velocity.

use crate::error::{InvalidInput, Result};
use crate::isopotential::{Isopotential, Shape};

/// Tolerance of the orthonormality check on a rotation.
const ORTHONORMAL_TOL: f64 = crate::ranges::ROTATION_TOLERANCE;

/// An obstacle: `C_world(x, t) = C(R^T (x - c(t)))` with `c(t) = center + velocity * t`.
#[derive(Debug, Clone, PartialEq)]
pub struct Obstacle {
    id: String,
    shape: Shape,
    center: Vec<f64>,
    velocity: Vec<f64>,
    /// Row-major `R` (columns are the obstacle's axes in the world), `None` for the identity.
    rotation: Option<Vec<f64>>,
}

impl Obstacle {
    /// Places `shape` at `center`; `rotation` (rows, d x d) must be orthonormal; `velocity` defaults to zero.
    pub fn new(
        id: impl Into<String>,
        shape: Shape,
        center: Vec<f64>,
        rotation: Option<Vec<Vec<f64>>>,
        velocity: Option<Vec<f64>>,
    ) -> Result<Self> {
        let d = shape.dim();
        if center.len() != d {
            return Err(InvalidInput::new(
                "center",
                format!("must have {d} entries (the shape's dimension), found {}", center.len()),
            )
            .into());
        }
        for (i, c) in center.iter().enumerate() {
            crate::error::ensure_finite(|| format!("center[{i}]"), *c)?;
        }
        let velocity = velocity.unwrap_or_else(|| vec![0.0; d]);
        if velocity.len() != d {
            return Err(InvalidInput::new(
                "velocity",
                format!("must have {d} entries, found {}", velocity.len()),
            )
            .into());
        }
        for (i, v) in velocity.iter().enumerate() {
            crate::error::ensure_finite(|| format!("velocity[{i}]"), *v)?;
        }
        let rotation = match rotation {
            None => None,
            Some(rows) => Some(check_rotation(&rows, d)?),
        };
        let rotation = rotation.filter(|r| !is_identity(r, d));
        Ok(Self { id: id.into(), shape, center, velocity, rotation })
    }

    /// The obstacle's name.
    pub fn id(&self) -> &str {
        &self.id
    }

    /// Its isopotential.
    pub fn shape(&self) -> &Shape {
        &self.shape
    }

    /// Dimension of the space it lives in.
    pub fn dim(&self) -> usize {
        self.shape.dim()
    }

    /// Centre at time zero.
    pub fn center(&self) -> &[f64] {
        &self.center
    }

    /// Constant velocity of the centre.
    pub fn velocity(&self) -> &[f64] {
        &self.velocity
    }

    /// The rotation, row-major, `None` for the identity.
    pub fn rotation(&self) -> Option<&[f64]> {
        self.rotation.as_deref()
    }

    /// Writes `c(t) = center + velocity * t` into `out`.
    pub fn center_at(&self, t: f64, out: &mut [f64]) {
        for ((o, c), v) in out.iter_mut().zip(&self.center).zip(&self.velocity) {
            *o = c + v * t;
        }
    }

    /// The same obstacle with its semi-axes enlarged by `margin`.
    pub fn inflated(&self, margin: f64) -> Result<Self> {
        Ok(Self { shape: self.shape.inflated(margin)?, ..self.clone() })
    }

    /// The same obstacle whose centre at time zero is moved to `center` (the rest unchanged).
    pub(crate) fn with_center(&self, center: Vec<f64>) -> Self {
        Self { center, ..self.clone() }
    }

    /// Moves the obstacle in place: centre at time zero and constant velocity (same dimension; a value that is
    /// not finite or of another length leaves it unchanged and returns false). Allocates nothing.
    pub(crate) fn set_motion(&mut self, center: &[f64], velocity: &[f64]) -> bool {
        let d = self.dim();
        if center.len() != d || velocity.len() != d || !center.iter().chain(velocity).all(|v| v.is_finite()) {
            return false;
        }
        self.center.copy_from_slice(center);
        self.velocity.copy_from_slice(velocity);
        true
    }

    /// `n` points on the surface, as offsets from the centre in the world frame (row-major `n x d`): the SPEC's
    /// boundary sampling of the point methods. They move with the obstacle.
    pub fn boundary_offsets(&self, n: usize) -> Vec<f64> {
        let d = self.dim();
        let mut local = vec![0.0; d];
        let mut out = vec![0.0; n * d];
        for (k, w) in crate::directions::unit_directions(d, n).iter().enumerate() {
            self.shape.surface_point(w, &mut local);
            rotate(self.rotation.as_deref(), &local, &mut out[k * d..(k + 1) * d]);
        }
        out
    }
}

/// Scratch and result of an evaluation of an isopotential placed in the world: `C`, its derivatives in the
/// obstacle's own frame (`y = R^T (x - c)`), and the world-frame gradient on request.
#[derive(Debug, Clone)]
pub(crate) struct WorldEval {
    /// `C`.
    pub(crate) c: f64,
    /// `grad_x C` (after [`WorldEval::eval`]).
    pub(crate) grad: Vec<f64>,
    /// The point in the obstacle's frame.
    pub(crate) y: Vec<f64>,
    /// `grad_y C`.
    pub(crate) gy: Vec<f64>,
    /// Row-major `H_y`, the Hessian in the obstacle's frame.
    pub(crate) hy: Vec<f64>,
    tmp: Vec<f64>,
    #[cfg(test)]
    tmp2: Vec<f64>,
    #[cfg(test)]
    hess: Vec<f64>,
}

impl WorldEval {
    /// Buffers for dimension `d`.
    pub(crate) fn new(d: usize) -> Self {
        Self {
            c: 0.0,
            grad: vec![0.0; d],
            y: vec![0.0; d],
            gy: vec![0.0; d],
            hy: vec![0.0; d * d],
            tmp: vec![0.0; d],
            #[cfg(test)]
            tmp2: vec![0.0; d],
            #[cfg(test)]
            hess: vec![0.0; d * d],
        }
    }

    /// `C`, `grad_y C` and `H_y` of `shape` centred at `center` with `rotation`, at `x`.
    pub(crate) fn eval_local(
        &mut self,
        shape: &Shape,
        rotation: Option<&[f64]>,
        center: &[f64],
        x: &[f64],
    ) -> f64 {
        let d = x.len();
        for i in 0..d {
            self.tmp[i] = x[i] - center[i];
        }
        rotate_transposed(rotation, &self.tmp, &mut self.y);
        self.c = shape.eval(&self.y, &mut self.gy, &mut self.hy);
        self.c
    }

    /// As [`WorldEval::eval_local`], and the world gradient into `grad`.
    ///
    /// # Formula
    /// `y = R^T (x - c)`, `grad_x C = R grad_y C`, `H_x = R H_y R^T`.
    pub(crate) fn eval(&mut self, shape: &Shape, rotation: Option<&[f64]>, center: &[f64], x: &[f64]) -> f64 {
        self.eval_local(shape, rotation, center, x);
        rotate(rotation, &self.gy, &mut self.grad);
        self.c
    }

    /// `out = H_x v = R H_y R^T v` at the point of the last evaluation.
    #[cfg(test)]
    pub(crate) fn hess_mul(&mut self, rotation: Option<&[f64]>, v: &[f64], out: &mut [f64]) {
        rotate_transposed(rotation, v, &mut self.tmp);
        mat_vec(&self.hy, &self.tmp, &mut self.tmp2);
        rotate(rotation, &self.tmp2, out);
    }

    /// The full world-frame Hessian (row-major) at the point of the last evaluation.
    #[cfg(test)]
    pub(crate) fn hessian(&mut self, rotation: Option<&[f64]>) -> &[f64] {
        let d = self.grad.len();
        let mut e = vec![0.0; d];
        let mut col = vec![0.0; d];
        for j in 0..d {
            e.fill(0.0);
            e[j] = 1.0;
            self.hess_mul(rotation, &e, &mut col);
            for i in 0..d {
                self.hess[i * d + j] = col[i];
            }
        }
        &self.hess
    }

    /// `C` only.
    pub(crate) fn value(
        &mut self,
        shape: &Shape,
        rotation: Option<&[f64]>,
        center: &[f64],
        x: &[f64],
    ) -> f64 {
        let d = x.len();
        for i in 0..d {
            self.tmp[i] = x[i] - center[i];
        }
        rotate_transposed(rotation, &self.tmp, &mut self.y);
        shape.value(&self.y)
    }

    /// The point `x` in the obstacle's frame, `R^T (x - c)`, written into `out`.
    pub(crate) fn to_local(rotation: Option<&[f64]>, center: &[f64], x: &[f64], out: &mut [f64]) {
        let d = x.len();
        let diff: Vec<f64> = (0..d).map(|i| x[i] - center[i]).collect();
        rotate_transposed(rotation, &diff, out);
    }
}

/// `out = M v` for a row-major square `M`.
pub(crate) fn mat_vec(m: &[f64], v: &[f64], out: &mut [f64]) {
    let d = v.len();
    for (i, o) in out.iter_mut().enumerate().take(d) {
        *o = m[i * d..(i + 1) * d].iter().zip(v).map(|(a, b)| a * b).sum();
    }
}

/// `out = R v` (identity when `r` is `None`).
pub(crate) fn rotate(r: Option<&[f64]>, v: &[f64], out: &mut [f64]) {
    let d = v.len();
    match r {
        None => out[..d].copy_from_slice(v),
        Some(r) => {
            for i in 0..d {
                out[i] = (0..d).map(|k| r[i * d + k] * v[k]).sum();
            }
        }
    }
}

/// `out = R^T v` (identity when `r` is `None`).
pub(crate) fn rotate_transposed(r: Option<&[f64]>, v: &[f64], out: &mut [f64]) {
    let d = v.len();
    match r {
        None => out[..d].copy_from_slice(v),
        Some(r) => {
            for i in 0..d {
                out[i] = (0..d).map(|k| r[k * d + i] * v[k]).sum();
            }
        }
    }
}

fn is_identity(r: &[f64], d: usize) -> bool {
    (0..d).all(|i| (0..d).all(|j| r[i * d + j] == if i == j { 1.0 } else { 0.0 }))
}

fn check_rotation(rows: &[Vec<f64>], d: usize) -> Result<Vec<f64>> {
    if rows.len() != d || rows.iter().any(|r| r.len() != d) {
        return Err(InvalidInput::new(
            "rotation",
            format!("must be a {d} x {d} matrix (one row per dimension)"),
        )
        .into());
    }
    let flat: Vec<f64> = rows.iter().flatten().copied().collect();
    if let Some(i) = flat.iter().position(|v| !v.is_finite()) {
        return Err(
            InvalidInput::new(format!("rotation[{}][{}]", i / d, i % d), "must be a finite number").into()
        );
    }
    for i in 0..d {
        for j in 0..d {
            let dot: f64 = (0..d).map(|k| flat[i * d + k] * flat[j * d + k]).sum();
            let want = if i == j { 1.0 } else { 0.0 };
            if (dot - want).abs() > ORTHONORMAL_TOL {
                return Err(InvalidInput::new(
                    "rotation",
                    format!("must be orthonormal (R R^T = I within {ORTHONORMAL_TOL}); rows {i} and {j} give {dot}"),
                )
                .into());
            }
        }
    }
    Ok(flat)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::isopotential::Superquadric;

    fn rot2(a: f64) -> Vec<Vec<f64>> {
        vec![vec![a.cos(), -a.sin()], vec![a.sin(), a.cos()]]
    }

    #[test]
    fn rotated_world_derivatives_match_finite_differences() {
        let shape = Shape::Superquadric(Superquadric::new(vec![0.3, 0.1], vec![2.0, 1.0]).unwrap());
        let o = Obstacle::new("box", shape, vec![0.2, -0.1], Some(rot2(0.6)), None).unwrap();
        let mut e = WorldEval::new(2);
        let x = [0.45, 0.2];
        e.eval(o.shape(), o.rotation(), o.center(), &x);
        let (g, h) = (e.grad.clone(), e.hessian(o.rotation()).to_vec());
        let eps = 1e-6;
        for j in 0..2 {
            let (mut xp, mut xm) = (x, x);
            xp[j] += eps;
            xm[j] -= eps;
            let fd = (e.value(o.shape(), o.rotation(), o.center(), &xp)
                - e.value(o.shape(), o.rotation(), o.center(), &xm))
                / (2.0 * eps);
            assert!((fd - g[j]).abs() < 1e-6 * (1.0 + g[j].abs()));
            e.eval(o.shape(), o.rotation(), o.center(), &xp);
            let gp = e.grad.clone();
            e.eval(o.shape(), o.rotation(), o.center(), &xm);
            for i in 0..2 {
                let fd = (gp[i] - e.grad[i]) / (2.0 * eps);
                assert!((fd - h[i * 2 + j]).abs() < 1e-4 * (1.0 + h[i * 2 + j].abs()));
            }
        }
    }

    #[test]
    fn boundary_offsets_lie_on_the_rotated_surface() {
        let shape = Shape::Superquadric(Superquadric::new(vec![0.3, 0.2], vec![1.0, 2.0]).unwrap());
        let o = Obstacle::new("e", shape, vec![-0.5, 0.7], Some(rot2(0.3)), Some(vec![0.1, 0.0])).unwrap();
        let offs = o.boundary_offsets(50);
        let mut e = WorldEval::new(2);
        let mut c = [0.0; 2];
        o.center_at(2.0, &mut c);
        for k in 0..50 {
            let p = [c[0] + offs[2 * k], c[1] + offs[2 * k + 1]];
            let v = e.value(o.shape(), o.rotation(), &c, &p);
            assert!(v.abs() < 1e-12);
        }
    }

    #[test]
    fn moving_a_compiled_field_in_place_equals_compiling_it_again() {
        use crate::field::{RepulsiveField, Scene};
        use crate::{Avoidance, Method, Perturbation};
        let shape = Shape::Superquadric(crate::Superquadric::ellipsoid(vec![0.3, 0.2]).unwrap());
        let at = |c: Vec<f64>, v: Vec<f64>| {
            Obstacle::new("o", shape.clone(), c, Some(rot2(0.4)), Some(v)).unwrap()
        };
        let avoidance = Avoidance::new(Method::DynamicVolumetric(crate::avoidance::DynamicVolumetric {
            lambda: 10.0,
            beta: 2.0,
            eta: 0.5,
        }));
        let field =
            |o: Obstacle| RepulsiveField::new(Scene::with_obstacles(vec![o], avoidance, 0), 2).unwrap();
        let mut moved = field(at(vec![0.0, 0.0], vec![0.0, 0.0]));
        assert!(moved.set_obstacle_motion(0, &[0.5, 0.4], &[-0.3, 0.1]));
        assert!(!moved.set_obstacle_motion(0, &[f64::NAN, 0.0], &[0.0, 0.0]), "refused, unchanged");
        assert!(!moved.set_obstacle_motion(1, &[0.0, 0.0], &[0.0, 0.0]));
        let mut fresh = field(at(vec![0.5, 0.4], vec![-0.3, 0.1]));
        let (mut a, mut b) = ([0.0; 2], [0.0; 2]);
        moved.add(0.7, &[0.1, 0.2], &[0.5, 0.3], 1.0, &mut a);
        fresh.add(0.7, &[0.1, 0.2], &[0.5, 0.3], 1.0, &mut b);
        assert_eq!(a, b);
        assert!(a.iter().any(|v| *v != 0.0));
    }

    #[test]
    fn non_orthonormal_rotations_are_refused() {
        let shape = Shape::Superquadric(Superquadric::ellipsoid(vec![0.3, 0.2]).unwrap());
        let err = Obstacle::new(
            "e",
            shape.clone(),
            vec![0.0, 0.0],
            Some(vec![vec![1.0, 0.1], vec![0.0, 1.0]]),
            None,
        )
        .unwrap_err();
        assert!(err.to_string().starts_with("rotation"), "{err}");
        assert!(Obstacle::new("e", shape, vec![0.0], None, None).is_err());
    }
}
