//! Signed Euclidean distance from a point to an obstacle's surface `C = 0`, used to report clearances.
//!
//! # Method
//! Every [`Shape`] is a convex body `K = {C <= 0}` around its centre, and `C` grows along every ray from the
//! centre, so each direction `p != 0` meets the surface once, at the *radial projection* `rho(p) = s p` with
//! `C(s p) = 0`. The distance from `y` to the surface is the smallest `|z - y|` over surface points `z`: a problem
//! with several local minima in general (inside, or outside a thin shape), solved in three steps.
//!
//! 1. **Local polish.** A surface point is polished by a damped Newton method on the surface
//!    (Levenberg-Marquardt on the KKT system of `min |z - y|^2 / 2` subject to `C(z) = 0`). At a surface point `z`
//!    with normal `nu = grad C / |grad C|`, residual `r = z - y`, tangential gradient `t = r - (r . nu) nu` and
//!    multiplier `mu = -(r . nu) / |grad C|`, the step solves
//!    `[[I + mu H + lambda I, nu], [nu^T, 0]] [dz; eta] = [-t; 0]` (`H` the Hessian of `C`, `I + mu H` the Hessian of
//!    the Lagrangian) and `z + dz` is projected back radially. A step is kept only if it is a descent direction of
//!    the model (`-t . dz > 0`), no longer than the largest semi-axis and lowers `|z - y|`; otherwise `lambda`
//!    grows tenfold. It stops when `|t| <= 1e-13 (|r| + a_max)` or when no step helps any more.
//! 2. **Certificate outside.** For `C(y) > 0` the distance is that to the convex set `K`, a strongly convex
//!    problem: with `F = |x - y|^2 / 2` plus the indicator of `K`, a surface point `z` with `y` on the outer side of
//!    its tangent plane (`r . nu < 0`) has the subgradient `r - (r . nu) nu = t`, so `F(z) - F* <= |t|^2 / 2` and
//!    `|z - y| - dist <= |t|^2 / |z - y|`. The polish of `rho(y)` almost always ends at such a point with that
//!    bound below `1e-12`, and then the answer is final.
//! 3. **Zooming cubes.** Otherwise (inside, or no certificate), with `D` the best distance so far, every surface
//!    point closer than `D` lies in the cube `y + [-D, D]^d` and is the radial projection of a point of that cube's
//!    faces. Each face carries a regular `(d - 1)`-dimensional grid (extended one node past its edges); the
//!    projected nodes that are discrete local minima of `|z - y|^2` over their face, the best node of each face and
//!    the best node overall are polished. `D` shrinks to the best result and the search repeats on the smaller
//!    cube, so the grid resolution follows the distance, until `D` stops decreasing.
//!
//! The result `|z* - y|` is attained by a point on the surface (to rounding), so it is never below the true
//! distance; its sign is that of `C(y)`. In 1-D the answer is `|y| - a` in closed form. The radial projection
//! is closed form or a monotone Newton iteration (module `radial`).

use crate::isopotential::{Isopotential, Shape};
use crate::obstacle::{Obstacle, WorldEval};

mod radial;

use radial::radial_projection;

/// Discrete local minima polished per cube.
const GRID_CANDIDATES: usize = 6;
/// Most local cubes searched.
const MAX_LEVELS: usize = 6;
/// Newton iterations per candidate.
const MAX_ITERATIONS: usize = 100;
/// Damping increases tried per iteration before giving up.
const MAX_DAMPING_TRIES: usize = 30;
/// Largest error, in length units, of a distance accepted through the outside certificate.
const CERTIFICATE_TOL: f64 = 1e-12;
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
pub(crate) fn nearest_surface_point(shape: &Shape, y: &[f64]) -> (f64, Vec<f64>) {
    let config =
        Config { intervals: grid_intervals(shape.dim()), per_grid: GRID_CANDIDATES, levels: MAX_LEVELS };
    nearest_with(shape, y, config)
}

/// [`nearest_surface_point`] with explicit search settings.
fn nearest_with(shape: &Shape, y: &[f64], config: Config) -> (f64, Vec<f64>) {
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
    let mut solver = Solver::new(shape, y, config);
    let (f, z) = solver.solve();
    (sign * f.sqrt(), z)
}

/// Search settings.
#[derive(Debug, Clone, Copy)]
struct Config {
    /// Grid intervals per face edge of the cubes.
    intervals: usize,
    /// Discrete local minima kept per grid.
    per_grid: usize,
    /// Most local cubes.
    levels: usize,
}

/// Outcome of one refinement.
struct Refined {
    /// `|z - y|^2`.
    f: f64,
    /// `y` is outside and `|z - y|` is certified to be its distance within [`CERTIFICATE_TOL`].
    certified: bool,
}

