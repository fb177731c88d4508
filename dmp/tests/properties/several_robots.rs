//! Several robots on one phase.

use std::f64::consts::PI;

use dmp::{Agent, Avoidance, Contact, Method, Motion, Primitive, RepulsiveField, Rollout, Scene};
use proptest::prelude::*;

use crate::fixtures::{config, dist, dynamic_volumetric, last_position, run, superquadric};

/// Three robots on a circle of radius 1, each going to the point opposite its start turned by `skew`: the
/// three straight paths pass close to the centre at the same time. Everything is turned by `turn`.
fn three_robots(turn: f64, skew: f64, robot_avoidance: Method) -> (Primitive, RepulsiveField) {
    let (mut start, mut goal) = (Vec::new(), Vec::new());
    for i in 0..3 {
        let a = turn + 2.0 * PI * i as f64 / 3.0;
        let b = a + PI + skew;
        start.extend([a.cos(), a.sin()]);
        goal.extend([b.cos(), b.sin()]);
    }
    let p = Primitive::straight_line(50, 4.0, vec![1050.0; 6], None, 1.0, start, goal).unwrap();
    let agents = (0..3)
        .map(|i| Agent {
            id: format!("r{i}"),
            dims: vec![2 * i, 2 * i + 1],
            footprint: Some(superquadric(&[0.3, 0.3], &[1.0, 1.0])),
        })
        .collect();
    let scene = Scene {
        obstacles: Vec::new(),
        avoidance: Avoidance::NONE,
        agents,
        robot_avoidance: Avoidance::new(robot_avoidance),
        point_samples: 50,
    };
    (p, RepulsiveField::new(scene, 6).unwrap())
}

fn robot_contacts(r: &Rollout) -> usize {
    r.contacts.iter().filter(|(_, c)| matches!(c, Contact::Robot { .. })).count()
}

fn min_pair_distance(r: &Rollout) -> f64 {
    let t = &r.trajectory;
    let mut min = f64::INFINITY;
    for k in 0..t.len() {
        let x = t.position(k);
        for i in 0..3 {
            for j in i + 1..3 {
                min = min.min(dist(&x[2 * i..2 * i + 2], &x[2 * j..2 * j + 2]));
            }
        }
    }
    min
}

proptest! {
    #![proptest_config(config(8))]

    #[test]
    fn three_crossing_robots_avoid_each_other_and_arrive(
        turn in 0.0f64..(2.0 * PI),
        skew_deg in 5.0f64..12.0,
    ) {
        three_crossing_robots_avoid_each_other_and_arrive_case(turn, skew_deg)?;
    }
}

fn three_crossing_robots_avoid_each_other_and_arrive_case(
    turn: f64,
    skew_deg: f64,
) -> Result<(), TestCaseError> {
    let skew = skew_deg.to_radians();
    let (p, blind) = three_robots(turn, skew, Method::None);
    let collide = run(&p, &Motion::of(&p), &blind, 1e-3, 3.0);
    prop_assert!(robot_contacts(&collide) > 0, "the paths do not cross: nothing to avoid");
    let (p, careful) = three_robots(turn, skew, dynamic_volumetric(60.0, 2.0, 0.2));
    let r = run(&p, &Motion::of(&p), &careful, 1e-3, 3.0);
    let (closest_blind, closest) = (min_pair_distance(&collide), min_pair_distance(&r));
    eprintln!(
        "three robots, skew {skew_deg:.1} deg: closest centres {closest_blind:.3} without avoidance, \
         {closest:.3} with"
    );
    prop_assert!(r.trajectory.is_finite());
    prop_assert_eq!(robot_contacts(&r), 0, "{:?}", r.contacts.first());
    prop_assert!(closest > 0.3);
    prop_assert!(r.stalls.is_empty(), "{:?}", r.stalls);
    let end = last_position(&r);
    for i in 0..3 {
        let d = dist(&end[2 * i..2 * i + 2], &p.goal[2 * i..2 * i + 2]);
        prop_assert!(d < 1e-3, "robot {} ends {} from its goal", i, d);
    }
    Ok(())
}
