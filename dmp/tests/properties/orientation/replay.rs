//! Unit outputs, the goal reached, the demonstration replayed, time scaling, random starts and goals, save and
//! load.

use dmp::orientation::quaternion::{angle_between, exp};
use dmp::{OrientationMotion, OrientationPrimitive, rollout_orientation};
use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use proptest::prelude::*;

use super::fixtures::{
    CHANGING, DT, SINGLE, changing_axis, max_angle, motion, new_motion, run, single_axis, times,
};
use crate::fixtures::config;

/// Both primitives with their demonstrations' own motions and with new starts and goals.
fn cases() -> Vec<(&'static str, &'static OrientationPrimitive, OrientationMotion)> {
    let mut out = Vec::new();
    for (name, p) in [("single axis", &*SINGLE), ("changing axis", &*CHANGING)] {
        out.push((name, p, OrientationMotion::of(p).unwrap()));
        out.push((name, p, new_motion(p)));
    }
    out
}

#[test]
fn every_output_quaternion_has_norm_one() {
    for (name, p, m) in cases() {
        let tr = run(p, &m, 2.5 * m.tau);
        let worst = tr.q.iter().map(|q| (Quaternion::from(*q).norm() - 1.0).abs()).fold(0.0, f64::max);
        eprintln!("{name}: largest |‖q‖ - 1| = {worst:e}");
        assert!(worst <= 1e-12, "{name}: {worst:e}");
    }
}

#[test]
fn the_goal_is_reached() {
    for (name, p, m) in cases() {
        let tr = run(p, &m, 2.5 * m.tau);
        let last = tr.len() - 1;
        let miss = angle_between(&tr.orientation(last), &m.goal).to_degrees();
        let spin = tr.angular_velocity(last).norm();
        eprintln!("{name}: {miss:.2e}° from the goal at {:.1} s, |ω| = {spin:.1e} rad/s", tr.t[last]);
        assert!(miss <= 0.1, "{name}: {miss}°");
        assert!(spin <= 1e-2, "{name}: still turning at {spin} rad/s");
    }
}

#[test]
fn the_demonstration_is_replayed() {
    for (name, p, curve) in [
        ("single axis", &*SINGLE, single_axis as fn(f64) -> UnitQuaternion<f64>),
        ("changing axis", &*CHANGING, changing_axis),
    ] {
        let tr = run(p, &OrientationMotion::of(p).unwrap(), p.dmp.tau);
        let t = times();
        assert_eq!(tr.len(), t.len());
        let worst = t
            .iter()
            .enumerate()
            .map(|(k, &tk)| angle_between(&tr.orientation(k), &curve(tk)).to_degrees())
            .fold(0.0, f64::max);
        eprintln!("{name}: largest angle to the demonstration {worst:.4}°");
        assert!(worst <= 1.0, "{name}: {worst}°");
    }
}

#[test]
fn twice_tau_is_the_same_path_at_half_speed() {
    for (name, p, m) in cases() {
        let fast = run(p, &m, 2.0 * m.tau);
        let slow = run(p, &OrientationMotion { tau: 2.0 * m.tau, ..m.clone() }, 4.0 * m.tau);
        assert_eq!(slow.len(), 2 * fast.len() - 1);
        // Row 2k of the slow run has the phase of row k of the fast one.
        let path = max_angle(&fast, &slow, 2);
        let (mut speed, mut accel, mut omega_max, mut omega_dot_max) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        for k in 0..fast.len() {
            let (w, wd) = (fast.angular_velocity(k), fast.angular_acceleration(k));
            speed = speed.max((slow.angular_velocity(2 * k) * 2.0 - w).norm());
            accel = accel.max((slow.angular_acceleration(2 * k) * 4.0 - wd).norm());
            omega_max = omega_max.max(w.norm());
            omega_dot_max = omega_dot_max.max(wd.norm());
        }
        eprintln!("{name}: path {path:.1e} rad, 2 ω_slow - ω {speed:.1e}, 4 ω̇_slow - ω̇ {accel:.1e}");
        assert!(path <= 1e-7, "{name}: {path}");
        assert!(speed <= 1e-6 * omega_max && accel <= 1e-5 * omega_dot_max, "{name}: {speed} {accel}");
    }
}

