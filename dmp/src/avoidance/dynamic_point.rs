//! Park's dynamic potential of a point obstacle (paper, `eq:dynamic_potential_park`).

use super::{dot, norm, pow};

/// # Formula
/// `U_d = lambda (-cos theta)^beta |u| / p` when `cos theta = <u, r> / (|u| p) < 0`, else 0; `r = x - o`,
/// `u` the velocity relative to the obstacle.
#[cfg(test)]
pub(crate) fn potential(r: &[f64], u: &[f64], lambda: f64, beta: f64) -> f64 {
    let (p, un) = (norm(r), norm(u));
    if p == 0.0 || un == 0.0 {
        return 0.0;
    }
    let cos = dot(u, r) / (un * p);
    if cos >= 0.0 { 0.0 } else { lambda * (-cos).powf(beta) * un / p }
}

/// Adds `phi = -grad_x U_d` to `out`.
///
/// # Formula
/// (ERRATA.md, term 2) `grad cos = (p^2 u - <u, r> r) / (|u| p^3)`,
/// `phi = lambda |u| (-cos)^(beta - 1) / p * (beta grad cos - cos r / p^2)`.
pub(crate) fn add_force(r: &[f64], u: &[f64], lambda: f64, beta: f64, out: &mut [f64]) {
    let (p2, un) = (dot(r, r), norm(u));
    if p2 == 0.0 || un == 0.0 {
        return;
    }
    let p = p2.sqrt();
    let ur = dot(u, r);
    let cos = ur / (un * p);
    if cos >= 0.0 {
        return;
    }
    let k = lambda * un * pow(-cos, beta - 1.0) / p;
    let inv = 1.0 / (un * p2 * p);
    for ((o, ri), ui) in out.iter_mut().zip(r).zip(u) {
        let grad_cos = (p2 * ui - ur * ri) * inv;
        *o += k * (beta * grad_cos - cos * ri / p2);
    }
}
