//! Signed Euclidean distance from a point to an obstacle's surface `C = 0`, used to report clearances.
//!
//! # Method
//! Every shape of [`Shape`] is a convex body `K = {C <= 0}` containing its centre, and `C` grows along every ray
//! from the centre. The distance from `y` to the surface is the smallest `|z - y|` over surface points `z`, a
//! non-convex problem in general (a point inside, or outside near a thin shape, sees several local minima), so it
//! is solved globally in two stages.
//!
//! 1. **Sampling.** The surface is sampled on an equiangular "cube sphere" of directions: on each of the `2 d`
//!    faces of `[-1, 1]^d` a regular `(d - 1)`-dimensional grid `u_j = tan(pi/4 s_j)` (extended by one node beyond
//!    the face). Each direction `v` is mapped to the surface in two ways: by the shape's own parametrization
//!    ([`Isopotential::surface_point`] of `v / |v|`, dense near corners) and by the radial projection
//!    `rho(v) = s v` with `C(s v) = 0` (dense near flat faces). The discrete local minima of `|z - y|^2` over
//!    each face grid (a node no larger than its `2 (d - 1)` neighbours), the best sample, the radial projection of
//!    `y` and the `2 d` axis vertices `+- a_i e_i` are the candidates; the best few distinct ones are kept.
//! 2. **Refinement.** Each candidate is polished by a damped Newton method on the surface (Levenberg-Marquardt on
//!    the KKT system of `min |z - y|^2 / 2` subject to `C(z) = 0`). At a surface point `z` with normal
//!    `nu = grad C / |grad C|`, residual `r = z - y`, tangential gradient `t = r - (r . nu) nu` and multiplier
//!    `mu = -(r . nu) / |grad C|`, the step solves
//!    `[[I + mu H + lambda I, nu], [nu^T, 0]] [dz; eta] = [-t; 0]` (`H` the Hessian of `C`, `I + mu H` the Hessian of
//!    the Lagrangian), then `z + dz` is projected back radially. A step is kept only when it is a descent
//!    direction of the model (`-t . dz > 0`), no longer than the largest semi-axis, and lowers `|z - y|`;
//!    otherwise `lambda` grows tenfold. It stops when `|t| <= 1e-13 (|r| + a_max)` or no step helps any more.
//!
//! The result is `|z* - y|` for the best polished `z*`, which lies on the surface to rounding, so it is never below
//! the true distance; its sign is that of `C(y)` (negative inside). In 1-D the answer is `|y| - a` in closed form.
//!
//! The radial projection is closed form for the nested shape (`C + 1` is homogeneous of degree `2 m`) and for a
//! superquadric with equal exponents (degree `2 n`); with mixed exponents `s = e^tau` solves
//! `psi(tau) = ln sum_i |p_i / a_i|^(2 n_i) e^(2 n_i tau) = 0` by Newton's method, started where `psi >= 0`: `psi` is
//! a convex, increasing log-sum-exp, so the iterates decrease monotonically to the root.

use std::f64::consts::FRAC_PI_4;

use crate::isopotential::{Isopotential, Shape, abs_pow};
use crate::obstacle::{Obstacle, WorldEval};

/// Grid intervals per face edge in 2-D.
const GRID_2D: usize = 64;
/// Grid intervals per face edge in 3-D.
const GRID_3D: usize = 12;
/// Target number of samples per parametrization above 3-D.
const SAMPLE_BUDGET: usize = 6000;
/// Candidates taken from each parametrization's grid.
const GRID_CANDIDATES: usize = 6;
/// Newton iterations per candidate.
const MAX_ITERATIONS: usize = 100;
/// Damping increases tried per iteration before giving up.
const MAX_DAMPING_TRIES: usize = 30;
/// Stop once the tangential gradient is below this fraction of `|r| + a_max`.
const TANGENT_TOL: f64 = 1e-13;

/// Signed Euclidean distance from `y` (a point in the shape's own frame, `R^T (x - c)`) to the surface `C = 0`:
/// positive outside, negative inside, zero on it. See the [module documentation](self) for the method.
///
/// A `y` with a NaN coordinate gives NaN; one with an infinite coordinate gives `+inf`.
///
/// ```
/// use dmp::distance::signed_distance;
/// use dmp::isopotential::{Shape, Superquadric};
/// let ellipse = Shape::Superquadric(Superquadric::ellipsoid(vec![0.5, 0.2]).unwrap());
/// assert!((signed_distance(&ellipse, &[0.9, 0.0]) - 0.4).abs() < 1e-12);
/// assert!((signed_distance(&ellipse, &[0.0, 0.0]) + 0.2).abs() < 1e-12);
/// ```
///
/// # Panics
/// If `y.len()` differs from the shape's dimension.
pub fn signed_distance(shape: &Shape, y: &[f64]) -> f64 {
    nearest_surface_point(shape, y).0
}

/// [`signed_distance`] of the world point `x` to `obstacle` at time `t`: `y = R^T (x - c(t))`.
///
/// # Panics
/// If `x.len()` differs from the obstacle's dimension.
pub fn signed_distance_world(obstacle: &Obstacle, x: &[f64], t: f64) -> f64 {
    let d = obstacle.dim();
    assert_eq!(x.len(), d, "point has {} coordinates, obstacle {} is {d}-D", x.len(), obstacle.id());
    let mut c = vec![0.0; d];
    obstacle.center_at(t, &mut c);
    let mut y = vec![0.0; d];
    WorldEval::to_local(obstacle.rotation(), &c, x, &mut y);
    signed_distance(obstacle.shape(), &y)
}

