//! The Jacobians of the exponential and logarithm maps of the rotation vector, and the time derivative of the
//! first: what turns the tangent-space state `(y, ẏ, ÿ)` into the angular velocity and acceleration, exactly.
//!
//! # Formula
//! With `E(t) = exp(y(t))` (rotation vector convention, [`super::quaternion`]), the angular velocity of `E` in the
//! world frame is `ω = 2 vec(Ė ⊗ Ē)`, and, with `J` the left Jacobian of SO(3) (Barfoot, *State Estimation for
//! Robotics*, the SO(3) Jacobians; pytransform3d's `left_jacobian_SO3` writes the same matrix as
//! `sin θ/θ I + (1 - cos θ)/θ [n]× + (1 - sin θ/θ) n nᵀ`), the tests below check every line against finite
//! differences:
//!
//! - `ω = J(y) ẏ`, `J(y) = I + a(θ) [y]× + b(θ) [y]×²`, `θ = |y|`, `a = (1 - cos θ) / θ²`, `b = (θ - sin θ) / θ³`;
//! - `ẏ = J⁻¹(y) ω`, `J⁻¹(y) = I - ½ [y]× + c(θ) [y]×²`, `c = (1 - (θ/2) cot(θ/2)) / θ²` (singular at `θ = 2π`);
//! - `ω̇ = J(y) ÿ + J̇ ẏ`, `J̇ ẏ = (y·ẏ) a₁(θ) y × ẏ + (y·ẏ) b₁(θ) y × (y × ẏ) + b(θ) ẏ × (y × ẏ)`, where
//!   `a₁ = a'(θ) / θ = (θ sin θ - 2 (1 - cos θ)) / θ⁴` and `b₁ = b'(θ) / θ = (θ (1 - cos θ) - 3 (θ - sin θ)) / θ⁵`
//!   (from `J̇ = ȧ [y]× + a [ẏ]× + ḃ [y]×² + b ([ẏ]× [y]× + [y]× [ẏ]×)`, `θ̇ = y·ẏ / θ`, `ẏ × ẏ = 0`).
//!
//! Every coefficient is an even function of `θ`, evaluated by its Taylor series below [`SERIES_BELOW`] where the
//! closed forms cancel, so each map is smooth through `y = 0`, where `J = J⁻¹ = I`.

use nalgebra::{Matrix3, Vector3};

/// Below this angle (radians) the coefficients are summed from their Taylor series (8 terms: the first omitted
/// one is under `1e-20` relative); above it the closed forms lose at most about `60 ε / θ⁴ < 3e-13` relative to
/// cancellation (the worst is `b₁`).
pub(crate) const SERIES_BELOW: f64 = 0.5;

/// Terms summed of each series.
const TERMS: i32 = 8;

/// The coefficients of `J` and `J̇` at angle `theta`.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Coefficients {
    a: f64,
    b: f64,
    a1: f64,
    b1: f64,
}

/// `sum_{k < TERMS} coef(k, 1 / n!) θ^{2k}` in Horner's form, where `n!` is the factorial `coef` asks for.
fn even_series(t2: f64, coef: impl Fn(i32, &dyn Fn(i32) -> f64) -> f64) -> f64 {
    let factorial = |n: i32| (2..=n).map(f64::from).product::<f64>();
    (0..TERMS).rev().fold(0.0, |acc, k| acc * t2 + coef(k, &factorial))
}

