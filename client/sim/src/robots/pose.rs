//! A pose robot's orientation in its report: how far it ended from its goal orientation, its angular speed,
//! acceleration and jerk as finite differences of the orientations it executed (what a robot's controller sees, as
//! the linear ones in `super::profile`), and its setpoints over the angular limits of its profile.
//!
//! # Angular finite differences
//! Between rows `k - 1` and `k`, `h` apart, the rotation `Δq = q_k q_(k-1)^*` (world frame, the sign taken with
//! `w >= 0`: the shorter way) turns by the angle `θ = 2 atan2(|v|, w)` about `v / |v|`, so `ω_k = θ v / (|v| h)`.
//! Then `α_k = (ω_k - ω_(k-1)) / h` and the jerk `(α_k - α_(k-1)) / h`, from rest before the first row, like the
//! linear differences. At 1 kHz and the Panda's 2.5 rad/s a step turns 2.5 mrad, far from the `π` where the shorter
//! way would be ambiguous.

use dmp::Limits;

use super::profile::{ROUNDING, over_rows};
use super::report::{PoseReport, RobotReport};
use super::robot::Executed;
use crate::error::SimError;

/// A pose robot reaches its goal orientation when its last orientation is within this angle of it, degrees (the
/// server's own goal tolerance is 0.057° by default).
pub(crate) const ORIENTATION_TOLERANCE_DEG: f64 = 0.5;

/// The peaks of the angular finite differences of `q` (4 per row at times `t`) and, per row, whether it is over
/// the angular limits of `limits` (by more than [`ROUNDING`]; 0 is no limit).
pub(crate) fn angular_differences(t: &[f64], q: &[f64], limits: &Limits) -> ([f64; 3], Vec<bool>) {
    let n = t.len().min(q.len() / 4);
    let (mut peaks, mut over) = ([0.0f64; 3], vec![false; n]);
    let (mut w_prev, mut a_prev) = ([0.0; 3], [0.0; 3]);
    let above = |value: f64, limit: f64| limit > 0.0 && value > limit * (1.0 + ROUNDING);
    for k in 1..n {
        let h = t[k] - t[k - 1];
        if h <= 0.0 {
            continue;
        }
        let w = rotation_vector(&q[4 * k..4 * k + 4], &q[4 * (k - 1)..4 * k]).map(|c| c / h);
        let a: [f64; 3] = std::array::from_fn(|i| (w[i] - w_prev[i]) / h);
        let j: [f64; 3] = std::array::from_fn(|i| (a[i] - a_prev[i]) / h);
        let s = [norm(&w), norm(&a), norm(&j)];
        for (p, v) in peaks.iter_mut().zip(s) {
            *p = p.max(v);
        }
        over[k] = above(s[0], limits.max_angular_speed)
            || above(s[1], limits.max_angular_acceleration)
            || above(s[2], limits.max_angular_jerk);
        (w_prev, a_prev) = (w, a);
    }
    (peaks, over)
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|c| c * c).sum::<f64>().sqrt()
}

/// `a b^*` of quaternions `[x, y, z, w]`.
fn times_conjugate(a: &[f64], b: &[f64]) -> [f64; 4] {
    let (bx, by, bz, bw) = (-b[0], -b[1], -b[2], b[3]);
    [
        a[3] * bx + a[0] * bw + a[1] * bz - a[2] * by,
        a[3] * by - a[0] * bz + a[1] * bw + a[2] * bx,
        a[3] * bz + a[0] * by - a[1] * bx + a[2] * bw,
        a[3] * bw - a[0] * bx - a[1] * by - a[2] * bz,
    ]
}