/// The signed distance of [`signed_distance`] together with the nearest surface point `z*` (shape frame).
///
/// # Panics
/// If `y.len()` differs from the shape's dimension.
pub fn nearest_surface_point(shape: &Shape, y: &[f64]) -> (f64, Vec<f64>) {
    nearest_with(shape, y, grid_intervals(shape.dim()), GRID_CANDIDATES)
}

/// [`nearest_surface_point`] with `intervals` grid intervals per face edge and `per_grid` candidates per grid.
fn nearest_with(shape: &Shape, y: &[f64], intervals: usize, per_grid: usize) -> (f64, Vec<f64>) {
    let d = shape.dim();
    assert_eq!(y.len(), d, "point has {} coordinates, shape is {d}-D", y.len());
    if y.iter().any(|v| v.is_nan()) {
        return (f64::NAN, vec![f64::NAN; d]);
    }
    if y.iter().any(|v| v.is_infinite()) {
        let dir: Vec<f64> = y.iter().map(|v| if v.is_infinite() { v.signum() } else { 0.0 }).collect();
        let mut z = vec![0.0; d];
        radial_projection(shape, &dir, &mut z);
        return (f64::INFINITY, z);
    }
    if d == 1 {
        // The interval [-a, a].
        let a = shape.semi_axes()[0];
        let z = if y[0] < 0.0 { -a } else { a };
        return (y[0].abs() - a, vec![z]);
    }
    let sign = if shape.value(y) < 0.0 { -1.0 } else { 1.0 };
    let mut solver = Solver::new(shape, y, intervals, per_grid);
    let (f, z) = solver.solve();
    (sign * f.sqrt(), z)
}

/// How a node `u` of the faces of the cube `[-1, 1]^d` is mapped to the surface.
#[derive(Debug, Clone, Copy)]
enum Param {
    /// [`Isopotential::surface_point`] of `u / |u|`, with equiangular nodes (`u_j = tan(pi/4 s_j)`).
    Surface,
    /// The radial projection of the scaled box point `a (.) u`, with evenly spaced nodes.
    Radial,
}

impl Param {
    /// The face coordinate of the grid abscissa `s` (`-1` and `1` are the face's edges).
    fn node(self, s: f64) -> f64 {
        match self {
            Param::Surface => (FRAC_PI_4 * s).tan(),
            Param::Radial => s,
        }
    }
}

/// Scratch of one distance query.
struct Solver<'a> {
    shape: &'a Shape,
    y: &'a [f64],
    d: usize,
    /// Largest semi-axis.
    length: f64,
    /// Grid intervals per face edge.
    intervals: usize,
    /// Candidates kept per grid.
    per_grid: usize,
    grad: Vec<f64>,
    hess: Vec<f64>,
    kkt: Vec<f64>,
    rhs: Vec<f64>,
    r: Vec<f64>,
    t: Vec<f64>,
    trial: Vec<f64>,
    projected: Vec<f64>,
}

impl<'a> Solver<'a> {
    fn new(shape: &'a Shape, y: &'a [f64], intervals: usize, per_grid: usize) -> Self {
        let d = shape.dim();
        let length = shape.semi_axes().iter().fold(0.0_f64, |m, a| m.max(*a));
        Self {
            shape,
            y,
            d,
            length,
            intervals,
            per_grid,
            grad: vec![0.0; d],
            hess: vec![0.0; d * d],
            kkt: vec![0.0; (d + 1) * (d + 1)],
            rhs: vec![0.0; d + 1],
            r: vec![0.0; d],
            t: vec![0.0; d],
            trial: vec![0.0; d],
            projected: vec![0.0; d],
        }
    }

    /// Squared distance and nearest point.
    fn solve(&mut self) -> (f64, Vec<f64>) {
        let d = self.d;
        let mut candidates: Vec<Vec<f64>> = Vec::new();
        self.grid_candidates(Param::Surface, &mut candidates);
        self.grid_candidates(Param::Radial, &mut candidates);
        let mut z = vec![0.0; d];
        if radial_projection(self.shape, self.y, &mut z) {
            candidates.push(z.clone());
        }
        let mut best = (f64::INFINITY, candidates[0].clone());
        for mut c in candidates {
            let f = self.refine(&mut c);
            if f < best.0 {
                best = (f, c);
            }
        }
        best
    }

