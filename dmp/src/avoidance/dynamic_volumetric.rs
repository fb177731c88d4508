//! The paper's contribution: the dynamic superquadric potential of a volume (`eq:dynamic_potential_volume`).

use super::{DynamicVolumetric, dot, norm, pow};

/// # Formula
/// `U_D = lambda (-cos theta)^beta |u| / C^eta` when `cos theta = <grad C, u> / (|grad C| |u|) < 0`, else 0.
#[cfg(test)]
pub(crate) fn potential(c: f64, grad: &[f64], u: &[f64], params: &DynamicVolumetric) -> f64 {
    let DynamicVolumetric { lambda, beta, eta } = *params;
    let (gn, un) = (norm(grad), norm(u));
    if gn == 0.0 || un == 0.0 {
        return 0.0;
    }
    let cos = dot(grad, u) / (gn * un);
    if cos >= 0.0 { 0.0 } else { lambda * (-cos).powf(beta) * un * c.powf(-eta) }
}

/// Whether the term is active: `cos theta < 0` (moving toward the obstacle), with `grad C` and `u` non-zero.
pub(crate) fn is_active(grad: &[f64], u: &[f64]) -> bool {
    dot(grad, u) < 0.0 && norm(grad) > 0.0 && norm(u) > 0.0
}

/// Adds `phi = -grad_x U_D` to `out`, for `C > 0`. `hu = H u` and `hg = H grad C` are the products of the Hessian
/// `H` of `C` with `u` and with `grad C` (all the term needs of `H`, so a caller with a rotated diagonal Hessian
/// never forms it).
///
/// # Formula
/// (ERRATA.md, term 5, with `|grad C|^2` in the denominator and the factor `eta` kept)
/// `grad cos = (H u |grad C| - <grad C, u> H grad C / |grad C|) / (|u| |grad C|^2)`,
/// `phi = lambda |u| (-cos)^(beta - 1) C^(-eta) (beta grad cos - eta cos grad C / C)`.
pub(crate) fn add_force(
    c: f64,
    grad: &[f64],
    hu: &[f64],
    hg: &[f64],
    u: &[f64],
    params: &DynamicVolumetric,
    out: &mut [f64],
) {
    let DynamicVolumetric { lambda, beta, eta } = *params;
    let (gn, un) = (norm(grad), norm(u));
    if gn == 0.0 || un == 0.0 {
        return;
    }
    let gu = dot(grad, u);
    let cos = gu / (gn * un);
    if cos >= 0.0 {
        return;
    }
    let k = lambda * un * pow(-cos, beta - 1.0) * pow(c, -eta);
    let inv = 1.0 / (un * gn * gn);
    for i in 0..grad.len() {
        let grad_cos = (hu[i] * gn - gu * hg[i] / gn) * inv;
        out[i] += k * (beta * grad_cos - eta * cos * grad[i] / c);
    }
}