/// The rotation vector (axis times angle, world frame) that turns `from` into `to`, the shorter way.
fn rotation_vector(to: &[f64], from: &[f64]) -> [f64; 3] {
    let mut d = times_conjugate(to, from);
    if d[3] < 0.0 {
        d = d.map(|c| -c);
    }
    let s = norm(&d[..3]);
    if s < 1e-300 {
        return [0.0; 3];
    }
    let angle = 2.0 * s.atan2(d[3]);
    [d[0] / s * angle, d[1] / s * angle, d[2] / s * angle]
}

/// The angle between two orientations, degrees (q and -q are the same).
pub fn angle_deg(a: &[f64], b: &[f64]) -> f64 {
    norm(&rotation_vector(a, b)).to_degrees()
}

/// Adds the orientation figures of `exec` (a pose run) to `r`: the goal counts as reached only within
/// [`ORIENTATION_TOLERANCE_DEG`] of `goal`, and `limit_violations` counts the setpoints over the linear or the
/// angular limits of `profile` (each setpoint once). `body` names the shape `r.min_clearance_m` measured. A run
/// without orientations is left as it is.
pub(crate) fn add_pose(
    r: &mut RobotReport,
    exec: &Executed,
    goal: [f64; 4],
    profile: Option<&Limits>,
    body: &str,
) {
    let Some(o) = &exec.orientations else { return };
    let limits = profile.unwrap_or(&Limits::NONE);
    let (peaks, angular) = angular_differences(&exec.traj.t, &o.q, limits);
    let (_, linear) = over_rows(&exec.traj, limits, &exec.late_splices);
    let rows = o.q.len() / 4;
    let final_orientation_error_deg =
        if rows == 0 { f64::INFINITY } else { angle_deg(&o.q[4 * (rows - 1)..], &goal) };
    let max_turn_from_start_deg =
        (0..rows).map(|k| angle_deg(&o.q[4 * k..4 * k + 4], &o.q[..4])).fold(0.0, f64::max);
    let streamed = (0..o.omega.len() / 3).map(|k| norm(&o.omega[3 * k..3 * k + 3])).fold(0.0, f64::max);
    r.limit_violations = (0..linear.len().max(angular.len()))
        .filter(|&k| linear.get(k) == Some(&true) || angular.get(k) == Some(&true))
        .count() as u64;
    r.reached_goal &= final_orientation_error_deg <= ORIENTATION_TOLERANCE_DEG;
    r.pose = Some(PoseReport {
        final_orientation_error_deg,
        goal_orientation: goal,
        max_turn_from_start_deg,
        peak_angular_speed: peaks[0],
        peak_angular_acceleration: peaks[1],
        peak_angular_jerk: peaks[2],
        streamed_peak_angular_speed: streamed,
        angular_limit_violations: angular.iter().filter(|o| **o).count() as u64,
        body: body.into(),
        min_body_clearance_m: r.min_clearance_m.values().copied().fold(f64::INFINITY, f64::min),
    });
}

/// `[x, y, z, w]` of the rotation by `angle` (radians) about the unit `axis`.
pub(crate) fn about(axis: [f64; 3], angle: f64) -> [f64; 4] {
    let (s, c) = (angle / 2.0).sin_cos();
    [axis[0] * s, axis[1] * s, axis[2] * s, c]
}

/// The product `a b` of quaternions `[x, y, z, w]`.
pub(crate) fn mul(a: &[f64], b: &[f64]) -> [f64; 4] {
    times_conjugate(a, &[-b[0], -b[1], -b[2], b[3]])
}

/// The orientation a fraction `s` of the shorter way from `from` to `to` (spherical linear interpolation).
pub(crate) fn slerp(from: &[f64; 4], to: &[f64; 4], s: f64) -> [f64; 4] {
    let r = rotation_vector(to, from);
    let angle = norm(&r);
    if angle < 1e-300 {
        return *from;
    }
    mul(&about(r.map(|c| c / angle), s * angle), from)
}

/// The orientations of `o` as `[x, y, z, w]` rows (for the figures).
pub(crate) fn rows(q: &[f64]) -> Vec<[f64; 4]> {
    q.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect()
}