    /// Appends candidates from the cube grid mapped by `param`: the best sample, the best core node of each face and
    /// the best discrete local minima, distinct, at most `2 d + per_grid + 1` of them.
    fn grid_candidates(&self, param: Param, out: &mut Vec<Vec<f64>>) {
        let d = self.d;
        let intervals = self.intervals;
        let nodes = intervals + 3;
        let per_face = nodes.pow(d as u32 - 1);
        let u: Vec<f64> = (0..nodes).map(|i| param.node(-1.0 + 2.0 * (i as f64 - 1.0) / intervals as f64)).collect();
        let strides: Vec<usize> = (0..d - 1).map(|s| nodes.pow(s as u32)).collect();
        let mut values = vec![f64::INFINITY; 2 * d * per_face];
        let (mut dir, mut w, mut z) = (vec![0.0; d], vec![0.0; d], vec![0.0; d]);
        let mut idx = vec![0usize; d - 1];
        let mut best = (f64::INFINITY, 0usize);
        for face in 0..2 * d {
            for flat in 0..per_face {
                decode(flat, nodes, &mut idx);
                face_direction(face, &idx, &u, &mut dir);
                if self.param_point(param, &mut dir, &mut w, &mut z) {
                    let f = dist2(&z, self.y);
                    values[face * per_face + flat] = f;
                    if f < best.0 {
                        best = (f, face * per_face + flat);
                    }
                }
            }
        }
        let mut face_best = vec![(f64::INFINITY, 0usize); 2 * d];
        let mut minima: Vec<(f64, usize)> = Vec::new();
        for (face, fb) in face_best.iter_mut().enumerate() {
            let base = face * per_face;
            for flat in 0..per_face {
                decode(flat, nodes, &mut idx);
                if idx.iter().any(|&i| i == 0 || i == nodes - 1) {
                    continue;
                }
                let v = values[base + flat];
                if !v.is_finite() {
                    continue;
                }
                if v < fb.0 {
                    *fb = (v, base + flat);
                }
                if strides.iter().all(|&s| values[base + flat - s] >= v && values[base + flat + s] >= v) {
                    minima.push((v, base + flat));
                }
            }
        }
        minima.sort_by(|a, b| a.0.total_cmp(&b.0));
        minima.truncate(self.per_grid);
        let separation = 1e-9 * self.length;
        for (v, node) in std::iter::once(best).chain(face_best).chain(minima) {
            if !v.is_finite() {
                continue;
            }
            decode(node % per_face, nodes, &mut idx);
            face_direction(node / per_face, &idx, &u, &mut dir);
            if self.param_point(param, &mut dir, &mut w, &mut z)
                && out.iter().all(|k| dist2(k, &z).sqrt() > separation)
            {
                out.push(z.clone());
            }
        }
    }

    /// The surface point of the cube direction `dir` under `param`, into `out` (`dir` and `w` are scratch);
    /// `false` if it is undefined.
    fn param_point(&self, param: Param, dir: &mut [f64], w: &mut [f64], out: &mut [f64]) -> bool {
        match param {
            Param::Surface => {
                let n = norm(dir);
                if !(n > 0.0 && n.is_finite()) {
                    return false;
                }
                for (wi, di) in w.iter_mut().zip(dir.iter()) {
                    *wi = di / n;
                }
                self.shape.surface_point(w, out);
                out.iter().all(|v| v.is_finite())
            }
            Param::Radial => {
                for (di, a) in dir.iter_mut().zip(self.shape.semi_axes()) {
                    *di *= a;
                }
                radial_projection(self.shape, dir, out)
            }
        }
    }

    /// Polishes the surface point `z` in place (damped Newton on the KKT system, see the module documentation) and
    /// returns `|z - y|^2`.
    fn refine(&mut self, z: &mut [f64]) -> f64 {
        let d = self.d;
        let k = d + 1;
        let mut f = dist2(z, self.y);
        let mut lambda = 0.0_f64;
        'outer: for _ in 0..MAX_ITERATIONS {
            self.shape.eval(z, &mut self.grad, &mut self.hess);
            let gn = norm(&self.grad);
            if !(gn > 0.0 && gn.is_finite()) {
                break;
            }
            if self.hess.iter().any(|h| !h.is_finite()) {
                self.hess.fill(0.0);
            }
            self.grad.iter_mut().for_each(|g| *g /= gn);
            for i in 0..d {
                self.r[i] = z[i] - self.y[i];
            }
            let rn = dot(&self.r, &self.grad);
            for i in 0..d {
                self.t[i] = self.r[i] - rn * self.grad[i];
            }
            let r_norm = norm(&self.r);
            if norm(&self.t) <= TANGENT_TOL * (r_norm + self.length) {
                break;
            }
            let mu = -rn / gn;
            let h_max = self.hess.iter().fold(0.0_f64, |m, h| m.max(h.abs()));
            let scale = 1.0 + mu.abs() * h_max;
            let max_step = self.length;
            let z_norm = norm(z);
            let mut accepted = false;
            for _ in 0..MAX_DAMPING_TRIES {
                for i in 0..d {
                    for j in 0..d {
                        let diag = if i == j { 1.0 + lambda } else { 0.0 };
                        self.kkt[i * k + j] = diag + mu * self.hess[i * d + j];
                    }
                    self.kkt[i * k + d] = self.grad[i];
                    self.kkt[d * k + i] = self.grad[i];
                    self.rhs[i] = -self.t[i];
                }
                self.kkt[d * k + d] = 0.0;
                self.rhs[d] = 0.0;
                let solved = solve_in_place(&mut self.kkt, &mut self.rhs, k);
                let dz = &self.rhs[..d];
                let step = norm(dz);
                // dz . (A + lambda I) dz = -t . dz must be positive for a descent step of the model.
                let descent = -dot(&self.t, dz);
                let mut ok = solved && descent > 0.0 && step <= max_step;
                if ok {
                    for i in 0..d {
                        self.trial[i] = z[i] + dz[i];
                    }
                    ok = radial_projection(self.shape, &self.trial, &mut self.projected);
                }
                if ok {
                    let f_new = dist2(&self.projected, self.y);
                    if f_new < f {
                        z.copy_from_slice(&self.projected);
                        f = f_new;
                        lambda = if lambda < 1e-9 * scale { 0.0 } else { lambda * 0.1 };
                        accepted = true;
                        break;
                    }
                    if step <= 1e-15 * (self.length + z_norm) {
                        break 'outer;
                    }
                }
                lambda = if lambda == 0.0 { 1e-6 * scale } else { lambda * 10.0 };
            }
            if !accepted {
                break;
            }
        }
        f
    }
}

