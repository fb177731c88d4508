//! The radial projection `rho(p) = s p` onto a shape's surface `C = 0`.
//!
//! It is closed form for the nested shape (`C + 1` is homogeneous of degree `2 m`) and for a
//! superquadric with equal exponents (degree `2 n`); with mixed exponents `s` solves
//! `psi(tau) = ln sum_i (c_i e^tau)^(2 n_i) = 0`, `c_i = |p_i| / a_i`, by Newton's method in `tau = ln s` started
//! where `psi >= 0`: `psi` is a convex, increasing log-sum-exp, so the iterates decrease monotonically to the root.

use crate::isopotential::{Isopotential, Shape, abs_pow};

/// `out = s p` with `C(s p) = 0`, `s > 0`; `false` (and `out` untouched) for `p = 0` or a non-finite result.
pub(super) fn radial_projection(shape: &Shape, p: &[f64], out: &mut [f64]) -> bool {
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
