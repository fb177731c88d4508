//! Unit quaternions at the edge and in the tangent space: the wire order, the logarithm and exponential maps, the
//! double cover, and the angle between two orientations.
//!
//! # Conventions (fixed once, used everywhere in [`crate::orientation`])
//! - **Wire order** `[x, y, z, w]`; Hamilton's product `⊗`; an orientation `q` rotates tool-frame vectors into the
//!   world frame, `v_world = q ⊗ v_tool ⊗ q̄`.
//! - **Logarithm: the rotation vector.** For `e = (w, v) = (cos(θ/2), sin(θ/2) n)`, [`log`] returns `θ n`, the
//!   *full* angle times the axis, `θ = 2 atan2(|v|, w)`: twice the half-angle logarithm `acos(w) v / |v|` of Ude et
//!   al. Its norm is the rotation angle in radians, so the stiffness of an orientation DMP is per radian, as the
//!   position DMP's is per metre, and at the identity its Jacobian is `I`. The inverse map is [`exp`],
//!   `exp(y) = (cos(|y|/2), sin(|y|/2) y / |y|)`. `atan2` rather than `acos` keeps small angles to full precision.
//! - **Double cover.** `q` and `-q` are the same orientation. [`log`] does not fold its argument to `w >= 0`: it
//!   returns an angle in `[0, 2π)`, continuous along any continuous path that avoids `e = -1`, which is what a
//!   sign-consistent demonstration needs. `closest_sign` picks the representative of a goal nearest to a
//!   reference (`w` of `q ⊗ ḡ` >= 0), so that a rotation never takes the 360° detour; [`angle_between`] is
//!   sign-blind.

use nalgebra::{Quaternion, UnitQuaternion, Vector3, Vector4};

use crate::error::InvalidInput;

/// How far from 1 the norm of an incoming quaternion may be. A quaternion of `f32`s normalised by the sender is
/// within about `1e-7`; anything further is refused rather than silently renormalised.
pub const UNIT_TOLERANCE: f64 = 1e-6;

/// The unit quaternion of `[x, y, z, w]`, checked and renormalised (see [`UNIT_TOLERANCE`]); the error names
/// `field`.
///
/// ```
/// use dmp::orientation::quaternion::{from_xyzw, to_xyzw};
/// let q = from_xyzw("q", [0.0, 0.0, std::f64::consts::FRAC_1_SQRT_2, std::f64::consts::FRAC_1_SQRT_2]).unwrap();
/// assert!((q.angle() - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
/// assert_eq!(to_xyzw(&q)[3], q.w);
/// assert!(from_xyzw("q", [0.0, 0.0, 0.0, 1.1]).is_err());
/// ```
pub fn from_xyzw(field: &str, q: [f64; 4]) -> Result<UnitQuaternion<f64>, InvalidInput> {
    if q.iter().any(|v| !v.is_finite()) {
        return Err(InvalidInput::new(field, "must be four finite numbers (x, y, z, w)"));
    }
    let raw = Quaternion::from(Vector4::from(q));
    let norm = raw.norm();
    if (norm - 1.0).abs() > UNIT_TOLERANCE {
        return Err(InvalidInput::new(
            field,
            format!(
                "must be a unit quaternion (x, y, z, w): its norm is {norm}, more than {UNIT_TOLERANCE} from 1"
            ),
        ));
    }
    Ok(UnitQuaternion::new_unchecked(raw / norm))
}

/// `[x, y, z, w]` of `q`.
pub fn to_xyzw(q: &UnitQuaternion<f64>) -> [f64; 4] {
    [q.i, q.j, q.k, q.w]
}

/// The rotation vector of `e`: its angle times its axis (see the module's conventions).
///
/// # Formula
/// `log(e) = 2 atan2(|v|, w) v / |v|` for `e = (w, v)`, and `0` for `v = 0`. The angle lies in `[0, 2π)`; `e` and
/// `-e` give angles `θ` and `2π - θ` about opposite axes.
pub fn log(e: &UnitQuaternion<f64>) -> Vector3<f64> {
    let v = e.imag();
    let n = v.norm();
    if n == 0.0 {
        return Vector3::zeros();
    }
    v * (2.0 * n.atan2(e.w) / n)
}