/// Grid intervals per face edge for dimension `d >= 2`.
fn grid_intervals(d: usize) -> usize {
    match d {
        2 => GRID_2D,
        3 => GRID_3D,
        _ => {
            let per_face = SAMPLE_BUDGET as f64 / (2 * d) as f64;
            (per_face.powf(1.0 / (d - 1) as f64).floor() as usize).saturating_sub(3).max(2)
        }
    }
}

/// Mixed-radix digits of `flat` in base `nodes`.
fn decode(mut flat: usize, nodes: usize, idx: &mut [usize]) {
    for i in idx.iter_mut() {
        *i = flat % nodes;
        flat /= nodes;
    }
}

/// The direction of node `idx` on cube face `face` (axis `face / 2`, sign `+` for even faces).
fn face_direction(face: usize, idx: &[usize], u: &[f64], dir: &mut [f64]) {
    let axis = face / 2;
    let mut slot = 0;
    for (j, v) in dir.iter_mut().enumerate() {
        if j == axis {
            *v = if face % 2 == 0 { 1.0 } else { -1.0 };
        } else {
            *v = u[idx[slot]];
            slot += 1;
        }
    }
}

/// `out = s p` with `C(s p) = 0`, `s > 0`; `false` (and `out` untouched) for `p = 0` or a non-finite result.
fn radial_projection(shape: &Shape, p: &[f64], out: &mut [f64]) -> bool {
    match radial_scale(shape, p) {
        Some(s) => {
            for (o, pi) in out.iter_mut().zip(p) {
                *o = s * pi;
            }
            true
        }
        None => false,
    }
}

/// The `s > 0` with `C(s p) = 0` (see the module documentation).
fn radial_scale(shape: &Shape, p: &[f64]) -> Option<f64> {
    let p_max = p.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    if !(p_max > 0.0 && p_max.is_finite()) {
        return None;
    }
    let s = match shape {
        Shape::Nested(nested) => {
            // C(s q) + 1 = s^(2m) (C(q) + 1), with q = p / p_max to avoid over- and underflow.
            let (_, m) = nested.exponents();
            let q = [p[0] / p_max, p[1] / p_max, p[2] / p_max];
            let v = nested.value(&q) + 1.0;
            if !(v > 0.0 && v.is_finite()) {
                return None;
            }
            v.powf(-0.5 / m) / p_max
        }
        Shape::Superquadric(sq) => superquadric_scale(sq.semi_axes(), sq.exponents(), p)?,
    };
    (s.is_finite() && s > 0.0).then_some(s)
}

/// Radial scale of a per-axis superquadric: with `c_i = |p_i| / a_i` scaled so that `max c_i = 1`, the root of
/// `psi(tau) = ln sum_i (c_i e^tau)^(e_i)`, `e_i = 2 n_i`, returned as `s = e^tau / c_max`. Started at `tau = 0`
/// (`psi >= 0`), so every term stays `<= 1`.
fn superquadric_scale(a: &[f64], n: &[f64], p: &[f64]) -> Option<f64> {
    let c_max = p.iter().zip(a).map(|(pi, ai)| pi.abs() / ai).fold(0.0_f64, f64::max);
    if !(c_max > 0.0 && c_max.is_finite()) {
        return None;
    }
    let ratio = |i: usize| p[i].abs() / a[i] / c_max;
    let e0 = 2.0 * n[0];
    if n.iter().all(|&ni| 2.0 * ni == e0) {
        // Homogeneous: s = (sum_i c_i^e)^(-1/e).
        let sum: f64 = (0..p.len()).map(|i| abs_pow(ratio(i), e0)).sum();
        return Some(sum.powf(-1.0 / e0) / c_max);
    }
    let mut s = 1.0;
    for _ in 0..64 {
        let (mut sum, mut dsum) = (0.0, 0.0);
        for i in 0..p.len() {
            let e = 2.0 * n[i];
            let term = abs_pow(ratio(i) * s, e);
            sum += term;
            dsum += e * term;
        }
        let step = sum.ln() / (dsum / sum);
        if !step.is_finite() {
            return None;
        }
        s *= (-step).exp();
        if step.abs() <= 1e-12 {
            break;
        }
    }
    Some(s / c_max)
}

