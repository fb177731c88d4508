//! Khatib's static potential of a point obstacle (paper, `eq:static_potential_khatib`).

use super::dot;

/// # Formula
/// `U_s = (eta / 2) (1/p - 1/p0)^2` for `p = |r| <= p0`, else 0, with `r = x - o`.
#[cfg(test)]
pub(crate) fn potential(r: &[f64], eta: f64, p0: f64) -> f64 {
    let p = super::norm(r);
    if p > p0 || p == 0.0 { 0.0 } else { 0.5 * eta * (1.0 / p - 1.0 / p0).powi(2) }
}

/// Adds `phi = -grad U_s` to `out`.
///
/// # Formula
/// `phi = eta (1/p - 1/p0) r / p^3` for `p <= p0` (ERRATA.md, term 1). At `p = 0` the direction is undefined and
/// nothing is added.
pub(crate) fn add_force(r: &[f64], eta: f64, p0: f64, out: &mut [f64]) {
    let p2 = dot(r, r);
    if p2 > p0 * p0 || p2 == 0.0 {
        return;
    }
    let p = p2.sqrt();
    let k = eta * (1.0 / p - 1.0 / p0) / (p2 * p);
    for (o, ri) in out.iter_mut().zip(r) {
        *o += k * ri;
    }
}
