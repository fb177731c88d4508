//! Goal filtering, obstacle blending and limits under the run's changes: rollbacks, pause and resume, `tau`
//! changes and a second goal change while the first is filtered.

use super::tests::alone;
use super::*;
use crate::Obstacle;
use crate::avoidance::Method;
use crate::avoidance::StaticVolumetric;
use crate::isopotential::{Shape, Superquadric};

/// A 2-D straight reach from the origin to (1, 0.5) in 1 s, alone, at `stepping`.
fn reach(stepping: Stepping, scene: Scene) -> Execution {
    let p =
        Primitive::straight_line(20, 4.0, vec![1000.0; 2], None, 1.0, vec![0.0; 2], vec![1.0, 0.5]).unwrap();
    alone(&p, scene, stepping, 2000)
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// The largest change of the acceleration between consecutive points of `xdd` (2-D), per output step.
fn largest_acc_step(xdd: &[f64]) -> f64 {
    xdd.chunks(2)
        .zip(xdd.chunks(2).skip(1))
        .map(|(a, b)| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt())
        .fold(0.0, f64::max)
}

/// Advances `n` points and returns the accelerations of the last point before and of the whole stretch.
fn acc_across_change(e: &mut Execution, change: impl FnOnce(&mut Execution)) -> f64 {
    let before = e.advance(10).unwrap();
    change(e);
    let after = e.advance(10).unwrap();
    let mut xdd = before.xdd[18..].to_vec();
    xdd.extend_from_slice(&after.xdd);
    largest_acc_step(&xdd)
}

#[test]
fn a_filtered_goal_change_keeps_the_acceleration_continuous_and_a_step_does_not() {
    // The largest change of the acceleration from one point to the next across two goal changes (the second while
    // the first is filtered), at output step `dt`.
    let worst = |alpha: f64, dt: f64| {
        let mut e = reach(Stepping::rk4(dt), Scene::empty());
        e.set_goal_filter(alpha).unwrap();
        e.advance((0.3 / dt).round() as usize).unwrap();
        let first = acc_across_change(&mut e, |e| e.set_goal(vec![0.2, 0.9]).unwrap());
        e.advance((0.03 / dt).round() as usize).unwrap();
        let second = acc_across_change(&mut e, |e| e.set_goal(vec![0.6, -0.2]).unwrap());
        let mut last = Stretch::default();
        for _ in 0..2000 {
            last = e.advance(10).unwrap();
            if last.outcome.is_final() {
                break;
            }
        }
        assert_eq!(last.outcome, Outcome::GoalReached, "alpha {alpha}");
        first.max(second)
    };
    let alpha = crate::integrate::goal_filter::DEFAULT_GOAL_ALPHA;
    let (step, step_fine) = (worst(0.0, 1e-3), worst(0.0, 5e-4));
    let (filtered, filtered_fine) = (worst(alpha, 1e-3), worst(alpha, 5e-4));
    // A step of the goal is a step of the acceleration, whatever the output step; filtered, the acceleration is
    // continuous: its change from one point to the next halves with the step.
    assert!(step > 100.0 && step_fine > 0.9 * step, "{step} {step_fine}");
    assert!(filtered < step / 20.0, "{filtered} against {step}");
    assert!(filtered_fine < 0.6 * filtered, "{filtered_fine} against {filtered}");
    assert!(reach(Stepping::rk4(1e-3), Scene::empty()).set_goal_filter(-1.0).is_err());
}

#[test]
fn a_rollback_while_filtering_recomputes_the_same_points_and_restores_the_filter() {
    for stepping in [Stepping::rk4(1e-3), Stepping { dt: 1e-3, step_points: 30, tolerance: Some(3e-6) }] {
        let mut e = reach(stepping, Scene::empty());
        e.advance(400).unwrap();
        e.set_goal(vec![0.2, 0.9]).unwrap();
        let kept = e.advance(50).unwrap();
        let first = e.advance(50).unwrap();
        // Back to a point after the change: the same points.
        assert_eq!(e.rollback_to(0.45), 0.45);
        let again = e.advance(50).unwrap();
        let worst = first.x.iter().zip(&again.x).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        if stepping.is_coarse() {
            assert!(worst < 1e-6, "{worst}");
        } else {
            assert_eq!(bits(&first.x), bits(&again.x));
        }
        // A second change at 0.5, then back before it: the filter goes on from where it was at 0.45.
        let mut g45 = [0.0; 2];
        e.filtered_goal_at(0.45, &mut g45);
        e.set_goal(vec![0.6, -0.2]).unwrap();
        e.advance(20).unwrap();
        assert_eq!(e.rollback_to(0.45), 0.45);
        let mut g = [0.0; 2];
        e.filtered_goal_at(0.45, &mut g);
        assert!((g[0] - g45[0]).abs() < 1e-12 && (g[1] - g45[1]).abs() < 1e-12, "{g:?} {g45:?}");
        let redo = e.advance(50).unwrap();
        // No jump where the recomputed points join the kept ones.
        let join = largest_acc_step(&[&kept.xdd[98..], &redo.xdd[..2]].concat());
        assert!(join <= 1.5 * largest_acc_step(&redo.xdd), "{stepping:?}: {join}");
    }
}

#[test]
fn the_filter_survives_pause_resume_and_tau_changes() {
    let mut e = reach(Stepping::rk4(1e-3), Scene::empty());
    e.advance(300).unwrap();
    e.set_goal(vec![0.2, 0.9]).unwrap();
    e.advance(40).unwrap();
    // A tau change while filtering: the filtered goal is continuous through it.
    let mut before = [0.0; 2];
    e.filtered_goal_at(e.time(), &mut before);
    e.set_tau(1.5).unwrap();
    let mut after = [0.0; 2];
    e.filtered_goal_at(e.time(), &mut after);
    assert!((before[0] - after[0]).abs() < 1e-12 && (before[1] - after[1]).abs() < 1e-12);
    e.advance(40).unwrap();
    // Paused, the filtered goal stays where it is; resumed, it goes on from there.
    e.set_holding(true);
    let mut held = [0.0; 2];
    e.filtered_goal_at(e.time(), &mut held);
    e.advance(200).unwrap();
    let mut still = [0.0; 2];
    e.filtered_goal_at(e.time(), &mut still);
    assert_eq!(held, still);
    e.set_holding(false);
    let mut last = Stretch::default();
    for _ in 0..800 {
        last = e.advance(10).unwrap();
        if last.outcome.is_final() {
            break;
        }
    }
    assert_eq!(last.outcome, Outcome::GoalReached);
}

#[test]
fn an_obstacle_that_appears_is_blended_in_without_a_jump() {
    let ball = || {
        let shape = Shape::Superquadric(Superquadric::new(vec![0.1, 0.1], vec![1.0, 1.0]).unwrap());
        Obstacle::new("ball", shape, vec![0.55, 0.3], None, None).unwrap()
    };
    let avoid = Avoidance::new(Method::StaticVolumetric(StaticVolumetric { a: 0.1, eta: 1.0 }));
    let mut worst = [0.0; 2];
    for (i, blend) in [0.0, DEFAULT_OBSTACLE_BLEND].into_iter().enumerate() {
        let mut e = reach(Stepping::rk4(1e-3), Scene::with_obstacles(Vec::new(), avoid, 0));
        e.set_obstacle_blend(blend).unwrap();
        e.advance(300).unwrap();
        worst[i] = acc_across_change(&mut e, |e| e.set_obstacles([(&ball(), 0.0)]).unwrap());
        let rest = e.advance(200).unwrap();
        worst[i] = worst[i].max(largest_acc_step(&rest.xdd));
        assert!(rest.contacts.is_empty());
    }
    assert!(worst[0] > 10.0 * worst[1], "blending smooths the change: {worst:?}");
    assert!(reach(Stepping::rk4(1e-3), Scene::empty()).set_obstacle_blend(f64::NAN).is_err());
}

/// Peak speed, acceleration and jerk of dimensions `dims` of points `x` (`dim` each) as backward differences.
fn peaks(x: &[f64], dim: usize, dims: std::ops::Range<usize>, dt: f64) -> [f64; 3] {
    let n = x.len() / dim;
    let p = |k: usize, i: usize| x[k * dim + i];
    let mut peak = [0.0f64; 3];
    for k in 3..n {
        let norm = |f: &dyn Fn(usize) -> f64| dims.clone().map(|i| f(i).powi(2)).sum::<f64>().sqrt();
        let v = norm(&|i| (p(k, i) - p(k - 1, i)) / dt);
        let a = norm(&|i| (p(k, i) - 2.0 * p(k - 1, i) + p(k - 2, i)) / (dt * dt));
        let j = norm(&|i| (p(k, i) - 3.0 * p(k - 1, i) + 3.0 * p(k - 2, i) - p(k - 3, i)) / (dt * dt * dt));
        for (m, q) in peak.iter_mut().zip([v, a, j]) {
            *m = m.max(q);
        }
    }
    peak
}

#[test]
fn a_pose_run_keeps_the_angular_limits_on_its_rotation_vector() {
    let start = vec![0.3, 0.0, 0.4, 0.0, 0.0, 0.0];
    let goal = vec![0.5, 0.1, 0.4, 0.0, 0.0, 1.0];
    let p = Primitive::straight_line(20, 4.0, vec![1000.0; 6], None, 0.5, start, goal).unwrap();
    let mut e = alone(&p, Scene::empty(), Stepping::rk4(1e-3), 10);
    assert!(e.set_limits(Limits::PANDA, true).is_ok());
    let mut x = e.advance(200).unwrap().x;
    e.set_goal(vec![0.5, 0.1, 0.4, 0.0, 1.5, -1.0]).unwrap();
    x.extend(e.advance(3000).unwrap().x);
    let (lin, ang) = (peaks(&x, 6, 0..3, 1e-3), peaks(&x, 6, 3..6, 1e-3));
    let l = Limits::PANDA;
    assert!(lin[0] <= l.max_speed && lin[1] <= l.max_acceleration && lin[2] <= l.max_jerk, "{lin:?}");
    assert!(
        ang[0] <= l.max_angular_speed && ang[1] <= l.max_angular_acceleration && ang[2] <= l.max_angular_jerk,
        "{ang:?}"
    );
    // Without the orientation, the same limits bound the six dimensions as one position.
    let tiny =
        Primitive::straight_line(20, 4.0, vec![1000.0; 3], None, 0.5, vec![0.0; 3], vec![0.1; 3]).unwrap();
    let mut e3 = alone(&tiny, Scene::empty(), Stepping::rk4(1e-3), 10);
    assert_eq!(e3.set_limits(Limits::PANDA, true).unwrap_err().field, "limits");
    let bad = Limits { max_speed: -1.0, ..Limits::PANDA };
    assert_eq!(e3.set_limits(bad, false).unwrap_err().field, "limits.max_speed");
}

#[test]
fn a_run_started_at_a_velocity_moves_on_at_it_and_only_before_its_first_point() {
    let dt = 1e-3;
    let v = vec![0.4, -0.3];
    let mut e = reach(Stepping::rk4(dt), Scene::empty());
    e.set_start_velocity(v.clone()).unwrap();
    let s = e.advance(3).unwrap();
    assert_eq!(s.x[..2], [0.0, 0.0], "it starts where it is told");
    assert_eq!(s.xd[..2], v[..], "and as fast");
    // The next point is one step at that velocity away (up to the acceleration's share).
    for i in 0..2 {
        let moved = s.x[2 + i] - s.x[i];
        assert!((moved - v[i] * dt).abs() < 50.0 * dt * dt, "dim {i}: moved {moved}");
        assert!((s.xd[2 + i] - v[i]).abs() < 50.0 * dt, "dim {i}: velocity {}", s.xd[2 + i]);
    }
    let e2 = e.set_start_velocity(vec![0.0, 0.0]).unwrap_err();
    assert_eq!(e2.field, "start_velocity");
    assert!(reach(Stepping::rk4(dt), Scene::empty()).set_start_velocity(vec![f64::NAN, 0.0]).is_err());
    assert!(reach(Stepping::rk4(dt), Scene::empty()).set_start_velocity(vec![0.0]).is_err());
    // With limits, the limiter takes the robot as moving at the start velocity: no braking from a standstill.
    let mut limited = reach(Stepping::rk4(dt), Scene::empty());
    limited.set_start_velocity(v.clone()).unwrap();
    limited.set_limits(Limits { max_acceleration: 50.0, ..Limits::NONE }, false).unwrap();
    let s = limited.advance(3).unwrap();
    // Each step changes the velocity by about what the acceleration limit allows in one step (50 mm/s here),
    // starting from the robot's: it neither starts from rest nor jumps.
    let mut before = v[0];
    for (i, xd) in s.xd.iter().step_by(2).enumerate() {
        assert!((xd - before).abs() <= 2.0 * 50.0 * dt, "point {i}: {:?}", &s.xd[..6]);
        before = *xd;
    }
}

/// After a point the limiter changed, at RK4 on every point, the accelerations handed out in the dimensions
/// without limits are still the DMP's (the grid then hands out its knots' ends, whose accelerations it must
/// evaluate), as are the points after a change that lands there.
#[test]
fn the_accelerations_of_unlimited_dimensions_stay_the_dmps_after_a_limited_point() {
    let start = vec![0.0; 6];
    let goal = vec![1.0, 0.5, 0.0, 0.3, -0.2, 0.4];
    let p = Primitive::straight_line(20, 4.0, vec![400.0; 6], None, 1.0, start, goal).unwrap();
    let mut e = alone(&p, Scene::empty(), Stepping::rk4(1e-3), 10);
    e.set_limits(Limits { max_speed: 0.4, ..Limits::NONE }, true).unwrap();
    let (mut xd, mut xdd) = (Vec::new(), Vec::new());
    for k in 0..150 {
        let s = e.advance(10).unwrap();
        xd.extend(s.xd);
        xdd.extend(s.xdd);
        if k % 7 == 3 {
            // A change between two stretches (the goal is the same: only the grid restarts).
            e.set_goal(vec![1.0, 0.5, 0.0, 0.3, -0.2, 0.4]).unwrap();
        }
    }
    assert!(e.cost().limited > 100, "{:?}", e.cost());
    let n = xd.len() / 6;
    let mut worst = 0.0f64;
    for k in 1..n - 1 {
        for i in 3..6 {
            // The central difference, or one of the one-sided ones (a change of tau from a point changes the
            // acceleration there).
            let back = (xd[k * 6 + i] - xd[(k - 1) * 6 + i]) / 1e-3;
            let ahead = (xd[(k + 1) * 6 + i] - xd[k * 6 + i]) / 1e-3;
            let a = xdd[k * 6 + i];
            let err = [back, ahead, 0.5 * (back + ahead)]
                .iter()
                .map(|d| (a - d).abs())
                .fold(f64::INFINITY, f64::min);
            worst = worst.max(err);
        }
    }
    assert!(worst < 0.1, "an acceleration handed out is {worst} m/s² off the velocities' differences");
}

/// Goal changes of a pose run across its chart's cut (`execution/pose.rs`, `orientation/pose.rs`).
#[cfg(feature = "orientation")]
mod across_the_cut {
    use nalgebra::{Quaternion, UnitQuaternion, Vector3};

    use super::*;
    use crate::orientation::pose::pose_motion;
    use crate::orientation::quaternion::{angle_between, exp, log, to_xyzw};
    use crate::primitive::OrientationChart;

    const DT: f64 = 1e-3;

    /// The axis of the first turn, and of the new goals beyond it.
    fn axis() -> Vector3<f64> {
        Vector3::new(0.3, -0.5, 0.8).normalize()
    }

    /// A pose primitive (3-D position, K = 400, `tau` = 1 s) in the chart at the identity, turning from `0` to
    /// `60°` about [`axis`]; `shaped`: with a forcing term on the orientation (a bump of about 0.1 rad across the
    /// turn), otherwise a straight line.
    fn turning(shaped: bool) -> Primitive {
        let y = axis() * 60f64.to_radians();
        let goal = vec![0.3, 0.1, -0.2, y[0], y[1], y[2]];
        let mut p = Primitive::straight_line(20, 4.0, vec![400.0; 6], None, 1.0, vec![0.0; 6], goal).unwrap();
        p.orientation = Some(OrientationChart { reference: [0.0, 0.0, 0.0, 1.0] });
        if shaped {
            for (i, w) in p.weights[3..].iter_mut().enumerate() {
                for (j, v) in w.iter_mut().enumerate() {
                    *v = 0.1 * ((j as f64) * 0.7 + i as f64).sin();
                }
            }
        }
        p
    }

    /// Orientations, angular velocities and accelerations of a pose run's points.
    #[derive(Default)]
    struct Turn {
        q: Vec<UnitQuaternion<f64>>,
        omega: Vec<Vector3<f64>>,
        omega_dot: Vec<Vector3<f64>>,
        outcome: Outcome,
    }

    impl Turn {
        fn extend(&mut self, s: &Stretch) {
            let o = &s.orientation;
            let quat = |q: &[f64]| UnitQuaternion::new_unchecked(Quaternion::new(q[3], q[0], q[1], q[2]));
            self.q.extend(o.q.chunks_exact(4).map(quat));
            self.omega.extend(o.omega.chunks_exact(3).map(Vector3::from_column_slice));
            self.omega_dot.extend(o.omega_dot.chunks_exact(3).map(Vector3::from_column_slice));
            self.outcome = s.outcome;
        }

        /// Advances `n` points at a time, at most `seconds`, or to the end of the run.
        fn run(&mut self, e: &mut Execution, n: usize, seconds: f64) {
            for _ in 0..(seconds / (n as f64 * DT)).round() as usize {
                let s = e.advance(n).unwrap();
                self.extend(&s);
                if s.outcome.is_final() {
                    break;
                }
            }
        }

        /// The rotation travelled from point `from` on: the sum of the angles between neighbours.
        fn travelled(&self, from: usize) -> f64 {
            self.q[from..].windows(2).map(|w| angle_between(&w[0], &w[1])).sum()
        }
    }

    /// `q` and `-q`.
    fn both_signs(q: UnitQuaternion<f64>) -> [UnitQuaternion<f64>; 2] {
        [q, UnitQuaternion::new_unchecked(-q.into_inner())]
    }

    /// Checks that the points `k - 3 ..= k + 3` around the change (the first point after it is `k`) have no jump
    /// in orientation, angular velocity or acceleration, by finite differences at the output rate: each step of
    /// the orientation is the one `ω` gives (to `|ω̇| dt²`); `ω` is the central difference of the
    /// orientations and `ω̇` that of `ω` (to `O(dt²)` and `O(dt)`, with jerk up to `max_jerk`); and `ω̇` changes from a point to the next by at most
    /// `max_jerk dt`.
    fn continuous_at(r: &Turn, k: usize, max_jerk: f64, label: &str) {
        let peak_acc = r.omega_dot[k - 3..=k + 3].iter().map(|a| a.norm()).fold(0.0, f64::max);
        for j in k - 2..=k + 3 {
            let step = angle_between(&r.q[j - 1], &r.q[j]);
            let expected = 0.5 * (r.omega[j - 1] + r.omega[j]).norm() * DT;
            let tol = peak_acc * DT * DT + 1e-9;
            assert!(
                (step - expected).abs() <= tol,
                "{label}: orientation at {j}: a step of {step}, not {expected}"
            );
        }
        for j in k - 2..=k + 2 {
            let fd = log(&(r.q[j + 1] * r.q[j - 1].conjugate())) / (2.0 * DT);
            let tol = 1e-4 * (1.0 + r.omega[j].norm()) + max_jerk * DT * DT / 3.0;
            assert!((fd - r.omega[j]).norm() <= tol, "{label}: ω at {j}: {fd} vs {}", r.omega[j]);
            let fd = (r.omega[j + 1] - r.omega[j - 1]) / (2.0 * DT);
            let tol = 2.0 * max_jerk * DT;
            assert!((fd - r.omega_dot[j]).norm() <= tol, "{label}: ω̇ at {j}: {fd} vs {}", r.omega_dot[j]);
        }
        for j in k - 3..=k + 3 {
            let jump = (r.omega_dot[j + 1] - r.omega_dot[j]).norm();
            assert!(jump <= max_jerk * DT, "{label}: ω̇ jumps by {jump} rad/s² at {j}");
        }
    }

    /// New goals 150° to 179° beyond the current orientation, across the chart's cut, in both signs: the run
    /// turns by the short angle (the rotation travelled after the change is within 0.5° of it, the angle to the
    /// goal only decreases once the change has settled) and reaches the goal, continuously at the change.
    #[test]
    fn a_goal_change_across_the_cut_turns_the_short_way() {
        for degrees in [150.0, 160.0, 162.2, 170.0, 175.0, 179.0] {
            let theta = f64::to_radians(degrees);
            for sign in 0..2 {
                let label = format!("{degrees}°, sign {sign}");
                let mut e = alone(&turning(false), Scene::empty(), Stepping::rk4(DT), 10);
                let mut r = Turn::default();
                // Nearly at rest at the first goal (60°), then on along the same axis.
                r.run(&mut e, 100, 1.5);
                let current = *r.q.last().unwrap();
                let goal = both_signs(exp(&(axis() * theta)) * current)[sign];
                e.set_pose_goal(None, Some(to_xyzw(&goal))).unwrap();
                let k = r.q.len();
                r.run(&mut e, 100, 6.0);
                assert_eq!(r.outcome, Outcome::GoalReached, "{label}");
                let miss = angle_between(r.q.last().unwrap(), &goal).to_degrees();
                assert!(miss <= 0.1, "{label}: ends {miss}° from the goal");
                let turned = (r.travelled(k - 1)).to_degrees();
                assert!((turned - degrees).abs() <= 0.5, "{label}: turned {turned}°");
                // Settled: from 0.05 s after the change on, the angle to the goal never grows.
                let to_goal: Vec<f64> = r.q[k + 50..].iter().map(|q| angle_between(q, &goal)).collect();
                for (j, w) in to_goal.windows(2).enumerate() {
                    assert!(w[1] <= w[0] + 1e-12, "{label}: the angle to the goal grows at {}", k + 50 + j);
                }
                // A filtered goal change: the jerk is at most K alpha_g / tau³ times the angle.
                continuous_at(&r, k, 400.0 * 10.0 * theta * 1.05, &label);
            }
        }
    }

    /// A change mid-turn (phase 0.25, turning at about 1.5 rad/s, with a forcing term on the orientation) to a goal
    /// 170° beyond the current orientation, across the cut: the orientation, `ω` and `ω̇` stay continuous (the
    /// start absorbs what the change of chart does to the transformation system's acceleration), the run turns by
    /// about the short angle (within the bend its motion and forcing term give it), and reaches the goal. A
    /// rollback to before the change then joins the points kept without a jump and reaches the goal too.
    #[test]
    fn a_goal_change_across_the_cut_mid_turn_is_continuous() {
        for sign in 0..2 {
            let label = format!("sign {sign}");
            let mut e = alone(&turning(true), Scene::empty(), Stepping::rk4(DT), 400);
            let mut r = Turn::default();
            r.run(&mut e, 50, 0.35);
            let k = r.q.len();
            assert!(r.omega[k - 1].norm() > 1.0, "{label}: turning at {}", r.omega[k - 1].norm());
            let jerk = |r: &Turn, range: std::ops::Range<usize>| {
                range.map(|j| (r.omega_dot[j + 1] - r.omega_dot[j]).norm() / DT).fold(0.0, f64::max)
            };
            let before = jerk(&r, k - 50..k - 1);
            let theta = 170f64.to_radians();
            let goal = both_signs(exp(&(axis() * theta)) * r.q[k - 1])[sign];
            e.set_pose_goal(None, Some(to_xyzw(&goal))).unwrap();
            r.run(&mut e, 50, 0.2);
            let kept = r.q.len();
            let max_jerk = 1.5 * before + 400.0 * 10.0 * theta * 1.05;
            continuous_at(&r, k, max_jerk, &label);
            let mut rest = Turn::default();
            rest.q.extend_from_slice(&r.q);
            rest.run(&mut e, 50, 6.0);
            assert_eq!(rest.outcome, Outcome::GoalReached, "{label}");
            let miss = angle_between(rest.q.last().unwrap(), &goal).to_degrees();
            assert!(miss <= 0.1, "{label}: ends {miss}° from the goal");
            let turned = rest.travelled(k - 1).to_degrees();
            assert!(turned < 175.0, "{label}: turned {turned}° for a goal 170° away");

            // Back to the change (what a server does: it rolls back to the first point not yet played, and
            // applies the change there): the same points.
            let mut again = alone(&turning(true), Scene::empty(), Stepping::rk4(DT), 400);
            let mut r2 = Turn::default();
            r2.run(&mut again, 50, 0.35);
            again.set_pose_goal(None, Some(to_xyzw(&goal))).unwrap();
            r2.run(&mut again, 50, 0.2);
            assert_eq!(r2.q.len(), kept);
            assert!((again.rollback_to(k as f64 * DT) - k as f64 * DT).abs() < 1e-9);
            let mut redo = Turn::default();
            redo.run(&mut again, 50, 0.2);
            for (j, (a, b)) in redo.q.iter().zip(&r.q[k..kept]).enumerate() {
                assert!(angle_between(a, b) < 1e-12, "{label}: recomputed point {j} differs");
            }
            // Back to 0.1 s before the change (the history there is in the old chart, mapped): the run goes on
            // from there continuously in orientation and `ω`, to the goal. The start absorbed the acceleration's
            // difference at the change, not there: `ω̇` may step, by a few per cent of a goal step.
            let back = (k - 100) as f64 * DT;
            assert!((again.rollback_to(back) - back).abs() < 1e-9);
            let join = k - 100;
            let mut r3 = Turn::default();
            r3.q.extend_from_slice(&r.q[..join]);
            r3.omega.extend_from_slice(&r.omega[..join]);
            r3.omega_dot.extend_from_slice(&r.omega_dot[..join]);
            r3.run(&mut again, 50, 6.0);
            assert_eq!(r3.outcome, Outcome::GoalReached, "{label}: after the rollback");
            let miss = angle_between(r3.q.last().unwrap(), &goal).to_degrees();
            assert!(miss <= 0.1, "{label}: after the rollback, ends {miss}° from the goal");
            let turned = r3.travelled(join - 1).to_degrees();
            let short = angle_between(&r3.q[join - 1], &goal).to_degrees();
            assert!(turned < short + 5.0, "{label}: after the rollback, turned {turned}° for {short}°");
            let step = 400.0 * theta;
            continuous_at(&r3, join, 1.5 * before + 400.0 * 10.0 * theta * 1.05 + 0.02 * step / DT, &label);
        }
    }

    /// A run whose initial goal is 150° to 179° beyond the primitive's goal orientation (121° to 150° from its
    /// start the short way, across the primitive's chart's cut), in both signs: `pose_motion` charts the run at
    /// its goal, so it turns by the short angle and reaches the goal.
    #[test]
    fn an_initial_goal_across_the_cut_turns_the_short_way() {
        let p = turning(false);
        let primitive_goal = exp(&(axis() * 60f64.to_radians()));
        let start = UnitQuaternion::identity();
        for degrees in [150.0, 162.2, 170.0, 179.0] {
            for sign in 0..2 {
                let label = format!("{degrees}°, sign {sign}");
                let goal = both_signs(exp(&(axis() * f64::to_radians(degrees))) * primitive_goal)[sign];
                let short = angle_between(&start, &goal).to_degrees();
                let position = Motion { start: p.start.clone(), goal: p.goal.clone(), tau: 1.0 };
                let m = pose_motion(&p, position, None, Some(to_xyzw(&goal))).unwrap();
                let mut e = Execution::new(
                    p.clone(),
                    m.motion,
                    Scene::empty(),
                    CellMateAvoidance::NONE,
                    Stepping::rk4(DT),
                    0,
                )
                .unwrap();
                e.set_orientation_chart(m.chart).unwrap();
                let mut r = Turn::default();
                r.run(&mut e, 100, 6.0);
                assert_eq!(r.outcome, Outcome::GoalReached, "{label}");
                assert!(angle_between(&r.q[0], &start) < 1e-12, "{label}");
                let miss = angle_between(r.q.last().unwrap(), &goal).to_degrees();
                assert!(miss <= 0.1, "{label}: ends {miss}° from the goal");
                let turned = r.travelled(0).to_degrees();
                assert!((turned - short).abs() <= 0.5, "{label}: turned {turned}° for {short}°");
            }
        }
    }
}