fn coefficients(theta: f64) -> Coefficients {
    if theta < SERIES_BELOW {
        let t2 = theta * theta;
        let sign = |k: i32| if k % 2 == 0 { 1.0 } else { -1.0 };
        Coefficients {
            // a = sum (-1)^k θ^2k / (2k + 2)!, b = sum (-1)^k θ^2k / (2k + 3)!, and their derivatives over θ.
            a: even_series(t2, |k, f| sign(k) / f(2 * k + 2)),
            b: even_series(t2, |k, f| sign(k) / f(2 * k + 3)),
            a1: even_series(t2, |k, f| -sign(k) * f64::from(2 * k + 2) / f(2 * k + 4)),
            b1: even_series(t2, |k, f| -sign(k) * f64::from(2 * k + 2) / f(2 * k + 5)),
        }
    } else {
        let (s, t2) = (theta.sin(), theta * theta);
        // 1 - cos θ without cancellation.
        let one_minus_cos = 2.0 * (0.5 * theta).sin().powi(2);
        let theta_minus_sin = theta - s;
        Coefficients {
            a: one_minus_cos / t2,
            b: theta_minus_sin / (t2 * theta),
            a1: (theta * s - 2.0 * one_minus_cos) / (t2 * t2),
            b1: (theta * one_minus_cos - 3.0 * theta_minus_sin) / (t2 * t2 * theta),
        }
    }
}

/// `c(θ) = (1 - (θ/2) cot(θ/2)) / θ²` of `J⁻¹`; below [`SERIES_BELOW`], `-sum_{n >= 1} (-1)^n B_2n θ^(2n-2) / (2n)!`
/// (Bernoulli numbers), all terms positive.
fn inverse_coefficient(theta: f64) -> f64 {
    if theta < SERIES_BELOW {
        const C: [f64; 7] = [
            1.0 / 12.0,
            1.0 / 720.0,
            1.0 / 30_240.0,
            1.0 / 1_209_600.0,
            1.0 / 47_900_160.0,
            691.0 / 1_307_674_368_000.0,
            1.0 / 74_724_249_600.0,
        ];
        let t2 = theta * theta;
        C.iter().rev().fold(0.0, |acc, c| acc * t2 + c)
    } else {
        let half = 0.5 * theta;
        (1.0 - half * half.cos() / half.sin()) / (theta * theta)
    }
}

/// The skew matrix `[y]×`, with `[y]× u = y × u`.
fn skew(y: &Vector3<f64>) -> Matrix3<f64> {
    y.cross_matrix()
}

/// `J(y)`: the world-frame angular velocity of `exp(y(t))` is `J(y) ẏ` (module formula).
pub(crate) fn exp_jacobian(y: &Vector3<f64>) -> Matrix3<f64> {
    let c = coefficients(y.norm());
    let s = skew(y);
    Matrix3::identity() + s * c.a + s * s * c.b
}

/// `J⁻¹(y)`: `d/dt log(e(t)) = J⁻¹(log e) ω` for the world-frame angular velocity `ω` of `e` (module formula).
/// Finite for angles below `2π`.
pub(crate) fn log_jacobian(y: &Vector3<f64>) -> Matrix3<f64> {
    let s = skew(y);
    Matrix3::identity() - s * 0.5 + s * s * inverse_coefficient(y.norm())
}

