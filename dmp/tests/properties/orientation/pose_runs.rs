//! Pose runs through the one execution engine: a pose primitive learned from positions and orientations replays
//! with unit outputs, reaches its goal orientation, follows the demonstration, scales with `tau`, ignores the sign
//! of its goal, gives angular velocities that are the derivative of its orientations, and keeps its positions
//! exactly as a position-only run of the same primitive would.

use dmp::avoidance::DynamicVolumetric;
use dmp::execution::CellMateAvoidance;
use dmp::orientation::pose::{PoseMotion, learn_pose, pose_motion};
use dmp::orientation::quaternion::{angle_between, exp, from_xyzw, log, to_xyzw};
use dmp::{
    Avoidance, Demonstration, Execution, LearnConfig, Method, Motion, Outcome, Primitive, Scene, Stepping,
};
use nalgebra::{UnitQuaternion, Vector3};

use super::fixtures::{DT, changing_axis, demo, min_jerk, times};

/// A 0.3 m minimum-jerk reach along a tilted line, sampled with the orientations of [`changing_axis`].
fn positions() -> Demonstration {
    let rows = times()
        .into_iter()
        .map(|t| (0..3).map(|i| [0.3, 0.1, -0.2][i] * min_jerk(t / 2.0) + 0.1 * i as f64).collect());
    Demonstration::new(times(), rows.collect()).unwrap()
}

fn pose_primitive() -> Primitive {
    learn_pose(&positions(), &demo(changing_axis), &LearnConfig::paper()).unwrap()
}

struct Run {
    outcome: Outcome,
    x: Vec<f64>,
    q: Vec<UnitQuaternion<f64>>,
    omega: Vec<Vector3<f64>>,
    omega_dot: Vec<Vector3<f64>>,
}

fn execution(p: &Primitive, m: &PoseMotion, scene: Scene) -> Execution {
    let mut e =
        Execution::new(p.clone(), m.motion.clone(), scene, CellMateAvoidance::NONE, Stepping::rk4(DT), 0)
            .unwrap();
    e.set_orientation_chart(m.chart).unwrap();
    e
}

/// Advances 100 points at a time for at most `seconds`, or to the end of the run.
fn run_out(e: &mut Execution, seconds: f64) -> Run {
    let mut r = Run { outcome: Outcome::Running, x: vec![], q: vec![], omega: vec![], omega_dot: vec![] };
    for _ in 0..(seconds / (100.0 * DT)).round() as usize {
        let s = e.advance(100).unwrap();
        r.x.extend_from_slice(&s.x);
        let o = &s.orientation;
        r.q.extend(
            o.q.chunks_exact(4)
                .map(|q| UnitQuaternion::new_unchecked(nalgebra::Quaternion::new(q[3], q[0], q[1], q[2]))),
        );
        r.omega.extend(o.omega.chunks_exact(3).map(Vector3::from_column_slice));
        r.omega_dot.extend(o.omega_dot.chunks_exact(3).map(Vector3::from_column_slice));
        r.outcome = s.outcome;
        if s.outcome.is_final() {
            break;
        }
    }
    r
}

fn own_motion(p: &Primitive, tau: f64) -> PoseMotion {
    let position = Motion { start: p.start.clone(), goal: p.goal.clone(), tau };
    pose_motion(p, position, None, None).unwrap()
}

#[test]
fn every_orientation_is_a_unit_quaternion_and_the_goal_is_reached() {
    let p = pose_primitive();
    let goal = exp(&Vector3::new(-0.3, 0.6, 0.2)) * changing_axis(2.0);
    let start = exp(&Vector3::new(0.5, 0.1, -0.2)) * changing_axis(0.0);
    let position = Motion { start: p.start.clone(), goal: p.goal.clone(), tau: 2.0 };
    let m = pose_motion(&p, position, Some(to_xyzw(&start)), Some(to_xyzw(&goal))).unwrap();
    let r = run_out(&mut execution(&p, &m, Scene::empty()), 8.0);
    assert_eq!(r.outcome, Outcome::GoalReached);
    for q in &r.q {
        assert!((q.coords.norm() - 1.0).abs() <= 1e-12, "norm {}", q.coords.norm());
    }
    assert!(angle_between(&r.q[0], &start) < 1e-12, "starts at the given start");
    let last = r.q.last().unwrap();
    assert!(angle_between(last, &goal).to_degrees() <= 0.1, "{}°", angle_between(last, &goal).to_degrees());
}

#[test]
fn the_demonstration_is_replayed_and_tau_scales_time() {
    let p = pose_primitive();
    let r = run_out(&mut execution(&p, &own_motion(&p, 2.0), Scene::empty()), 2.0);
    let worst =
        (0..r.q.len()).map(|k| angle_between(&r.q[k], &changing_axis(k as f64 * DT))).fold(0.0, f64::max);
    assert!(worst.to_degrees() < 1.0, "replay within {}° of the demonstration", worst.to_degrees());
    let slow = run_out(&mut execution(&p, &own_motion(&p, 4.0), Scene::empty()), 4.0);
    let worst = (0..r.q.len()).map(|k| angle_between(&r.q[k], &slow.q[2 * k])).fold(0.0, f64::max);
    assert!(worst.to_degrees() < 0.05, "tau = 4 s is the same motion twice as slow: {}°", worst.to_degrees());
}

