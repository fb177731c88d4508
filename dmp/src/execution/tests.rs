//! The execution's own contract: rollbacks recompute the same points, changes keep the motion continuous, stops and
//! end times end the run where they say.

use super::*;

/// A run of `p` with its own motion, in `scene`, without cell-mates, keeping `history` points.
pub(super) fn alone(p: &Primitive, scene: Scene, stepping: Stepping, history: usize) -> Execution {
    Execution::new(p.clone(), Motion::of(p), scene, CellMateAvoidance::NONE, stepping, history).unwrap()
}

/// A 2-D straight reach from the origin to (1, 0.5) in 1 s, alone, at `stepping`.
fn reach(stepping: Stepping) -> Execution {
    let p =
        Primitive::straight_line(20, 4.0, vec![1000.0; 2], None, 1.0, vec![0.0; 2], vec![1.0, 0.5]).unwrap();
    alone(&p, Scene::empty(), stepping, 200)
}

/// Advances ten points at a time until the run is complete, at most `stretches` times; the last outcome.
fn advance_until_final(e: &mut Execution, stretches: usize) -> Outcome {
    let mut outcome = Outcome::Running;
    for _ in 0..stretches {
        outcome = e.advance(10).unwrap().outcome;
        if outcome.is_final() {
            break;
        }
    }
    outcome
}