#[test]
fn a_saved_primitive_replays_identically() {
    let p = &*CHANGING;
    let text = serde_json::to_string(p).unwrap();
    let back: OrientationPrimitive = serde_json::from_str(&text).unwrap();
    back.validate().unwrap();
    let m = new_motion(p);
    assert_eq!(run(p, &m, 1.0), run(&back, &m, 1.0));
    let mut flat: serde_json::Value = serde_json::from_str(&text).unwrap();
    flat["dmp"]["dim"] = 2.into();
    let bad: OrientationPrimitive = serde_json::from_value(flat).unwrap();
    assert!(bad.validate().is_err());
}

fn unit_quaternion() -> impl Strategy<Value = UnitQuaternion<f64>> {
    proptest::array::uniform4(-1.0..1.0f64)
        .prop_filter("not too short to normalise", |v| v.iter().map(|x| x * x).sum::<f64>() > 0.01)
        .prop_map(|[x, y, z, w]| UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z)))
}

proptest! {
    #![proptest_config(config(12))]

    /// Any start and goal, up to 180° apart, in either sign: unit, finite, converging outputs.
    #[test]
    fn any_start_and_goal_is_reached(start in unit_quaternion(), goal in unit_quaternion(), tau in 0.5..4.0f64) {
        let p = &*CHANGING;
        let m = motion(start, goal, tau);
        let tr = rollout_orientation(p, &m, DT, (2.5 * tau / DT).round() as usize).unwrap();
        prop_assert!(tr.q.iter().flatten().chain(tr.omega.iter().flatten()).all(|v| v.is_finite()));
        for q in &tr.q {
            prop_assert!((Quaternion::from(*q).norm() - 1.0).abs() <= 1e-12);
        }
        prop_assert!(angle_between(&tr.orientation(0), &start) <= 1e-12);
        let miss = angle_between(&tr.orientation(tr.len() - 1), &goal).to_degrees();
        prop_assert!(miss <= 0.1, "{} deg from the goal", miss);
    }
}

#[test]
fn the_output_starts_at_the_start_as_given() {
    let p = &*SINGLE;
    let start = UnitQuaternion::new_unchecked(-exp(&Vector3::new(0.1, 0.2, 0.3)).into_inner());
    let tr = run(p, &motion(start, p.goal_orientation().unwrap(), p.dmp.tau), 0.01);
    let q0 = tr.orientation(0);
    assert!((q0.coords - start.coords).norm() < 1e-15, "{q0:?} vs {start:?}");
    assert!(tr.angular_velocity(0).norm() == 0.0);
}

/// The largest amount by which a distance rises above its running minimum once it has fallen to half its first
/// value: 0 for a monotone approach, the size of the overshoot or oscillation otherwise.
fn rise_after_halfway(distances: &[f64]) -> f64 {
    let half = distances.iter().position(|d| *d <= 0.5 * distances[0]).expect("never halfway");
    let (mut low, mut rise) = (f64::INFINITY, 0.0f64);
    for d in &distances[half..] {
        low = low.min(*d);
        rise = rise.max(d - low);
    }
    rise
}

#[test]
fn a_new_goal_is_approached_without_oscillation() {
    for (name, p) in [("single axis", &*SINGLE), ("changing axis", &*CHANGING)] {
        for (what, m) in [("own goal", OrientationMotion::of(p).unwrap()), ("new goal", new_motion(p))] {
            let tr = run(p, &m, 2.5 * m.tau);
            let d: Vec<f64> = (0..tr.len()).map(|k| angle_between(&tr.orientation(k), &m.goal)).collect();
            let rise = rise_after_halfway(&d).to_degrees();
            eprintln!("{name}, {what}: past halfway, the distance to the goal rises by at most {rise:.1e}°");
            assert!(rise <= 0.01, "{name}, {what}: {rise}°");
        }
    }
}
