//! The static superquadric potential of a volume (paper, `eq:static_potential_volume`).

/// # Formula
/// `U_S = A exp(-eta C) / C`.
#[cfg(test)]
pub(crate) fn potential(c: f64, a: f64, eta: f64) -> f64 {
    a * (-eta * c).exp() / c
}

/// Adds `phi = -grad U_S` to `out`, for `C > 0` (the caller floors `C` inside an obstacle).
///
/// # Formula
/// `phi = A exp(-eta C) (eta / C + 1 / C^2) grad C` (ERRATA.md, term 4).
pub(crate) fn add_force(c: f64, grad: &[f64], a: f64, eta: f64, out: &mut [f64]) {
    let k = a * (-eta * c).exp() * (eta / c + 1.0 / (c * c));
    for (o, g) in out.iter_mut().zip(grad) {
        *o += k * g;
    }
}