/// A 2-D straight reach (K = 100) to (1, 0.5) in 1 s, alone at RK4, held to `max_speed`: it wants several times
/// that much.
fn held_to_speed(max_speed: f64) -> Execution {
    let p =
        Primitive::straight_line(20, 4.0, vec![100.0; 2], None, 1.0, vec![0.0; 2], vec![1.0, 0.5]).unwrap();
    let mut e = alone(&p, Scene::empty(), Stepping::rk4(1e-3), 200);
    e.set_limits(Limits { max_speed, ..Limits::NONE }, false).unwrap();
    e
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

#[test]
fn a_rollback_recomputes_the_same_points_bit_for_bit() {
    for stepping in [
        Stepping::rk4(1e-3),
        Stepping { dt: 1e-3, step_points: 5, tolerance: None },
        Stepping { dt: 1e-3, step_points: 30, tolerance: Some(3e-6) },
    ] {
        let mut e = reach(stepping);
        e.advance(50).unwrap();
        let first = e.advance(50).unwrap();
        assert_eq!(e.rollback_to(0.050), 0.050, "{stepping:?}");
        let again = e.advance(50).unwrap();
        assert_eq!(again.start_time, first.start_time);
        for (a, b, tol) in
            [(&first.x, &again.x, 1e-6), (&first.xd, &again.xd, 1e-4), (&first.xdd, &again.xdd, 1e-2)]
        {
            if stepping.is_coarse() {
                // The grid restarts at the rolled-back point: the same trajectory to the integration's accuracy.
                let worst = a.iter().zip(b).map(|(p, q)| (p - q).abs()).fold(0.0, f64::max);
                assert!(worst < tol, "{stepping:?}: {worst}");
            } else {
                assert_eq!(bits(a), bits(b), "{stepping:?}");
            }
        }
    }
}

#[test]
fn a_goal_change_keeps_position_and_velocity_continuous_and_is_reached() {
    let mut e = reach(Stepping::rk4(1e-3));
    let before = e.advance(400).unwrap();
    e.set_goal(vec![0.2, 0.9]).unwrap();
    let after = e.advance(1).unwrap();
    let (x0, v0) = (&before.x[798..], &before.xd[798..]);
    for i in 0..2 {
        assert!((after.x[i] - x0[i] - 1e-3 * v0[i]).abs() < 1e-5, "position jumps");
        assert!((after.xd[i] - v0[i]).abs() < 0.05, "velocity jumps: {} -> {}", v0[i], after.xd[i]);
    }
    let outcome = advance_until_final(&mut e, 400);
    assert_eq!(outcome, Outcome::GoalReached);
    assert!(e.set_goal(vec![1.0]).is_err() && e.set_goal(vec![f64::NAN, 0.0]).is_err());
}

#[test]
fn a_stop_comes_to_rest_ends_the_run_and_is_not_resumed() {
    let mut e = reach(Stepping::rk4(1e-3));
    e.advance(300).unwrap();
    e.stop();
    assert_eq!(e.advance(10).unwrap().outcome, Outcome::Holding);
    e.set_holding(false);
    assert!(e.is_holding(), "a stop is not resumed");
    let outcome = advance_until_final(&mut e, 200);
    assert_eq!(outcome, Outcome::Stopped);
    assert!(e.at_rest() && !e.arrived());
}

/// A run slowed by temporal coupling (a tight speed limit stretches its `tau`) stops at the rate of its own `tau`:
/// stretched tenfold, the damping would take ten times as long to bring it to rest.
#[test]
fn a_stop_of_a_run_slowed_by_its_limits_is_as_quick_as_its_own_tau() {
    let mut e = held_to_speed(0.2);
    e.advance(1000).unwrap();
    assert!(e.tau_scale() > 3.0, "the limit did not slow the run: {}", e.tau_scale());
    let moving = e.last().1.iter().map(|v| v * v).sum::<f64>().sqrt();
    assert!(moving > 0.1, "{moving}");
    e.stop();
    let stopped_at = e.time();
    assert_eq!(advance_until_final(&mut e, 200), Outcome::Stopped);
    // From `moving` to ARRIVED_SPEED at the rate D / tau = 20 / s: ln(0.2 / 1e-3) / 20 ≈ 0.27 s (2.7 s stretched).
    let took = e.time() - stopped_at;
    let own = (moving / ARRIVED_SPEED).ln() / 20.0;
    assert!(took < own + 0.05, "stopped in {took} s, its own tau's damping takes {own} s");
}

#[test]
fn the_end_time_ends_the_run_on_its_point() {
    let mut e = reach(Stepping::rk4(1e-3));
    e.set_end_time(0.25);
    let mut last = Stretch::default();
    while !last.outcome.is_final() {
        last = e.advance(40.min(e.points_to_end())).unwrap();
    }
    assert_eq!(last.outcome, Outcome::EndTime);
    assert!((e.time() - 1e-3 - 0.25).abs() < 1e-12, "the last point is at the end time: {}", e.time());
}

#[test]
fn a_pause_holds_without_stalling_and_a_resume_goes_on() {
    let mut e = reach(Stepping::rk4(1e-3));
    e.advance(200).unwrap();
    e.set_holding(true);
    for _ in 0..100 {
        let s = e.advance(10).unwrap();
        assert_eq!(s.outcome, Outcome::Holding);
        assert!(s.stalls.is_empty());
    }
    assert!(e.at_rest());
    e.set_holding(false);
    let outcome = advance_until_final(&mut e, 400);
    assert_eq!(outcome, Outcome::GoalReached);
}

/// On a coarse grid, each point the limiter changes restarts the DMP with a probe of one output step (one
/// evaluation), not a whole step: a run held at its limits costs about one evaluation a limited point more, and
/// follows the path of the same limited run at RK4 on every output point.
#[test]
fn limited_points_on_a_coarse_grid_cost_one_evaluation_and_follow_the_fine_grid() {
    let p =
        Primitive::straight_line(20, 4.0, vec![100.0; 2], None, 1.0, vec![0.0; 2], vec![1.0, 0.5]).unwrap();
    let limits = Limits { max_speed: 0.3, max_acceleration: 5.0, max_jerk: 500.0, ..Limits::NONE };
    let run = |stepping| {
        let mut e = alone(&p, Scene::empty(), stepping, 200);
        e.set_limits(limits, false).unwrap();
        let mut x = Vec::new();
        for _ in 0..300 {
            x.extend(e.advance(10).unwrap().x);
        }
        (x, e.cost())
    };
    let (fine, _) = run(Stepping::rk4(1e-3));
    let (coarse, cost) = run(Stepping { dt: 1e-3, step_points: 30, tolerance: Some(3e-6) });
    assert!(cost.limited > 300, "the run is not held at its limits: {cost:?}");
    let extra = cost.evaluations as f64 - 6.0 * cost.steps.saturating_sub(cost.limited) as f64;
    assert!(extra <= 1.2 * cost.limited as f64, "limited points cost more than one evaluation: {cost:?}");
    // The same path: a decision of the limiter or the coupling that falls a point apart on the two grids shifts
    // the timing (millimetres along the path by the end), not the path.
    let path = coarse
        .chunks(2)
        .map(|c| fine.chunks(2).map(|f| (f[0] - c[0]).hypot(f[1] - c[1])).fold(f64::INFINITY, f64::min))
        .fold(0.0, f64::max);
    assert!(path < 5e-4, "the coarse grid's path leaves the fine one's by {path} m");
}

/// Temporal coupling slows the robot, not only its phase (the `-tau' v` term, `limiting.rs`): a reach that wants
/// 4.5 times its speed limit is stretched about as much as the DMP's own time scaling needs (its peak speed over
/// the limit, over the coupling's threshold: 5), and arrives. Without the term the speed stayed at the limit
/// while the phase slowed, so the stretch ran on to its cap.
#[test]
fn temporal_coupling_slows_the_robot_as_much_as_its_phase() {
    let p =
        Primitive::straight_line(20, 4.0, vec![100.0; 2], None, 1.0, vec![0.0; 2], vec![1.0, 0.0]).unwrap();
    let run = |limits: Limits| {
        let mut e = alone(&p, Scene::empty(), Stepping::rk4(1e-3), 200);
        e.set_limits(limits, false).unwrap();
        let (mut peak, mut stretch, mut last) = (0.0f64, 1.0f64, Stretch::default());
        while !last.outcome.is_final() && e.time() < 10.0 {
            last = e.advance(10).unwrap();
            peak = peak.max(last.xd.chunks(2).map(|v| v[0].hypot(v[1])).fold(0.0, f64::max));
            stretch = stretch.max(e.tau_scale());
        }
        (peak, stretch, last.outcome)
    };
    let (free, ..) = run(Limits::NONE);
    let limit = free / 4.5;
    let (peak, stretch, outcome) = run(Limits { max_speed: limit, ..Limits::NONE });
    assert_eq!(outcome, Outcome::GoalReached);
    assert!(peak <= limit * (1.0 + 1e-9), "{peak} > {limit}");
    let needed = free / limit / super::limiting::COUPLE_ABOVE;
    assert!(
        stretch < 1.5 * needed && stretch < super::limiting::MAX_TAU_SCALE,
        "stretched {stretch}, needed {needed}"
    );
}

/// Limits taken off mid-run: the time scale the coupling stretched relaxes back to the run's own, the speed
/// coupling's term goes, and the run arrives.
#[test]
fn limits_taken_off_mid_run_give_the_run_its_own_time_scale_back() {
    let mut e = held_to_speed(0.3);
    e.advance(500).unwrap();
    assert!(e.tau_scale() > 2.0, "{}", e.tau_scale());
    e.set_limits(Limits::NONE, false).unwrap();
    assert_eq!((advance_until_final(&mut e, 1000), e.tau_scale()), (Outcome::GoalReached, 1.0));
}

/// The speed coupling's term comes and goes by steps of a quarter of its rate (`COUPLE_RATE_PERIODS`): held at
/// its speed limit, the run's acceleration never jumps by much more than a quarter of `COUPLE_RATE |x'|` from one
/// point to the next (switched whole, it jumped by about `COUPLE_RATE |x'|` each time the speed crossed the
/// coupling's threshold).
#[test]
fn the_speed_coupling_term_comes_and_goes_without_jumps() {
    use super::limiting::{COUPLE_RATE, COUPLE_RATE_PERIODS};
    let speed = 0.3;
    let mut e = held_to_speed(speed);
    let mut a = Vec::new();
    for _ in 0..300 {
        a.extend(e.advance(10).unwrap().xdd);
    }
    assert!(e.cost().limited > 100, "not held at its limit: {:?}", e.cost());
    // From 0.1 s on: the DMP's start asks for a jump of its own.
    let jump = (100..a.len() / 2)
        .map(|k| (a[k * 2] - a[(k - 1) * 2]).hypot(a[k * 2 + 1] - a[(k - 1) * 2 + 1]))
        .fold(0.0, f64::max);
    let step = COUPLE_RATE * speed / COUPLE_RATE_PERIODS;
    assert!(jump < 1.5 * step, "the acceleration jumps by {jump} m/s², the term's step is {step}");
}
