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

/// A run held at its speed limit, the robot behind the DMP, stops at the rate of its own `tau` from where the
/// robot is: the stop restarts the DMP there (not where the DMP ran ahead to), and the final stage brakes with it.
#[test]
fn a_stop_of_a_run_held_at_its_limits_stops_where_the_robot_is() {
    let mut e = held_to_speed(0.2);
    e.advance(1000).unwrap();
    assert!(e.cost().limited > 500, "the limit did not hold the run: {:?}", e.cost());
    let moving = e.last().1.iter().map(|v| v * v).sum::<f64>().sqrt();
    assert!(moving > 0.19, "{moving}");
    let at = e.last().0.to_vec();
    e.stop();
    let stopped_at = e.time();
    assert_eq!(advance_until_final(&mut e, 200), Outcome::Stopped);
    // From `moving` to ARRIVED_SPEED at the rate D / tau = 20 / s: ln(0.2 / 1e-3) / 20 ≈ 0.27 s.
    let took = e.time() - stopped_at;
    let own = (moving / ARRIVED_SPEED).ln() / 20.0;
    assert!(took < own + 0.05, "stopped in {took} s, its own tau's damping takes {own} s");
    // Within what the damping covers from that speed (v tau / D = 0.01 m), not at the DMP's lead.
    let went = e.last().0.iter().zip(&at).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt();
    assert!(went < 0.012, "went {went} m after the stop");
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

/// On a straight reach the robot's lag behind the DMP is free (no deviation from a straight path): a reach that
/// wants 4.5 times its speed limit takes the time-optimal time at that limit (`D / V` with no acceleration bound),
/// never faster than the limit, without stretching its phase.
#[test]
fn a_straight_reach_over_its_speed_limit_takes_the_time_optimal_time() {
    let p =
        Primitive::straight_line(20, 4.0, vec![100.0; 2], None, 1.0, vec![0.0; 2], vec![1.0, 0.0]).unwrap();
    let run = |limits: Limits| {
        let mut e = alone(&p, Scene::empty(), Stepping::rk4(1e-3), 200);
        e.set_limits(limits, false).unwrap();
        let (mut peak, mut stretch, mut last, mut within) = (0.0f64, 1.0f64, Stretch::default(), None);
        while !last.outcome.is_final() && e.time() < 10.0 {
            last = e.advance(10).unwrap();
            for (k, v) in last.xd.chunks(2).enumerate() {
                peak = peak.max(v[0].hypot(v[1]));
                let x = &last.x[2 * k..2 * k + 2];
                if within.is_none() && (x[0] - 1.0).hypot(x[1]) <= 1e-3 {
                    within = Some(last.start_time + k as f64 * 1e-3);
                }
            }
            stretch = stretch.max(e.tau_scale());
        }
        (peak, stretch, last.outcome, within.unwrap_or(f64::INFINITY))
    };
    let (free, ..) = run(Limits::NONE);
    let limit = free / 4.5;
    let (peak, stretch, outcome, within) = run(Limits { max_speed: limit, ..Limits::NONE });
    assert_eq!(outcome, Outcome::GoalReached);
    assert!(peak <= limit * (1.0 + 1e-9), "{peak} > {limit}");
    let optimum = (1.0 - 1e-3) / limit;
    assert!(within <= 1.02 * optimum, "within 1 mm at {within} s, the optimum is {optimum} s");
    assert_eq!(stretch, 1.0);
}

/// Round an obstacle the DMP's path curves, and a robot held at its speed limit would cut the curve if the DMP
/// ran ahead: the phase waits (temporal coupling on the lag), and the robot's path stays within a few path
/// tolerances of the DMP's own.
#[test]
fn the_phase_waits_for_a_robot_held_back_on_a_curve() {
    use crate::avoidance::{Avoidance, Method, StaticVolumetric};
    use crate::isopotential::{Shape, Superquadric};
    use crate::obstacle::Obstacle;
    let p =
        Primitive::straight_line(20, 4.0, vec![100.0; 2], None, 1.0, vec![0.0; 2], vec![1.0, 0.0]).unwrap();
    let ball = Obstacle::new(
        "ball",
        Shape::Superquadric(Superquadric::new(vec![0.1, 0.1], vec![1.0, 1.0]).unwrap()),
        vec![0.5, 0.02],
        None,
        None,
    )
    .unwrap();
    let avoid = Avoidance::new(Method::StaticVolumetric(StaticVolumetric { a: 0.1, eta: 1.0 }));
    let run = |limits: Limits| {
        let mut e = alone(&p, Scene::with_obstacles(vec![ball.clone()], avoid, 0), Stepping::rk4(1e-3), 200);
        e.set_limits(limits, false).unwrap();
        let (mut x, mut stretch, mut last) = (Vec::new(), 1.0f64, Stretch::default());
        while !last.outcome.is_final() && e.time() < 20.0 {
            last = e.advance(10).unwrap();
            x.extend_from_slice(&last.x);
            stretch = stretch.max(e.tau_scale());
        }
        (x, stretch, last.outcome)
    };
    let (free, ..) = run(Limits::NONE);
    let (held, stretch, outcome) = run(Limits { max_speed: 0.3, max_acceleration: 3.0, ..Limits::NONE });
    assert_eq!(outcome, Outcome::GoalReached);
    assert!(stretch > 1.2, "the phase did not wait: {stretch}");
    // The robot keeps the clearance the DMP keeps round the ball (the chords of a robot ahead of its phase
    // would cut towards it).
    let clearance =
        |x: &[f64]| x.chunks(2).map(|c| (c[0] - 0.5).hypot(c[1] - 0.02) - 0.1).fold(f64::INFINITY, f64::min);
    let (c_free, c_held) = (clearance(&free), clearance(&held));
    assert!(
        c_held >= c_free - 2.0 * super::tracking::PATH_TOLERANCE,
        "clearance {c_held} m, the DMP's {c_free} m"
    );
}

/// Limits taken off mid-run: the final stage hands back to the DMP, and the run arrives on its own time scale.
#[test]
fn limits_taken_off_mid_run_give_the_run_its_own_time_scale_back() {
    let mut e = held_to_speed(0.3);
    e.advance(500).unwrap();
    assert!(e.cost().limited > 100, "{:?}", e.cost());
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
