//! Each robot's limit profile: put in its robot record on the server before it moves (so every run of the robot
//! keeps it), and checked on what it executed: the finite differences of the setpoints it kept, at their own times,
//! against the profile.

use dmp::{Limits, Trajectory};
use dmp_client::grpc::DmpClient;
use dmp_proto::v1;
use serde::Serialize;

use super::within;
use crate::error::SimError;

/// Relative slack of the check: the server keeps the limits on its own finite differences, which the robot's
/// (of the same setpoints) match to rounding.
pub(crate) const ROUNDING: f64 = 1e-6;

/// Stores `limits` as the limits of `robot`'s record (its footprint and tool left unset: the simulations send
/// their footprints with each request), and its safety distance: the server's default (`None`), or `Some(m)`
/// (negative: none).
pub(crate) async fn put_profile(
    client: &DmpClient,
    robot: &str,
    limits: &Limits,
    margin: Option<f64>,
) -> Result<(), SimError> {
    let record = v1::RobotRecord {
        robot_id: robot.into(),
        limits: Some(dmp_proto::limits::limits_to_proto(limits)),
        margin: margin.unwrap_or(0.0),
        ..Default::default()
    };
    within("put robot", client.put_robot(record)).await??;
    Ok(())
}

/// The linear peaks of a run's setpoints as finite differences.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Peaks {
    /// Largest `|x_k - x_(k-1)| / h`, m/s.
    pub peak_speed: f64,
    /// Largest second difference, m/s².
    pub peak_acceleration: f64,
    /// Largest third difference, m/s³.
    pub peak_jerk: f64,
}

/// Backward differences of the positions of `traj` (at rest before its first setpoint), each over its own time
/// step: their peaks, and how many setpoints have a speed, acceleration or jerk over `limits` (by more than
/// [`ROUNDING`]; a field 0 is no limit). The rows whose differences reach back across one of `late_splices` (a
/// switch to a segment that arrived late, [`super::robot::Executed::late_splices`]) are left out: they measure the
/// lateness, not the stream.
pub(crate) fn finite_differences(traj: &Trajectory, limits: &Limits, late_splices: &[usize]) -> (Peaks, u64) {
    let (peaks, over) = over_rows(traj, limits, late_splices);
    (peaks, over.iter().filter(|o| **o).count() as u64)
}

/// [`finite_differences`] with, per setpoint, whether it is over the linear limits.
pub(crate) fn over_rows(traj: &Trajectory, limits: &Limits, late_splices: &[usize]) -> (Peaks, Vec<bool>) {
    let d = traj.dim();
    let (mut k, mut violations) = (Peaks::default(), vec![false; traj.len()]);
    let (mut v_prev, mut a_prev) = (vec![0.0; d], vec![0.0; d]);
    let over = |value: f64, limit: f64| limit > 0.0 && value > limit * (1.0 + ROUNDING);
    for i in 1..traj.len() {
        let h = traj.t[i] - traj.t[i - 1];
        if h <= 0.0 {
            continue;
        }
        let v: Vec<f64> = (0..d).map(|j| (traj.x[i * d + j] - traj.x[(i - 1) * d + j]) / h).collect();
        let a: Vec<f64> = (0..d).map(|j| (v[j] - v_prev[j]) / h).collect();
        let jerk: Vec<f64> = (0..d).map(|j| (a[j] - a_prev[j]) / h).collect();
        let norm = |x: &[f64]| x.iter().map(|y| y * y).sum::<f64>().sqrt();
        let (sv, sa, sj) = (norm(&v), norm(&a), norm(&jerk));
        // The jerk at row `i` differences rows `i - 3 ..= i`.
        if late_splices.iter().any(|&s| s <= i && i < s + 3) {
            (v_prev, a_prev) = (v, a);
            continue;
        }
        k.peak_speed = k.peak_speed.max(sv);
        k.peak_acceleration = k.peak_acceleration.max(sa);
        k.peak_jerk = k.peak_jerk.max(sj);
        violations[i] =
            over(sv, limits.max_speed) || over(sa, limits.max_acceleration) || over(sj, limits.max_jerk);
        (v_prev, a_prev) = (v, a);
    }
    (k, violations)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run of `x(t)` sampled every `dt` for `n` points, in 1-D.
    fn sampled(x: impl Fn(f64) -> f64, dt: f64, n: usize) -> Trajectory {
        let mut t = Trajectory::with_capacity(1, n);
        for i in 0..n {
            let s = i as f64 * dt;
            t.push(s, &[x(s)], &[0.0], &[0.0]);
        }
        t
    }

    #[test]
    fn peaks_are_the_finite_differences_and_setpoints_over_the_profile_are_counted() {
        // x = t^3: jerk 6, acceleration 6 t, speed 3 t^2 (the differences lag by about a step).
        let dt = 1e-3;
        let traj = sampled(|t| t.powi(3), dt, 1001);
        let (none, violations) = finite_differences(&traj, &Limits::NONE, &[]);
        assert_eq!(violations, 0);
        assert!((none.peak_speed - 3.0).abs() < 1e-2, "{none:?}");
        assert!((none.peak_acceleration - 6.0).abs() < 2e-2, "{none:?}");
        let slow = Limits { max_speed: 0.75, ..Limits::NONE };
        let (_, over) = finite_differences(&traj, &slow, &[]);
        // Speed 3 t^2 > 0.75 from t = 0.5 s on: about half the points.
        assert!((499..=502).contains(&over), "{over}");
        // Jerk 6 everywhere but at the first differences (from rest): over 1 from the third point on.
        let tight = Limits { max_jerk: 1.0, ..Limits::NONE };
        let (_, over) = finite_differences(&traj, &tight, &[]);
        assert!((998..=1000).contains(&over), "{over}");
    }
}