#[test]
fn the_sign_of_the_goal_does_not_matter_and_no_run_turns_the_long_way() {
    let p = pose_primitive();
    let start = changing_axis(0.0);
    // 170° away: the short way is 170°, the long one 190°.
    let goal = exp(&(Vector3::new(0.2, 1.0, -0.4).normalize() * 170f64.to_radians())) * start;
    let minus = UnitQuaternion::new_unchecked(-goal.into_inner());
    let runs: Vec<Run> = [goal, minus]
        .iter()
        .map(|g| {
            let position = Motion { start: p.start.clone(), goal: p.goal.clone(), tau: 2.0 };
            let m = pose_motion(&p, position, Some(to_xyzw(&start)), Some(to_xyzw(g))).unwrap();
            run_out(&mut execution(&p, &m, Scene::empty()), 3.0)
        })
        .collect();
    for (a, b) in runs[0].q.iter().zip(&runs[1].q) {
        assert!(angle_between(a, b) < 1e-12);
    }
    let farthest = runs[0].q.iter().map(|q| angle_between(q, &start)).fold(0.0, f64::max);
    assert!(farthest.to_degrees() < 175.0, "turned {}° from the start", farthest.to_degrees());
}

#[test]
fn angular_velocity_and_acceleration_are_the_derivatives_of_the_orientations() {
    let p = pose_primitive();
    let r = run_out(&mut execution(&p, &own_motion(&p, 2.0), Scene::empty()), 2.5);
    let peak = |v: &[Vector3<f64>]| v.iter().map(|w| w.norm()).fold(0.0, f64::max);
    let (omega, omega_dot) = (peak(&r.omega), peak(&r.omega_dot));
    assert!(omega > 0.5 && omega_dot > 1.0, "the run hardly turns");
    for k in 1..r.q.len() - 1 {
        // Central differences, O(dt²): ω from the rotation between neighbours, ω̇ from the neighbours' ω (the
        // same bounds as the orientation run's own test, `derivatives.rs`).
        let fd = log(&(r.q[k + 1] * r.q[k - 1].conjugate())) / (2.0 * DT);
        assert!((fd - r.omega[k]).norm() <= 1e-4 * omega, "ω at {k}: {fd} vs {}", r.omega[k]);
        let fd_dot = (r.omega[k + 1] - r.omega[k - 1]) / (2.0 * DT);
        assert!(
            (fd_dot - r.omega_dot[k]).norm() <= 1e-2 * omega_dot,
            "ω̇ at {k}: {fd_dot} vs {}",
            r.omega_dot[k]
        );
    }
}

#[test]
fn positions_are_those_of_a_position_run_even_among_obstacles() {
    let p = pose_primitive();
    let obstacle = crate::fixtures::ellipsoid("ball", &[0.25, 0.18, 0.05], &[0.04, 0.04, 0.04]);
    let method = Method::DynamicVolumetric(DynamicVolumetric { lambda: 10.0, beta: 2.0, eta: 1.0 });
    let scene = || Scene::with_obstacles(vec![obstacle.clone()], Avoidance::new(method), 0);
    let pose = run_out(&mut execution(&p, &own_motion(&p, 2.0), scene()), 2.0);
    let mut position_only = p.clone();
    position_only.orientation = None;
    position_only.dim = 3;
    for v in [&mut position_only.k, &mut position_only.d, &mut position_only.start, &mut position_only.goal] {
        v.truncate(3);
    }
    position_only.weights.truncate(3);
    let motion = Motion { start: position_only.start.clone(), goal: position_only.goal.clone(), tau: 2.0 };
    let mut e = Execution::new(position_only, motion, scene(), CellMateAvoidance::NONE, Stepping::rk4(DT), 0)
        .unwrap();
    let plain = run_out(&mut e, 2.0);
    assert!(plain.q.is_empty(), "a position run has no orientations");
    let pose_positions: Vec<f64> = pose.x.chunks_exact(6).flat_map(|r| r[..3].to_vec()).collect();
    assert_eq!(pose_positions, plain.x, "bit for bit");
}

#[test]
fn a_new_goal_orientation_mid_run_is_reached() {
    let p = pose_primitive();
    let mut e = execution(&p, &own_motion(&p, 2.0), Scene::empty());
    run_out(&mut e, 0.8);
    let goal = exp(&Vector3::new(0.0, 0.0, 0.5)) * changing_axis(2.0);
    e.set_pose_goal(None, Some(to_xyzw(&goal))).unwrap();
    let r = run_out(&mut e, 6.0);
    assert_eq!(r.outcome, Outcome::GoalReached);
    assert!(angle_between(r.q.last().unwrap(), &goal).to_degrees() <= 0.1);
    let e2 = e.set_pose_goal(None, Some([0.0, 0.0, 0.0, 2.0])).unwrap_err();
    assert_eq!(e2.field, "goal_orientation");
    assert_eq!(e.set_pose_goal(Some(vec![0.0; 2]), None).unwrap_err().field, "goal");
}

#[test]
fn pose_primitives_refuse_what_they_cannot_do() {
    let p = pose_primitive();
    let bad = from_xyzw("q", [0.0, 0.0, 0.0, 1.0]).map(|_| [0.0, 0.0, 0.0, 3.0]).unwrap();
    let position = Motion { start: p.start.clone(), goal: p.goal.clone(), tau: 2.0 };
    assert_eq!(pose_motion(&p, position.clone(), Some(bad), None).unwrap_err().field, "start_orientation");
    let mut plain = p.clone();
    plain.orientation = None;
    assert_eq!(pose_motion(&plain, position, None, None).unwrap_err().field, "goal_orientation");
    let short = Demonstration::new(times()[..10].to_vec(), positions().positions()[..10].to_vec()).unwrap();
    let err = learn_pose(&short, &demo(changing_axis), &LearnConfig::paper()).unwrap_err();
    assert!(err.to_string().contains("demonstration.orientations"), "{err}");
}
