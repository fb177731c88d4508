//! "At the goal and at rest": a run reaches its goal at the first point of the unbroken run of points within the
//! tolerance asked for, and reports when that run began.

use dmp::execution::{CellMateAvoidance, GoalTolerance};
use dmp::{Execution, Motion, Outcome, Primitive, Scene, Stepping};

use crate::fixtures::{PAPER, demo_of, uniform_times};

const DT: f64 = 1e-3;

fn run(p: &Primitive, tau: f64, tolerance: GoalTolerance) -> Execution {
    let motion = Motion { start: p.start.clone(), goal: p.goal.clone(), tau };
    let mut e =
        Execution::new(p.clone(), motion, Scene::empty(), CellMateAvoidance::NONE, Stepping::rk4(DT), 200)
            .unwrap();
    e.set_goal_tolerance(tolerance).unwrap();
    e
}

/// Advances ten points at a time until the run is complete (at most 10 s); its outcome and every point handed out.
fn to_the_end(e: &mut Execution) -> (Outcome, Vec<f64>, Vec<f64>) {
    let (mut x, mut xd) = (Vec::new(), Vec::new());
    for _ in 0..1000 {
        let s = e.advance(10).unwrap();
        x.extend_from_slice(&s.x);
        xd.extend_from_slice(&s.xd);
        if s.outcome.is_final() {
            return (s.outcome, x, xd);
        }
    }
    (Outcome::Running, x, xd)
}

/// The time of the first point of the last unbroken run of points within `tol` of `goal`, counted independently.
fn first_met(x: &[f64], xd: &[f64], goal: &[f64], tol: GoalTolerance) -> Option<f64> {
    let d = goal.len();
    let mut since = None;
    for (k, (p, v)) in x.chunks_exact(d).zip(xd.chunks_exact(d)).enumerate() {
        let dist = p.iter().zip(goal).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt();
        let speed = v.iter().map(|a| a * a).sum::<f64>().sqrt();
        if dist <= tol.position && speed <= tol.speed {
            since = since.or(Some(k as f64 * DT));
        } else {
            since = None;
        }
    }
    since
}

/// The minimum-jerk reach from the origin to (0.3, 0.2) in 1 s: it ends at rest.
fn minimum_jerk() -> Primitive {
    let curve = |t: f64| {
        let s = 10.0 * t.powi(3) - 15.0 * t.powi(4) + 6.0 * t.powi(5);
        vec![0.3 * s, 0.2 * s]
    };
    dmp::learn(&demo_of(&uniform_times(), curve), &dmp::LearnConfig::paper()).unwrap()
}

#[test]
fn the_goal_is_reached_within_a_stretch_of_the_first_point_within_tolerance() {
    let mut previous = f64::INFINITY;
    for tol in [GoalTolerance::DEFAULT, GoalTolerance::linear(1e-3, 1e-2), GoalTolerance::linear(1e-2, 1e-1)]
    {
        let mut e = run(&PAPER, 1.0, tol);
        let (outcome, x, xd) = to_the_end(&mut e);
        assert_eq!(outcome, Outcome::GoalReached, "{tol:?}");
        let since = e.goal_met_since().expect("arrived");
        let counted = first_met(&x, &xd, &PAPER.goal, tol).unwrap();
        assert!((since - counted).abs() < 1e-9, "{tol:?}: {since} against {counted}");
        // The run ends at the end of the stretch in which it arrived.
        let end = (x.len() / 2 - 1) as f64 * DT;
        assert!(end - since < 10.0 * DT, "{tol:?}: arrived at {since}, ended at {end}");
        // The paper's curve passes its goal at t = tau at speed: it is not at rest there.
        assert!(since > 1.2, "{tol:?}: {since}");
        // A looser tolerance is met no later.
        assert!(since <= previous, "{tol:?}: {since} after {previous}");
        previous = since;
    }
}

#[test]
fn a_demonstration_that_ends_at_rest_arrives_at_about_tau() {
    let p = minimum_jerk();
    for tau in [1.0, 2.0] {
        let mut e = run(&p, tau, GoalTolerance::DEFAULT);
        let (outcome, ..) = to_the_end(&mut e);
        assert_eq!(outcome, Outcome::GoalReached);
        let since = e.goal_met_since().unwrap();
        assert!((0.9 * tau..=1.05 * tau).contains(&since), "tau {tau}: arrived at {since}");
    }
}

#[test]
fn a_rollback_before_the_arrival_forgets_it_and_finds_it_again() {
    let mut e = run(&PAPER, 1.0, GoalTolerance::linear(1e-3, 1e-2));
    let (outcome, ..) = to_the_end(&mut e);
    assert_eq!(outcome, Outcome::GoalReached);
    let since = e.goal_met_since().unwrap();
    e.rollback_to(since - 0.02);
    assert_eq!(e.goal_met_since(), None);
    let (outcome, ..) = to_the_end(&mut e);
    assert_eq!(outcome, Outcome::GoalReached);
    assert!((e.goal_met_since().unwrap() - since).abs() < 1e-9);
}

#[test]
fn a_tolerance_that_is_not_positive_is_refused_with_its_field() {
    let mut e = run(&PAPER, 1.0, GoalTolerance::DEFAULT);
    let err = e.set_goal_tolerance(GoalTolerance::linear(0.0, 1e-3)).unwrap_err();
    assert_eq!(err.field, "goal_tolerance.position");
    let err = e.set_goal_tolerance(GoalTolerance::linear(1e-3, f64::NAN)).unwrap_err();
    assert_eq!(err.field, "goal_tolerance.speed");
    assert_eq!(e.goal_tolerance(), GoalTolerance::DEFAULT);
}
