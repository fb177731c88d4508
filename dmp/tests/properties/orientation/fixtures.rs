//! Realistic pose demonstrations: a minimum-jerk rotation of 90° about a tilted axis over 2 s at 1 kHz, and one
//! whose axis changes while it turns.

use std::f64::consts::FRAC_PI_2;
use std::sync::LazyLock;

use dmp::orientation::quaternion::{angle_between, exp, to_xyzw};
use dmp::{
    LearnConfig, OrientationDemonstration, OrientationMotion, OrientationPrimitive, OrientationTrajectory,
    learn_orientation, rollout_orientation,
};
use nalgebra::{UnitQuaternion, Vector3};

/// The demonstrations' duration, seconds.
pub(crate) const DURATION: f64 = 2.0;

/// The output step, seconds (the demonstrations' sampling period too).
pub(crate) const DT: f64 = 1e-3;

/// `10 u³ - 15 u⁴ + 6 u⁵` on `[0, 1]`, constant outside.
pub(crate) fn min_jerk(u: f64) -> f64 {
    let u = u.clamp(0.0, 1.0);
    u * u * u * (10.0 + u * (-15.0 + 6.0 * u))
}

/// An orientation away from the identity, so that world and tool frames differ.
pub(crate) fn base() -> UnitQuaternion<f64> {
    exp(&Vector3::new(0.4, -0.7, 1.1))
}

/// The tilted axis of the single-axis demonstration.
pub(crate) fn tilted_axis() -> Vector3<f64> {
    Vector3::new(0.3, -0.5, 0.8).normalize()
}

/// 90° about [`tilted_axis`] (world frame), minimum jerk over [`DURATION`].
pub(crate) fn single_axis(t: f64) -> UnitQuaternion<f64> {
    exp(&(tilted_axis() * (FRAC_PI_2 * min_jerk(t / DURATION)))) * base()
}

/// 70° about the tilted axis over the whole demonstration, composed with 50° about another axis between 0.4 s
/// and 1.8 s: the axis of the motion turns as it goes.
pub(crate) fn changing_axis(t: f64) -> UnitQuaternion<f64> {
    let second = Vector3::new(1.0, 0.2, -0.1).normalize();
    exp(&(tilted_axis() * (70f64.to_radians() * min_jerk(t / DURATION))))
        * exp(&(second * (50f64.to_radians() * min_jerk((t - 0.4) / 1.4))))
        * base()
}

/// `0, 1 ms, ..., 2 s`.
pub(crate) fn times() -> Vec<f64> {
    (0..=(DURATION / DT).round() as usize).map(|k| k as f64 * DT).collect()
}

/// Samples `curve` at [`times`], `[x, y, z, w]`.
pub(crate) fn samples(curve: impl Fn(f64) -> UnitQuaternion<f64>) -> Vec<[f64; 4]> {
    times().iter().map(|&t| to_xyzw(&curve(t))).collect()
}

/// The demonstration of `curve`.
pub(crate) fn demo(curve: impl Fn(f64) -> UnitQuaternion<f64>) -> OrientationDemonstration {
    OrientationDemonstration::new(times(), samples(curve)).unwrap()
}

/// [`single_axis`] learned with the paper's settings (N = 50, K = 1050, alpha = 4).
pub(crate) static SINGLE: LazyLock<OrientationPrimitive> =
    LazyLock::new(|| learn_orientation(&demo(single_axis), &LearnConfig::paper()).unwrap());

/// [`changing_axis`] learned with the paper's settings.
pub(crate) static CHANGING: LazyLock<OrientationPrimitive> =
    LazyLock::new(|| learn_orientation(&demo(changing_axis), &LearnConfig::paper()).unwrap());

/// A motion of `tau` between two orientations.
pub(crate) fn motion(start: UnitQuaternion<f64>, goal: UnitQuaternion<f64>, tau: f64) -> OrientationMotion {
    OrientationMotion { start, goal, tau }
}

/// A new start and goal: the demonstration's, each turned by 30° to 40° about other axes.
pub(crate) fn new_motion(p: &OrientationPrimitive) -> OrientationMotion {
    let start = exp(&Vector3::new(0.5, 0.1, -0.2)) * p.start_orientation().unwrap();
    let goal = exp(&Vector3::new(-0.3, 0.6, 0.2)) * p.goal_orientation().unwrap();
    motion(start, goal, p.dmp.tau)
}

/// Rolls out for `duration` seconds at [`DT`].
pub(crate) fn run(p: &OrientationPrimitive, m: &OrientationMotion, duration: f64) -> OrientationTrajectory {
    rollout_orientation(p, m, DT, (duration / DT).round() as usize).unwrap()
}

/// The largest angle between rows of `a` and `b` taken at `k` and `stride * k`.
pub(crate) fn max_angle(a: &OrientationTrajectory, b: &OrientationTrajectory, stride: usize) -> f64 {
    (0..a.len().min(b.len().div_ceil(stride)))
        .map(|k| angle_between(&a.orientation(k), &b.orientation(stride * k)))
        .fold(0.0, f64::max)
}

/// The angle turned along a trajectory: the sum of the angles between consecutive rows.
pub(crate) fn travelled(tr: &OrientationTrajectory) -> f64 {
    (1..tr.len()).map(|k| angle_between(&tr.orientation(k), &tr.orientation(k - 1))).sum()
}
