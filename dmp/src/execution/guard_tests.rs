//! The safety distance ([`Execution::set_margin`], `guard.rs`): a robot that can brake never comes closer than the
//! margin to an obstacle's true shape, whatever the field does, and goes on when the way clears.

use super::tests::alone;
use super::*;
use crate::avoidance::{DynamicVolumetric, Method};
use crate::distance::signed_distance_world;
use crate::isopotential::{Shape, Superquadric};
use crate::obstacle::Obstacle;

/// A 2-D straight reach (K = 150) from the origin to `goal` in `tau`.
fn reach(goal: [f64; 2], tau: f64) -> Primitive {
    Primitive::straight_line(20, 4.0, vec![150.0; 2], None, tau, vec![0.0; 2], goal.to_vec()).unwrap()
}

fn ball(id: &str, center: [f64; 2], r: f64) -> Obstacle {
    Obstacle::new(
        id,
        Shape::Superquadric(Superquadric::ellipsoid(vec![r, r]).unwrap()),
        center.to_vec(),
        None,
        None,
    )
    .unwrap()
}

/// What a run handed out until it ended (or `until` seconds): the points, the smallest clearance of any point from
/// `truth` (at its time), the actions, and the last outcome.
struct Ran {
    x: Vec<f64>,
    clearance: f64,
    blocked: usize,
    collisions: usize,
    outcome: Outcome,
}

fn run(e: &mut Execution, truth: &[Obstacle], until: f64, mut at: impl FnMut(&mut Execution, f64)) -> Ran {
    let mut r =
        Ran { x: Vec::new(), clearance: f64::INFINITY, blocked: 0, collisions: 0, outcome: Outcome::Running };
    while !r.outcome.is_final() && e.time() < until {
        at(e, e.time());
        let s = e.advance(10).unwrap();
        for k in 0..s.x.len() / 2 {
            let t = s.start_time + k as f64 * e.dt();
            for o in truth {
                r.clearance = r.clearance.min(signed_distance_world(o, &s.x[2 * k..2 * k + 2], t));
            }
        }
        r.blocked += usize::from(s.limit == LimitAction::Blocked);
        r.collisions += s.contacts.len();
        r.x.extend_from_slice(&s.x);
        r.outcome = s.outcome;
    }
    r
}

/// A goal inside an obstacle: with the field, the robot keeps the margin round it; without one (avoidance off),
/// it brakes before the margin and is held there, blocked, to the end. Never closer than the margin.
#[test]
fn a_goal_inside_an_obstacle_is_approached_to_the_margin_and_no_closer() {
    let p = reach([1.0, 0.0], 1.0);
    let wall = ball("wall", [1.0, 0.0], 0.2);
    let margin = 0.03;
    let dynamic =
        Avoidance::new(Method::DynamicVolumetric(DynamicVolumetric { lambda: 1.0, beta: 2.0, eta: 1.0 }));
    for avoid in [dynamic, Avoidance::NONE] {
        let mut e = alone(&p, Scene::with_obstacles(vec![wall.clone()], avoid, 0), Stepping::rk4(1e-3), 200);
        e.set_limits(Limits::PANDA, false).unwrap();
        e.set_margin(margin).unwrap();
        e.set_end_time(3.0);
        let r = run(&mut e, std::slice::from_ref(&wall), 5.0, |_, _| {});
        assert_eq!(r.collisions, 0, "{avoid:?}");
        assert!(
            r.clearance >= margin - 1e-9,
            "{avoid:?}: clearance {} m under the margin {margin} m",
            r.clearance
        );
        assert_eq!(r.outcome, Outcome::EndTime, "{avoid:?}");
        if avoid == Avoidance::NONE {
            assert!(r.blocked > 0, "never blocked");
            // Held close to the margin: it brakes to rest before it, not far short.
            assert!(r.clearance < margin + 0.02, "held {} m away", r.clearance);
        }
    }
}