/// The unit quaternion of the rotation vector `y`: the inverse of [`log`].
///
/// # Formula
/// `exp(y) = (cos(|y|/2), sin(|y|/2) y / |y|)` (nalgebra's `UnitQuaternion::from_scaled_axis`).
pub fn exp(y: &Vector3<f64>) -> UnitQuaternion<f64> {
    UnitQuaternion::from_scaled_axis(*y)
}

/// `goal` or `-goal`, whichever is nearer to `reference`: the one with `w` of `reference ⊗ ḡoal` >= 0, that is a
/// non-negative 4-dot product, so that `log(reference ⊗ ḡoal)` has an angle of at most π.
pub(crate) fn closest_sign(
    goal: &UnitQuaternion<f64>,
    reference: &UnitQuaternion<f64>,
) -> UnitQuaternion<f64> {
    if goal.coords.dot(&reference.coords) < 0.0 {
        UnitQuaternion::new_unchecked(-goal.into_inner())
    } else {
        *goal
    }
}

/// The angle of the rotation between two orientations, in `[0, π]`, whatever their signs.
///
/// # Formula
/// `2 atan2(|v|, |w|)` with `(w, v) = a ⊗ b̄`.
pub fn angle_between(a: &UnitQuaternion<f64>, b: &UnitQuaternion<f64>) -> f64 {
    let e = a * b.conjugate();
    2.0 * e.imag().norm().atan2(e.w.abs())
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use super::*;

    #[test]
    fn log_inverts_exp_over_the_whole_range() {
        let axis = Vector3::new(0.3, -0.5, 0.8).normalize();
        for angle in [0.0, 1e-300, 1e-12, 1e-4, 0.5, 3.0, PI, 4.0, 6.0] {
            let y = axis * angle;
            let back = log(&exp(&y));
            assert!((back - y).norm() <= 1e-15 * (1.0 + angle), "angle {angle}: {back:?}");
        }
    }

    #[test]
    fn small_angles_keep_full_precision() {
        let y = Vector3::new(1e-9, -2e-9, 3e-9);
        assert!((log(&exp(&y)) - y).norm() < 1e-24);
    }

    #[test]
    fn the_closest_sign_never_takes_the_long_way() {
        let a = exp(&Vector3::new(0.2, 0.1, -0.3));
        let g = exp(&Vector3::new(-1.0, 2.0, 0.5));
        let minus_g = UnitQuaternion::new_unchecked(-g.into_inner());
        for goal in [g, minus_g] {
            let e = a * closest_sign(&goal, &a).conjugate();
            assert!(e.w >= 0.0 && log(&e).norm() <= PI);
            assert!((log(&e).norm() - angle_between(&a, &goal)).abs() < 1e-14);
        }
        assert!((angle_between(&a, &minus_g) - angle_between(&a, &g)).abs() < 1e-15);
    }

    #[test]
    fn wire_conversions_check_and_round_trip() {
        let q = exp(&Vector3::new(0.4, -0.7, 1.1));
        let back = from_xyzw("q", to_xyzw(&q)).unwrap();
        assert!((back.coords - q.coords).norm() < 1e-15);
        let e = from_xyzw("goal", [0.0, 0.0, 0.0, 0.0]).unwrap_err();
        assert_eq!(e.field, "goal");
        assert!(e.rule.contains("unit quaternion"), "{e}");
        assert!(from_xyzw("q", [f64::NAN, 0.0, 0.0, 1.0]).unwrap_err().rule.contains("finite"));
        assert!(from_xyzw("q", [0.0, 0.0, 0.0, 1.0 + 5e-7]).is_ok());
    }
}