/// The angular velocity `ω = J(y) ẏ` and acceleration `ω̇ = J(y) ÿ + J̇ ẏ` of `exp(y(t))`, world frame.
pub(crate) fn angular_motion(
    y: &Vector3<f64>,
    yd: &Vector3<f64>,
    ydd: &Vector3<f64>,
) -> (Vector3<f64>, Vector3<f64>) {
    let c = coefficients(y.norm());
    let jac = |u: &Vector3<f64>| {
        let yu = y.cross(u);
        u + yu * c.a + y.cross(&yu) * c.b
    };
    let y_yd = y.cross(yd);
    let rate = y.dot(yd);
    let jdot_yd = y_yd * (rate * c.a1) + y.cross(&y_yd) * (rate * c.b1) + yd.cross(&y_yd) * c.b;
    (jac(yd), jac(ydd) + jdot_yd)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::orientation::quaternion::{exp, log};

    /// Rotation vectors of small, medium, near-π and beyond-π angles, on both sides of the series switch.
    fn points() -> Vec<Vector3<f64>> {
        let axis = Vector3::new(0.3, -0.5, 0.8).normalize();
        [0.0, 1e-6, 0.05, 0.3, SERIES_BELOW * (1.0 - 1e-12), SERIES_BELOW, 0.7, 2.0, 3.1, 4.5, 5.5]
            .iter()
            .map(|&t| axis * t + Vector3::new(0.0, 1e-3, 0.0) * t.min(1.0))
            .collect()
    }

    fn direction() -> Vector3<f64> {
        Vector3::new(-0.4, 0.9, 0.25)
    }

    #[test]
    fn the_exp_jacobian_is_the_finite_difference_of_the_orientation() {
        let h = 1e-5;
        let v = direction();
        for y in points() {
            // ω = Log(exp(y + h v) ⊗ exp(y - h v)⁻¹) / 2h + O(h²).
            let fd = log(&(exp(&(y + v * h)) * exp(&(y - v * h)).conjugate())) / (2.0 * h);
            let exact = exp_jacobian(&y) * v;
            assert!((fd - exact).norm() < 1e-9, "y = {y:?}: {fd:?} vs {exact:?}");
            let (omega, _) = angular_motion(&y, &v, &Vector3::zeros());
            assert!((omega - exact).norm() < 1e-15);
        }
    }

    #[test]
    fn the_log_jacobian_is_the_finite_difference_of_the_logarithm() {
        let h = 1e-5;
        let omega = direction();
        for y in points() {
            let e = exp(&y);
            let fd = (log(&(exp(&(omega * h)) * e)) - log(&(exp(&(-omega * h)) * e))) / (2.0 * h);
            let exact = log_jacobian(&y) * omega;
            assert!((fd - exact).norm() < 1e-8, "y = {y:?}: {fd:?} vs {exact:?}");
            assert!((exp_jacobian(&y) * log_jacobian(&y) - Matrix3::identity()).norm() < 1e-13);
        }
    }

    #[test]
    fn the_angular_acceleration_is_the_finite_difference_of_the_angular_velocity() {
        // A curve y(t) = y + t v + t² w / 2, so ẏ(0) = v and ÿ(0) = w; ω(t) = J(y(t)) ẏ(t).
        let h = 1e-5;
        let (v, w) = (direction(), Vector3::new(0.7, 0.1, -0.6));
        for y in points() {
            let omega_at = |t: f64| {
                let (o, _) =
                    angular_motion(&(y + v * t + w * (0.5 * t * t)), &(v + w * t), &Vector3::zeros());
                o
            };
            let fd = (omega_at(h) - omega_at(-h)) / (2.0 * h);
            let (_, exact) = angular_motion(&y, &v, &w);
            assert!((fd - exact).norm() < 1e-8, "y = {y:?}: {fd:?} vs {exact:?}");
        }
    }

    #[test]
    fn the_series_and_the_closed_forms_agree_at_the_switch() {
        let below = coefficients(SERIES_BELOW * (1.0 - 1e-15));
        let above = coefficients(SERIES_BELOW);
        for (x, y) in [(below.a, above.a), (below.b, above.b), (below.a1, above.a1), (below.b1, above.b1)] {
            assert!((x - y).abs() <= 1e-12 * y.abs(), "{x} vs {y}");
        }
        let (x, y) = (inverse_coefficient(SERIES_BELOW * (1.0 - 1e-15)), inverse_coefficient(SERIES_BELOW));
        assert!((x - y).abs() <= 1e-12 * y, "{x} vs {y}");
    }

    #[test]
    fn along_a_fixed_axis_the_jacobian_is_the_identity() {
        let y = Vector3::new(0.3, -0.5, 0.8);
        let (omega, omega_dot) = angular_motion(&y, &(y * 2.0), &(y * -3.0));
        assert!((omega - y * 2.0).norm() < 1e-15 && (omega_dot - y * -3.0).norm() < 1e-15);
    }
}