/// An obstacle appears in front of a fast robot, more than a braking distance and the margin ahead, with no
/// avoidance at all: the robot brakes to rest before the margin, is held, and goes on to its goal once the
/// obstacle is gone.
#[test]
fn an_obstacle_that_appears_ahead_is_braked_for_and_the_run_goes_on_when_it_leaves() {
    let p = reach([1.2, 0.0], 0.8);
    let block = ball("block", [0.75, 0.0], 0.1);
    let margin = 0.02;
    let mut e = alone(&p, Scene::empty(), Stepping::rk4(1e-3), 200);
    e.set_limits(Limits::PANDA, false).unwrap();
    e.set_margin(margin).unwrap();
    let appear = 0.2;
    let leave = 1.2;
    let mut x_at_appear = None;
    let r = run(&mut e, std::slice::from_ref(&block), 6.0, |e, t| {
        if (t - appear).abs() < 1e-9 {
            e.set_obstacles([(&block, 0.0)]).unwrap();
            x_at_appear = Some(e.last().0[0]);
        }
        if (t - leave).abs() < 1e-9 {
            e.set_obstacles(std::iter::empty()).unwrap();
        }
    });
    // It was far enough away to brake: the surface 0.65 m ahead of the origin, the robot short of it.
    let x0 = x_at_appear.expect("the block appeared");
    assert!(x0 < 0.4, "the robot was at {x0} m when the block appeared");
    assert_eq!(r.collisions, 0);
    assert!(r.blocked > 0, "never blocked");
    // While the block was there (it is measured over the whole run: after it left the robot passes through).
    let before_leave: Vec<f64> =
        r.x.chunks(2).take((leave / e.dt()).round() as usize).map(|c| c[0]).collect();
    let furthest = before_leave.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    assert!(
        furthest <= 0.75 - 0.1 - margin + 1e-9,
        "came to x = {furthest}, the margin starts at {}",
        0.65 - margin
    );
    assert_eq!(r.outcome, Outcome::GoalReached);
}

/// Where the field keeps the robot away (an obstacle beside a straight reach), the margin changes only the shapes the
/// potentials act on: the robot goes round without ever braking for it, keeps the margin, and arrives.
#[test]
fn a_field_that_keeps_the_margin_is_never_braked() {
    let p = reach([1.0, 0.0], 1.0);
    let side = ball("side", [0.5, 0.12], 0.1);
    let avoid =
        Avoidance::new(Method::DynamicVolumetric(DynamicVolumetric { lambda: 1.0, beta: 2.0, eta: 1.0 }));
    let margin = 0.01;
    let mut e = alone(&p, Scene::with_obstacles(vec![side.clone()], avoid, 0), Stepping::rk4(1e-3), 200);
    e.set_limits(Limits::PANDA, false).unwrap();
    e.set_margin(margin).unwrap();
    let r = run(&mut e, &[side], 5.0, |_, _| {});
    assert_eq!((r.blocked, r.collisions), (0, 0));
    assert!(r.clearance >= margin, "clearance {}", r.clearance);
    assert_eq!(r.outcome, Outcome::GoalReached);
}

#[test]
fn a_margin_must_be_finite_and_not_negative() {
    let mut e = alone(&reach([1.0, 0.0], 1.0), Scene::empty(), Stepping::rk4(1e-3), 20);
    for bad in [-0.1, f64::NAN, f64::INFINITY] {
        assert!(e.set_margin(bad).is_err(), "{bad}");
    }
    e.set_margin(0.0).unwrap();
}

/// Each stretch's reported clearance is the smallest exact distance over its points (within the exact band), though
/// the exact distance is computed at few of them: a reach past a long, moving ellipse.
#[test]
fn the_reported_clearance_is_the_exact_minimum_over_the_points() {
    let p = reach([1.0, 0.0], 1.0);
    let shape = Shape::Superquadric(Superquadric::ellipsoid(vec![0.3, 0.05]).unwrap());
    let long = Obstacle::new("long", shape, vec![0.5, 0.15], None, Some(vec![0.0, -0.02])).unwrap();
    let mut e = alone(&p, Scene::empty(), Stepping::rk4(1e-3), 200);
    e.set_obstacles([(&long, 0.0)]).unwrap();
    let mut checked = 0;
    while e.time() < 1.5 {
        let s = e.advance(10).unwrap();
        let exact = (0..s.x.len() / 2)
            .map(|k| signed_distance_world(&long, &s.x[2 * k..2 * k + 2], s.start_time + k as f64 * e.dt()))
            .fold(f64::INFINITY, f64::min);
        if exact < super::clearance::EXACT_WITHIN {
            assert!((s.min_clearance[0] - exact).abs() < 1e-9, "{} against {exact}", s.min_clearance[0]);
            checked += 1;
        } else {
            assert!(s.min_clearance[0] <= exact + 1e-9);
        }
    }
    assert!(checked > 50, "{checked} stretches within the exact band");
}