/// Scratch of one distance query.
struct Solver<'a> {
    shape: &'a Shape,
    y: &'a [f64],
    d: usize,
    /// Largest semi-axis.
    length: f64,
    config: Config,
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
    fn new(shape: &'a Shape, y: &'a [f64], config: Config) -> Self {
        let d = shape.dim();
        let length = shape.semi_axes().iter().fold(0.0_f64, |m, a| m.max(*a));
        Self {
            shape,
            y,
            d,
            length,
            config,
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
        let outside = self.shape.value(self.y) > 0.0;
        let mut best = (f64::INFINITY, vec![0.0; d]);
        // Seed: the radial projection of y.
        let mut z = vec![0.0; d];
        if radial_projection(self.shape, self.y, &mut z) {
            let refined = self.refine(&mut z);
            if refined.f == 0.0 || (outside && refined.certified) {
                return (refined.f, z);
            }
            best = (refined.f, z);
        }
        // Every surface point closer than the best so far lies in the cube of that half-side around y.
        let mut half = if best.0.is_finite() { best.0.sqrt() } else { self.length };
        let mut candidates: Vec<Vec<f64>> = Vec::new();
        for _ in 0..self.config.levels {
            self.cube_candidates(half * (1.0 + 1e-9), &mut candidates);
            for mut c in candidates.drain(..) {
                let refined = self.refine(&mut c);
                if refined.f < best.0 {
                    best = (refined.f, c);
                    if outside && refined.certified {
                        return best;
                    }
                }
            }
            let new_half = best.0.sqrt();
            if new_half.is_nan() || new_half >= half * (1.0 - 1e-6) {
                break;
            }
            half = new_half;
        }
        if !best.0.is_finite() {
            // Unreachable for valid shapes; a vertex keeps the answer finite.
            best.1.fill(0.0);
            best.1[0] = self.shape.semi_axes()[0];
            best.0 = dist2(&best.1, self.y);
        }
        best
    }

    /// Appends the polishing candidates of the cube `y + [-half, half]^d`: the radial projections of the grid nodes
    /// on its faces that are the best overall, the best of their face, or (the best `per_grid` of) the discrete
    /// local minima of `|z - y|^2` over their face; near-duplicates are skipped.
    fn cube_candidates(&self, half: f64, out: &mut Vec<Vec<f64>>) {
        let d = self.d;
        let intervals = self.config.intervals;
        // Nodes 1..=intervals + 1 cover the face [-1, 1]; nodes 0 and intervals + 2 lie one step beyond its edges.
        let nodes = intervals + 3;
        let per_face = nodes.pow(d as u32 - 1);
        let u: Vec<f64> = (0..nodes).map(|i| -1.0 + 2.0 * (i as f64 - 1.0) / intervals as f64).collect();
        let strides: Vec<usize> = (0..d - 1).map(|s| nodes.pow(s as u32)).collect();
        let mut values = vec![f64::INFINITY; 2 * d * per_face];
        let (mut p, mut z) = (vec![0.0; d], vec![0.0; d]);
        let mut idx = vec![0usize; d - 1];
        let mut best = (f64::INFINITY, 0usize);
        for face in 0..2 * d {
            for flat in 0..per_face {
                decode(flat, nodes, &mut idx);
                self.cube_point(half, face, &idx, &u, &mut p);
                if radial_projection(self.shape, &p, &mut z) {
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
        minima.truncate(self.config.per_grid);
        let separation = 1e-9 * self.length;
        for (v, node) in std::iter::once(best).chain(face_best).chain(minima) {
            if !v.is_finite() {
                continue;
            }
            decode(node % per_face, nodes, &mut idx);
            self.cube_point(half, node / per_face, &idx, &u, &mut p);
            if radial_projection(self.shape, &p, &mut z)
                && out.iter().all(|k| dist2(k, &z).sqrt() > separation)
            {
                out.push(z.clone());
            }
        }
    }

    /// Node `idx` of face `face` (axis `face / 2`, on the `+` side for even faces) of the cube `y + [-half, half]^d`.
    fn cube_point(&self, half: f64, face: usize, idx: &[usize], u: &[f64], p: &mut [f64]) {
        let axis = face / 2;
        let mut slot = 0;
        for (j, v) in p.iter_mut().enumerate() {
            let offset = if j == axis {
                if face.is_multiple_of(2) { 1.0 } else { -1.0 }
            } else {
                slot += 1;
                u[idx[slot - 1]]
            };
            *v = self.y[j] + half * offset;
        }
    }

    /// Polishes the surface point `z` in place (damped Newton on the KKT system, see the module documentation).
    fn refine(&mut self, z: &mut [f64]) -> Refined {
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
        Refined { f, certified: self.certify(z) }
    }

    /// Whether `|z - y|` is within [`CERTIFICATE_TOL`] of the distance from an outside `y` to `K`: for `y` on the
    /// outer side of the tangent plane (`r . nu < 0`), strong convexity of `F = |x - y|^2 / 2 + indicator(K)` with the
    /// subgradient `r - (r . nu) nu = t` gives `F(z) - F* <= |t|^2 / 2`, so `|z - y| - dist <= |t|^2 / |z - y|`.
    fn certify(&mut self, z: &[f64]) -> bool {
        let d = self.d;
        self.shape.eval(z, &mut self.grad, &mut self.hess);
        let gn = norm(&self.grad);
        if !(gn > 0.0 && gn.is_finite()) {
            return false;
        }
        for i in 0..d {
            self.r[i] = z[i] - self.y[i];
        }
        self.grad.iter_mut().for_each(|g| *g /= gn);
        let rn = dot(&self.r, &self.grad);
        for i in 0..d {
            self.t[i] = self.r[i] - rn * self.grad[i];
        }
        rn < 0.0 && dot(&self.t, &self.t) <= CERTIFICATE_TOL * norm(&self.r)
    }
}

/// Grid intervals per face edge of the cubes for dimension `d >= 2` (`2 d (n + 3)^(d - 1)` nodes per cube).
fn grid_intervals(d: usize) -> usize {
    match d {
        2 => 8,
        3 => 6,
        4 => 4,
        _ => 2,
    }
}

/// Mixed-radix digits of `flat` in base `nodes`.
fn decode(mut flat: usize, nodes: usize, idx: &mut [usize]) {
    for i in idx.iter_mut() {
        *i = flat % nodes;
        flat /= nodes;
    }
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
mod tests;