/// Samples of the surface of the superquadric `(semi, exponents)` (tool frame), for its outline in a figure.
pub(crate) fn outline_samples(semi: &[f64], exponents: &[f64]) -> Result<Vec<[f64; 3]>, SimError> {
    let plot = |e: dmp::DmpError| SimError::Plot(e.to_string());
    let shape =
        dmp::Shape::Superquadric(dmp::Superquadric::new(semi.to_vec(), exponents.to_vec()).map_err(plot)?);
    let tool = dmp::tool::Tool::new(shape, [0.0; 3], dmp::tool::ControlPoints::default()).map_err(plot)?;
    Ok(dmp::tool::surface_samples(&tool, 400).iter().map(|v| [v.x, v.y, v.z]).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn angular_differences_of_a_steady_turn_and_of_one_that_speeds_up() {
        // A turn about z at 2 rad/s, 1 kHz: 2 rad/s, and an acceleration of 2000 rad/s² at the first step only (from
        // rest), which the Panda's 25 rad/s² counts once; its jerk, over 12,500 rad/s³, twice.
        let dt = 1e-3;
        let t: Vec<f64> = (0..1001).map(|k| k as f64 * dt).collect();
        let q: Vec<f64> = t.iter().flat_map(|s| about([0.0, 0.0, 1.0], 2.0 * s)).collect();
        let (peaks, over) = angular_differences(&t, &q, &Limits::PANDA);
        assert!((peaks[0] - 2.0).abs() < 1e-9, "{peaks:?}");
        assert!((peaks[1] - 2000.0).abs() < 1e-6, "{peaks:?}");
        assert_eq!(over.iter().filter(|o| **o).count(), 2);
        // theta = t^3 about x: the jerk is 6 rad/s³ and the speed 3 t^2 (over 2.5 rad/s from t = 0.913 s).
        let q: Vec<f64> = t.iter().flat_map(|s| about([1.0, 0.0, 0.0], s.powi(3))).collect();
        let (peaks, over) = angular_differences(&t, &q, &Limits::PANDA);
        assert!((peaks[0] - 3.0).abs() < 1e-2, "{peaks:?}");
        assert!((peaks[2] - 6.0).abs() < 0.1, "{peaks:?}");
        let n = over.iter().filter(|o| **o).count();
        assert!((86..=89).contains(&n), "{n}");
        // q and -q are the same orientation: a sign flip is no turn.
        let flipped: Vec<f64> = q
            .chunks(4)
            .enumerate()
            .flat_map(|(k, c)| c.iter().map(move |v| if k % 2 == 0 { *v } else { -v }))
            .collect();
        let (same, _) = angular_differences(&t, &flipped, &Limits::PANDA);
        assert!((same[0] - peaks[0]).abs() < 1e-9);
    }

    #[test]
    fn slerp_goes_the_shorter_way() {
        let a = about([0.0, 0.0, 1.0], 0.2);
        let b = about([0.0, 0.0, 1.0], 1.2);
        let m = slerp(&a, &b, 0.25);
        assert!(angle_deg(&m, &about([0.0, 0.0, 1.0], 0.45)) < 1e-9);
        // -b is b: still a quarter of the 1 rad turn.
        assert!(angle_deg(&slerp(&a, &b.map(|c| -c), 0.25), &m) < 1e-9);
        assert!(angle_deg(&mul(&b, &a), &about([0.0, 0.0, 1.0], 1.4)) < 1e-9);
    }

    #[test]
    fn angle_between_orientations() {
        let a = about([0.0, 0.0, 1.0], 0.3);
        let b = about([0.0, 0.0, 1.0], -0.2);
        assert!((angle_deg(&a, &b) - 0.5f64.to_degrees()).abs() < 1e-9);
        assert!(angle_deg(&a, &a.map(|c| -c)).abs() < 1e-6);
    }
}