/// Solves `A x = b` (`A` row-major `k x k`) by Gaussian elimination with partial pivoting; `x` overwrites `b`.
fn solve_in_place(a: &mut [f64], b: &mut [f64], k: usize) -> bool {
    for col in 0..k {
        let pivot =
            (col..k).max_by(|&i, &j| a[i * k + col].abs().total_cmp(&a[j * k + col].abs())).unwrap_or(col);
        let pv = a[pivot * k + col];
        if !(pv != 0.0 && pv.is_finite()) {
            return false;
        }
        if pivot != col {
            for c in 0..k {
                a.swap(pivot * k + c, col * k + c);
            }
            b.swap(pivot, col);
        }
        for row in col + 1..k {
            let factor = a[row * k + col] / pv;
            if factor != 0.0 {
                for c in col..k {
                    a[row * k + c] -= factor * a[col * k + c];
                }
                b[row] -= factor * b[col];
            }
        }
    }
    for row in (0..k).rev() {
        let mut acc = b[row];
        for c in row + 1..k {
            acc -= a[row * k + c] * b[c];
        }
        b[row] = acc / a[row * k + row];
    }
    b.iter().all(|v| v.is_finite())
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

fn dist2(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::directions::unit_directions;
    use crate::isopotential::{NestedSuperquadric, Superquadric};

    /// A small deterministic generator (xorshift64*), uniform in `[lo, hi)`.
    struct Rng(u64);

    impl Rng {
        fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            let bits = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11;
            lo + (hi - lo) * (bits as f64 / (1u64 << 53) as f64)
        }

        fn direction(&mut self, d: usize) -> Vec<f64> {
            loop {
                let v: Vec<f64> = (0..d).map(|_| self.uniform(-1.0, 1.0)).collect();
                let n = norm(&v);
                if n > 1e-3 && n <= 1.0 {
                    return v.iter().map(|x| x / n).collect();
                }
            }
        }
    }

    fn sq(a: &[f64], n: &[f64]) -> Shape {
        Shape::Superquadric(Superquadric::new(a.to_vec(), n.to_vec()).unwrap())
    }

    /// The radial projection by plain bisection on `C(s v) = 0` (independent of the code under test).
    fn radial_bisection(shape: &Shape, v: &[f64]) -> Vec<f64> {
        let at = |s: f64| v.iter().map(|x| s * x).collect::<Vec<f64>>();
        let (mut lo, mut hi) = (0.0, 1.0);
        while shape.value(&at(hi)) < 0.0 {
            hi *= 2.0;
        }
        for _ in 0..80 {
            let mid = 0.5 * (lo + hi);
            if shape.value(&at(mid)) < 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        at(0.5 * (lo + hi))
    }

    /// Brute force: the nearest of `samples`, then a derivative-free compass search over radial directions from
    /// the best few distinct samples. An upper bound of the true unsigned distance.
    fn reference(shape: &Shape, samples: &[Vec<f64>], y: &[f64]) -> f64 {
        let d = y.len();
        let length = shape.semi_axes().iter().fold(0.0_f64, |m, a| m.max(*a));
        let mut order: Vec<(f64, usize)> =
            samples.iter().enumerate().map(|(i, s)| (dist2(s, y), i)).collect();
        order.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut starts: Vec<&Vec<f64>> = Vec::new();
        for &(_, i) in &order {
            if starts.len() == 3 {
                break;
            }
            if starts.iter().all(|s| dist2(s, &samples[i]).sqrt() > 0.05 * length) {
                starts.push(&samples[i]);
            }
        }
        let mut best = order[0].0;
        for start in starts {
            let mut v = start.clone();
            let mut f = dist2(&radial_bisection(shape, &v), y);
            let mut h = 0.02 * length;
            let mut iterations = 0;
            while h > 1e-12 * length && iterations < 5000 {
                iterations += 1;
                let mut improved = false;
                for i in 0..d {
                    for s in [1.0, -1.0] {
                        let mut trial = v.clone();
                        trial[i] += s * h;
                        let ft = dist2(&radial_bisection(shape, &trial), y);
                        if ft < f {
                            (v, f, improved) = (trial, ft, true);
                        }
                    }
                }
                if improved {
                    h *= 1.5;
                } else {
                    h *= 0.5;
                }
            }
            best = best.min(f);
        }
        best.sqrt()
    }

    /// `n` surface points from the shape's own parametrization.
    fn dense_samples(shape: &Shape, n: usize) -> Vec<Vec<f64>> {
        let d = shape.dim();
        unit_directions(d, n)
            .iter()
            .map(|w| {
                let mut z = vec![0.0; d];
                shape.surface_point(w, &mut z);
                z
            })
            .collect()
    }

    /// Test points: inside (shrunk surface points, including near the centre), near the surface on both sides,
    /// near corners (diagonal directions), and outside up to a few metres.
    fn test_points(shape: &Shape, count: usize, seed: u64) -> Vec<Vec<f64>> {
        let d = shape.dim();
        let mut rng = Rng(seed);
        let mut points = Vec::new();
        for k in 0..count {
            let w = if k % 4 == 0 {
                // Near a corner: all components of similar size.
                let v: Vec<f64> = (0..d)
                    .map(|_| rng.uniform(0.8, 1.0) * if rng.uniform(0.0, 1.0) < 0.5 { -1.0 } else { 1.0 })
                    .collect();
                let n = norm(&v);
                v.iter().map(|x| x / n).collect()
            } else {
                rng.direction(d)
            };
            let mut z = vec![0.0; d];
            shape.surface_point(&w, &mut z);
            let s = match k % 6 {
                0 => rng.uniform(0.0, 0.3),
                1 => rng.uniform(0.3, 0.99),
                2 => rng.uniform(0.99, 1.01),
                3 => rng.uniform(1.01, 2.0),
                _ => rng.uniform(2.0, 3.0 / norm(&z)),
            };
            points.push(z.iter().map(|x| s * x).collect());
        }
        points
    }

    /// Compares against the brute-force reference; returns the largest difference.
    fn check_against_reference(shape: &Shape, samples: usize, count: usize, seed: u64) -> f64 {
        let dense = dense_samples(shape, samples);
        let mut worst = 0.0_f64;
        for y in test_points(shape, count, seed) {
            let (sd, z) = nearest_surface_point(shape, &y);
            assert!(sd.is_finite(), "{y:?}");
            assert!(shape.value(&z).abs() < 1e-12, "nearest point off the surface: {z:?}");
            assert!((dist2(&z, &y).sqrt() - sd.abs()).abs() < 1e-14);
            let c = shape.value(&y);
            if c.abs() > 1e-12 {
                assert_eq!(sd < 0.0, c < 0.0, "sign at {y:?}");
            }
            let reference = reference(shape, &dense, &y);
            let diff = sd.abs() - reference;
            assert!(diff.abs() < 1e-7, "{shape:?} at {y:?}: distance {sd}, reference {reference}");
            worst = worst.max(diff.abs());
        }
        worst
    }

    #[test]
    fn circle_and_sphere_are_closed_form() {
        let mut rng = Rng(7);
        let shapes = [
            (sq(&[0.3, 0.3], &[1.0, 1.0]), 0.3),
            (sq(&[0.01, 0.01], &[1.0, 1.0]), 0.01),
            (sq(&[1.5, 1.5, 1.5], &[1.0, 1.0, 1.0]), 1.5),
            (Shape::Nested(NestedSuperquadric::new([0.2, 0.2, 0.2], 1.0, 1.0).unwrap()), 0.2),
        ];
        for (shape, r) in &shapes {
            let d = shape.dim();
            for k in 0..40 {
                let radius = if k % 2 == 0 { rng.uniform(0.0, *r) } else { rng.uniform(*r, 3.0) };
                let y: Vec<f64> = rng.direction(d).iter().map(|x| x * radius).collect();
                let want = norm(&y) - r;
                let got = signed_distance(shape, &y);
                assert!((got - want).abs() < 1e-12, "{shape:?} at {y:?}: {got} vs {want}");
            }
        }
    }

    #[test]
    fn ellipse_axes_are_known() {
        let (a, b) = (0.5, 0.2);
        let e = sq(&[a, b], &[1.0, 1.0]);
        let check = |y: [f64; 2], want: f64| {
            let got = signed_distance(&e, &y);
            assert!((got - want).abs() < 1e-10, "at {y:?}: {got} vs {want}");
        };
        // Outside on the axes: the nearest vertex.
        for x in [0.5001, 0.7, 2.0, 3.5] {
            check([x, 0.0], x - a);
            check([-x, 0.0], x - a);
        }
        for y in [0.2001, 0.5, 3.0] {
            check([0.0, y], y - b);
            check([0.0, -y], y - b);
        }
        // Inside on the major axis: b sqrt(1 - x^2 / (a^2 - b^2)) while |x| <= (a^2 - b^2) / a, then a - |x|.
        let knee = (a * a - b * b) / a;
        for x in [0.0, 0.1, 0.3, 0.41, knee, 0.43, 0.49, 0.4999] {
            let want = if x <= knee { b * (1.0 - x * x / (a * a - b * b)).sqrt() } else { a - x };
            check([x, 0.0], -want);
            check([-x, 0.0], -want);
        }
        // Inside on the minor axis: the co-vertex.
        for y in [0.0, 0.05, 0.19, 0.1999] {
            check([0.0, y], -(b - y));
            check([0.0, -y], -(b - y));
        }
    }

    #[test]
    fn ellipse_matches_dense_sampling() {
        let (a, b) = (0.4, 0.15);
        let e = sq(&[a, b], &[1.0, 1.0]);
        let n = 200_000;
        let dense: Vec<[f64; 2]> = (0..n)
            .map(|k| {
                let th = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
                [a * th.cos(), b * th.sin()]
            })
            .collect();
        let mut rng = Rng(11);
        for k in 0..60 {
            let y = if k % 2 == 0 {
                let s = rng.uniform(0.0, 1.0);
                [rng.uniform(-a, a) * s, rng.uniform(-b, b) * s]
            } else {
                [rng.uniform(-2.0, 2.0), rng.uniform(-2.0, 2.0)]
            };
            let brute = dense.iter().map(|z| dist2(z, &y)).fold(f64::INFINITY, f64::min).sqrt();
            let got = signed_distance(&e, &y);
            assert_eq!(got < 0.0, e.value(&y) < 0.0);
            // The dense minimum is within ~1e-10 of the truth and never below it.
            assert!(got.abs() <= brute + 1e-12, "at {y:?}: {got} vs brute force {brute}");
            assert!(brute - got.abs() < 1e-9, "at {y:?}: {got} vs brute force {brute}");
        }
    }

    #[test]
    fn two_dimensional_superquadrics_match_brute_force() {
        for (shape, seed) in [
            (sq(&[0.4, 0.15], &[1.0, 1.0]), 1),
            (sq(&[0.3, 0.2], &[2.0, 2.0]), 2),
            (sq(&[0.3, 0.1], &[4.0, 4.0]), 3),
            (sq(&[0.01, 0.02], &[3.0, 3.0]), 4),
            (sq(&[2.0, 0.05], &[1.0, 2.5]), 5),
        ] {
            check_against_reference(&shape, 20_000, 60, seed);
        }
    }

    #[test]
    fn rounded_box_matches_brute_force() {
        check_against_reference(&sq(&[0.3, 0.2, 0.5], &[2.0, 2.0, 2.0]), 100_000, 40, 21);
        check_against_reference(&sq(&[0.05, 0.3, 0.1], &[4.0, 4.0, 4.0]), 100_000, 40, 22);
        check_against_reference(&sq(&[0.05, 0.05, 0.2], &[1.0, 1.0, 2.0]), 100_000, 40, 23);
    }

    #[test]
    fn nested_superquadric_matches_brute_force() {
        let shape = Shape::Nested(NestedSuperquadric::new([0.3, 0.2, 0.5], 2.0, 3.0).unwrap());
        check_against_reference(&shape, 100_000, 40, 31);
        let shape = Shape::Nested(NestedSuperquadric::new([0.02, 0.01, 0.015], 3.0, 1.5).unwrap());
        check_against_reference(&shape, 100_000, 30, 32);
    }

    #[test]
    fn four_dimensional_superquadric_matches_brute_force() {
        check_against_reference(&sq(&[1.0, 0.4, 0.7, 0.2], &[1.5, 3.0, 1.0, 2.0]), 200_000, 20, 41);
    }

    #[test]
    fn boxes_on_their_axes() {
        let shape = sq(&[0.3, 0.2, 0.5], &[4.0, 4.0, 4.0]);
        for (i, a) in [0.3, 0.2, 0.5].iter().enumerate() {
            for x in [a + 1e-4, a + 0.3, 2.5] {
                let mut y = vec![0.0; 3];
                y[i] = -x;
                assert!((signed_distance(&shape, &y) - (x - a)).abs() < 1e-12);
            }
        }
        // Inside on the short axis, the nearest face is straight ahead.
        assert!((signed_distance(&shape, &[0.0, 0.15, 0.0]) + 0.05).abs() < 1e-12);
    }

    #[test]
    fn surface_points_are_at_distance_zero() {
        let shapes = [
            sq(&[0.3, 0.2], &[1.0, 1.0]),
            sq(&[0.3, 0.2], &[4.0, 2.0]),
            sq(&[0.3, 0.2, 0.5], &[2.0, 2.0, 2.0]),
            sq(&[0.01, 0.3, 0.2], &[1.0, 3.5, 1.2]),
            Shape::Nested(NestedSuperquadric::new([0.3, 0.2, 0.5], 2.0, 3.0).unwrap()),
            sq(&[1.0, 0.4, 0.7, 0.2], &[1.5, 3.0, 1.0, 2.0]),
        ];
        let mut rng = Rng(3);
        for shape in &shapes {
            let d = shape.dim();
            let mut z = vec![0.0; d];
            for _ in 0..30 {
                shape.surface_point(&rng.direction(d), &mut z);
                let got = signed_distance(shape, &z);
                assert!(got.abs() < 1e-12, "{shape:?} at {z:?}: {got}");
            }
        }
    }

    #[test]
    fn the_centre_is_at_minus_the_smallest_semi_axis() {
        // Every shape contains the ball of radius a_min, which touches the surface at +- a_min e_min.
        let shapes = [
            sq(&[0.3, 0.2], &[1.0, 1.0]),
            sq(&[0.3, 0.3], &[1.0, 1.0]),
            sq(&[0.3, 0.2, 0.5], &[4.0, 4.0, 4.0]),
            sq(&[0.5, 0.5, 0.5], &[2.0, 2.0, 2.0]),
            Shape::Nested(NestedSuperquadric::new([0.3, 0.2, 0.5], 2.0, 3.0).unwrap()),
            sq(&[1.0, 0.4, 0.7, 0.2], &[1.5, 3.0, 1.0, 2.0]),
            sq(&[0.7], &[2.0]),
        ];
        for shape in &shapes {
            let y = vec![0.0; shape.dim()];
            let a_min = shape.semi_axes().iter().fold(f64::INFINITY, |m, a| m.min(*a));
            let got = signed_distance(shape, &y);
            assert!(got.is_finite() && got < 0.0);
            assert!((got + a_min).abs() < 1e-12, "{shape:?}: {got}");
        }
    }

    #[test]
    fn one_dimensional_is_closed_form() {
        let s = sq(&[0.4], &[3.0]);
        for (y, want) in [(0.0, -0.4), (0.1, -0.3), (-0.3, -0.1), (0.4, 0.0), (-1.4, 1.0), (2.0, 1.6)] {
            assert!((signed_distance(&s, &[y]) - want).abs() < 1e-15);
        }
    }

    #[test]
    fn non_finite_inputs() {
        let s = sq(&[0.3, 0.2], &[1.0, 1.0]);
        assert!(signed_distance(&s, &[f64::NAN, 0.0]).is_nan());
        assert_eq!(signed_distance(&s, &[f64::INFINITY, 0.0]), f64::INFINITY);
    }

    #[test]
    fn world_frame_moves_and_rotates_the_point() {
        let shape = sq(&[0.3, 0.1, 0.2], &[2.0, 1.0, 3.0]);
        let (c, s) = (0.6_f64.cos(), 0.6_f64.sin());
        let rows = vec![vec![c, -s, 0.0], vec![s, c, 0.0], vec![0.0, 0.0, 1.0]];
        let o = Obstacle::new(
            "o",
            shape.clone(),
            vec![0.2, -0.1, 0.4],
            Some(rows.clone()),
            Some(vec![0.1, 0.0, -0.2]),
        )
        .unwrap();
        let t = 1.5;
        let centre = [0.2 + 0.1 * t, -0.1, 0.4 - 0.2 * t];
        for y in [[0.0, 0.0, 0.0], [0.5, 0.2, -0.1], [0.1, 0.05, 0.1], [-2.0, 1.0, 0.5]] {
            // x = c(t) + R y.
            let x: Vec<f64> =
                (0..3).map(|i| centre[i] + (0..3).map(|k| rows[i][k] * y[k]).sum::<f64>()).collect();
            let got = signed_distance_world(&o, &x, t);
            let want = signed_distance(&shape, &y);
            assert!((got - want).abs() < 1e-12, "{got} vs {want}");
        }
    }

    fn random_shape(rng: &mut Rng, d: usize) -> Shape {
        let axis = |rng: &mut Rng| 10f64.powf(rng.uniform(-2.0, 0.3));
        let exponent = |rng: &mut Rng| match (rng.uniform(0.0, 6.0)) as usize {
            0 => 1.0,
            1 => 2.0,
            2 => 3.0,
            3 => 4.0,
            _ => rng.uniform(1.0, 5.0),
        };
        if d == 3 && rng.uniform(0.0, 1.0) < 0.3 {
            let a = [axis(rng), axis(rng), axis(rng)];
            return Shape::Nested(NestedSuperquadric::new(a, exponent(rng), exponent(rng)).unwrap());
        }
        let a: Vec<f64> = (0..d).map(|_| axis(rng)).collect();
        let same = rng.uniform(0.0, 1.0) < 0.5;
        let e0 = exponent(rng);
        let n: Vec<f64> = (0..d).map(|_| if same { e0 } else { exponent(rng) }).collect();
        sq(&a, &n)
    }

    /// Sweep: `STRESS_D=3 STRESS_N=8 cargo test -p dmp --release distance::tests::stress -- --ignored --nocapture`.
    #[test]
    #[ignore]
    fn stress() {
        let d: usize = std::env::var("STRESS_D").map(|v| v.parse().unwrap()).unwrap_or(3);
        let shapes: usize = std::env::var("STRESS_SHAPES").map(|v| v.parse().unwrap()).unwrap_or(200);
        let coarse: Vec<usize> = std::env::var("STRESS_N")
            .map(|v| v.split(',').map(|x| x.parse().unwrap()).collect())
            .unwrap_or_else(|_| vec![grid_intervals(d)]);
        let fine = 4 * grid_intervals(d).max(8);
        let mut rng = Rng(12345);
        let mut worst = vec![(0.0_f64, String::new()); coarse.len()];
        let mut bad = vec![0usize; coarse.len()];
        let mut total = 0;
        for k in 0..shapes {
            let shape = random_shape(&mut rng, d);
            for y in test_points(&shape, 50, 1000 + k as u64) {
                let fine_result = nearest_with(&shape, &y, fine, 40).0;
                let results: Vec<f64> =
                    coarse.iter().map(|&n| nearest_with(&shape, &y, n, GRID_CANDIDATES).0).collect();
                let reference = results.iter().fold(fine_result.abs(), |m, r| m.min(r.abs()));
                if fine_result.abs() - reference > 1e-9 {
                    println!("fine missed by {:e}: {shape:?} y={y:?}", fine_result.abs() - reference);
                }
                total += 1;
                for (j, &got) in results.iter().enumerate() {
                    let diff = got.abs() - reference;
                    if diff.abs() > 1e-9 {
                        bad[j] += 1;
                    }
                    if diff.abs() > worst[j].0 {
                        worst[j] = (diff.abs(), format!("{shape:?} y={y:?} got={got} fine={reference}"));
                    }
                }
            }
        }
        for (j, n) in coarse.iter().enumerate() {
            println!("N={n}: {} of {total} differ by > 1e-9; worst {:e}: {}", bad[j], worst[j].0, worst[j].1);
        }
    }

    #[test]
    #[ignore]
    fn debug_case() {
        let shape = sq(&[0.038192055192756695, 0.0415112927437198, 1.9154416801833019], &[4.0, 4.0, 4.0]);
        let y = [0.01488182841659313, 0.018506278703039263, -0.5883559183677924];
        for n in [8, 12, 24, 48] {
            let mut solver = Solver::new(&shape, &y, n, 40);
            let mut cands = Vec::new();
            solver.grid_candidates(Param::Surface, &mut cands);
            let ns = cands.len();
            solver.grid_candidates(Param::Radial, &mut cands);
            for (i, c) in cands.iter().enumerate() {
                let f0 = dist2(c, &y).sqrt();
                let mut z = c.clone();
                let f = solver.refine(&mut z).sqrt();
                println!(
                    "N={n} {} {c:.4?} start {f0:.6} -> {f:.9} at {z:.5?}",
                    if i < ns { "S" } else { "R" }
                );
            }
        }
    }

    /// Time per call: `cargo test -p dmp --release distance::tests::timing -- --ignored --nocapture`.
    #[test]
    #[ignore]
    fn timing() {
        let shapes = [
            ("ellipse", sq(&[0.3, 0.2], &[1.0, 1.0])),
            ("box n=4 2-D", sq(&[0.3, 0.1], &[4.0, 4.0])),
            ("ellipsoid", sq(&[0.3, 0.2, 0.5], &[1.0, 1.0, 1.0])),
            ("box n=2", sq(&[0.3, 0.2, 0.5], &[2.0, 2.0, 2.0])),
            ("mixed (1,1,2)", sq(&[0.05, 0.05, 0.2], &[1.0, 1.0, 2.0])),
            ("nested (2,3)", Shape::Nested(NestedSuperquadric::new([0.3, 0.2, 0.5], 2.0, 3.0).unwrap())),
            ("4-D", sq(&[1.0, 0.4, 0.7, 0.2], &[1.5, 3.0, 1.0, 2.0])),
        ];
        for (name, shape) in &shapes {
            let points = test_points(shape, 1000, 5);
            let start = std::time::Instant::now();
            let mut acc = 0.0;
            for y in &points {
                acc += signed_distance(shape, y);
            }
            let per_call = start.elapsed().as_secs_f64() / points.len() as f64;
            println!("{name:>14}: {:8.1} us per call (checksum {acc:.6})", per_call * 1e6);
        }
    }
}
