//! The canonical system, integrated in closed form.

/// Phase decay of the canonical system (paper, `eq:can_sys`).
///
/// # Formula
/// `tau * ds/dt = -alpha * s`, `s(0) = 1`, hence `s(t) = exp(-alpha * t / tau)`. Over a step of length `dt`
/// with `tau` constant, `s(t + dt) = s(t) * exp(-alpha * dt / tau)`: stepping the phase this way is exact and
/// stays continuous when `tau` changes between steps.
///
/// ```
/// let s = dmp::canonical::phase_after(1.0, 4.0, 1.0, 0.5);
/// assert!((s - (-2.0f64).exp()).abs() < 1e-15);
/// ```
pub fn phase_after(s: f64, alpha: f64, tau: f64, dt: f64) -> f64 {
    s * (-alpha * dt / tau).exp()
}

/// The phase at time `t` of a run that started at `s = 1` with a constant `tau` (learning fits the forcing term at
/// these phases).
#[cfg(any(test, feature = "learn"))]
pub(crate) fn phase_at(alpha: f64, tau: f64, t: f64) -> f64 {
    (-alpha * t / tau).exp()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stepping_matches_the_closed_form() {
        let (alpha, tau, dt) = (4.0, 1.3, 1e-3);
        let mut s = 1.0;
        for _ in 0..1000 {
            s = phase_after(s, alpha, tau, dt);
        }
        assert!((s - phase_at(alpha, tau, 1.0)).abs() < 1e-12);
        assert!(s > 0.0 && s <= 1.0);
    }
}
