//! Guard rails: never NaN or infinity, contacts and stalls reported.

use std::f64::consts::PI;

use dmp::{Avoidance, Contact, Method, Motion, Obstacle, Perturbation, Primitive, RepulsiveField, Scene};
use proptest::prelude::*;

use crate::fixtures::{
    PAPER, config, dist, dynamic_point, dynamic_volumetric, ellipsoid, empty_field, field, last_position,
    norm, obstacle_contacts, paper_ellipse, paper_methods, run, static_volumetric, superquadric,
};

/// All five methods, and the two dynamic ones with beta = 1 (where they jump at the switch).
fn all_methods() -> Vec<Method> {
    let mut m = paper_methods().to_vec();
    m.push(dynamic_point(0.2, 1.0));
    m.push(dynamic_volumetric(10.0, 1.0, 0.5));
    m
}

#[test]
fn a_start_inside_an_obstacle_gives_a_finite_trajectory_and_a_contact() {
    let p = &*PAPER;
    let shape = superquadric(&[0.2, 0.15], &[1.0, 1.0]);
    let obstacles = [
        // Off-centre around the start, still.
        Obstacle::new("still", shape.clone(), vec![0.05, -0.03], None, None).unwrap(),
        // Centred exactly on the start, where grad C = 0.
        Obstacle::new("centred", shape.clone(), vec![0.0, 0.0], None, None).unwrap(),
        // Around the start and moving along with the robot's first direction of motion.
        Obstacle::new("moving", shape, vec![0.1, 0.0], None, Some(vec![0.5, 0.2])).unwrap(),
    ];
    for method in all_methods() {
        for o in &obstacles {
            let f = field(vec![o.clone()], method, 2);
            let r = run(p, &Motion::of(p), &f, 1e-3, 1.0);
            let label = format!("{} in {}", method.name(), o.id());
            assert!(r.trajectory.is_finite(), "{label}: not finite");
            let (row, contact) = r.contacts.first().copied().unwrap_or_else(|| panic!("{label}: no contact"));
            assert_eq!(row, 0, "{label}");
            match contact {
                Contact::Obstacle { agent: 0, obstacle: 0, c } => assert!(c <= 0.0, "{label}: C = {c}"),
                other => panic!("{label}: {other:?}"),
            }
            assert!(r.contacts.iter().all(|(_, c)| matches!(c, Contact::Obstacle { .. })));
        }
    }
}

#[test]
fn a_robot_at_rest_feels_no_dynamic_term_and_stays_finite() {
    // start = goal and no forcing term: only a repulsive term could move the robot.
    let p = Primitive::straight_line(50, 4.0, vec![1050.0; 2], None, 1.0, vec![0.0, 0.0], vec![0.0, 0.0])
        .unwrap();
    let near = ellipsoid("near", &[0.25, 0.0], &[0.2, 0.2]);
    for method in [
        dynamic_point(0.2, 2.0),
        dynamic_point(0.2, 1.0),
        paper_methods()[2],
        dynamic_volumetric(10.0, 2.0, 0.5),
    ] {
        let r = run(&p, &Motion::of(&p), &field(vec![near.clone()], method, 2), 1e-3, 0.5);
        assert!(r.trajectory.is_finite(), "{}", method.name());
        assert!(r.trajectory.x.iter().all(|&x| x == 0.0), "{}: a robot at rest moved", method.name());
    }
    // The static terms do push it, so the test above could see a motion.
    let r = run(&p, &Motion::of(&p), &field(vec![near.clone()], static_volumetric(10.0, 1.0), 2), 1e-3, 0.5);
    assert!(last_position(&r)[0] < -1e-3);
    // An obstacle coming at a robot at rest: the relative velocity is not zero, the dynamic terms push it
    // away.
    let coming = Obstacle::new(
        "coming",
        superquadric(&[0.2, 0.2], &[1.0, 1.0]),
        vec![0.8, 0.0],
        None,
        Some(vec![-1.0, 0.0]),
    )
    .unwrap();
    for method in
        [dynamic_point(0.2, 2.0), dynamic_volumetric(10.0, 2.0, 0.5), dynamic_volumetric(10.0, 1.0, 0.5)]
    {
        let r = run(&p, &Motion::of(&p), &field(vec![coming.clone()], method, 2), 1e-3, 1.0);
        assert!(r.trajectory.is_finite(), "{}", method.name());
        let pushed = (0..r.trajectory.len()).map(|k| r.trajectory.position(k)[0]).fold(0.0, f64::min);
        assert!(pushed < -1e-2, "{}: pushed only to {pushed}", method.name());
    }
    // The steering angle rotates the robot's own velocity: at rest it does nothing, and the obstacle runs it
    // over.
    let r = run(&p, &Motion::of(&p), &field(vec![coming], paper_methods()[2], 2), 1e-3, 1.0);
    assert!(r.trajectory.is_finite());
    assert!(obstacle_contacts(&r) > 0);
}

#[test]
fn a_robot_stuck_in_front_of_a_large_disc_is_reported_as_stalled() {
    // Aimed straight through the centre of a disc: by symmetry the static potential only pushes back along
    // the line, and the robot stops where it balances the attraction to the goal.
    let p = Primitive::straight_line(50, 4.0, vec![1050.0; 2], None, 1.0, vec![0.0, 0.0], vec![2.0, 0.0])
        .unwrap();
    let disc = ellipsoid("disc", &[1.0, 0.0], &[0.5, 0.5]);
    let r = run(&p, &Motion::of(&p), &field(vec![disc], static_volumetric(10.0, 1.0), 2), 1e-3, 3.0);
    assert!(r.trajectory.is_finite());
    assert!(r.contacts.is_empty(), "{:?}", r.contacts.first());
    let end = last_position(&r);
    assert!(end[0] < 0.5 && end[1] == 0.0, "ends at {end:?}");
    let &(robot, stall) = r.stalls.first().expect("no stall reported");
    eprintln!(
        "stall: robot {robot} stopped at t = {:.3} s, {:.3} from its goal, at x = {:.3}",
        stall.since, stall.distance, end[0]
    );
    assert_eq!(robot, 0);
    assert!(stall.distance > 1.0 && stall.since < stall.detected_at && stall.detected_at < 3.0);
    // Without the disc it arrives and nothing is reported.
    let free = run(&p, &Motion::of(&p), &empty_field(2), 1e-3, 3.0);
    assert!(free.stalls.is_empty());
    assert!(dist(last_position(&free), &p.goal) < 1e-3);
}

#[test]
fn the_dynamic_terms_are_finite_exactly_at_their_switch_and_jump_there_only_for_beta_1() {
    // A disc of radius 0.2 at the origin (one boundary sample for the point method, at (0.2, 0)). The robot
    // is at `x` with velocity (1, -e): for e = 0 it moves exactly perpendicular to grad C (cos theta = 0, the
    // switch), for e > 0 slightly toward the obstacle.
    let disc = ellipsoid("disc", &[0.0, 0.0], &[0.2, 0.2]);
    let phi = |method: Method, x: [f64; 2], e: f64| {
        let scene = Scene::with_obstacles(vec![disc.clone()], Avoidance::new(method), 1);
        let mut f = RepulsiveField::new(scene, 2).unwrap();
        let mut out = [0.0; 2];
        f.add(0.0, &x, &[1.0, -e], 1.0, &mut out);
        assert!(out.iter().all(|v| v.is_finite()), "{} at e = {e}: {out:?}", method.name());
        norm(&out)
    };
    for (method, x) in [
        (dynamic_volumetric(10.0, 1.0, 0.5), [0.0, 0.5]),
        (dynamic_volumetric(10.0, 2.0, 0.5), [0.0, 0.5]),
        (dynamic_point(0.2, 1.0), [0.2, 0.5]),
        (dynamic_point(0.2, 2.0), [0.2, 0.5]),
    ] {
        let (at, past) = (phi(method, x, 0.0), phi(method, x, 1e-9));
        let beta = match method {
            Method::DynamicVolumetric(p) => p.beta,
            Method::DynamicPoint(p) => p.beta,
            _ => unreachable!(),
        };
        eprintln!("{} beta {beta}: |phi| at the switch {at:.3e}, just past it {past:.3e}", method.name());
        assert_eq!(at, 0.0);
        if beta == 1.0 {
            assert!(past > 1e-2, "{}: no jump for beta = 1 ({past})", method.name());
        } else {
            assert!(past < 1e-6, "{}: jump for beta = 2 ({past})", method.name());
        }
    }
    // Rollouts through the paper's scene cross the switch: finite, and with beta = 1 still no collision.
    let p = &*PAPER;
    for method in [dynamic_point(0.2, 1.0), dynamic_volumetric(10.0, 1.0, 0.5)] {
        let r = run(p, &Motion::of(p), &field(vec![paper_ellipse()], method, 2), 1e-3, 1.0);
        assert!(r.trajectory.is_finite(), "{}", method.name());
        assert!(r.contacts.is_empty(), "{}: {:?}", method.name(), r.contacts.first());
    }
}

/// Points where the terms have a singular or degenerate form: the centre, a boundary sample, the surface,
/// inside.
fn special_point() -> impl Strategy<Value = [f64; 2]> {
    prop_oneof![
        Just([-0.5, 0.7]),
        Just([-0.2, 0.7]),
        Just([-0.5, 0.5]),
        Just([-0.5, 0.6]),
        Just([-0.5 + 0.3 * (2.0 * PI / 50.0).cos(), 0.7 + 0.2 * (2.0 * PI / 50.0).sin()]),
        prop::array::uniform2(-1.5f64..0.5),
    ]
}

fn special_velocity() -> impl Strategy<Value = [f64; 2]> {
    prop_oneof![
        Just([0.0, 0.0]),
        Just([1.0, 0.0]),
        Just([0.0, -1.0]),
        Just([1e-300, 0.0]),
        prop::array::uniform2(-5.0f64..5.0)
    ]
}

proptest! {
    #![proptest_config(config(256))]

    /// Every method, still or moving obstacle, at any point (inside included) and any velocity (zero
    /// included): the term is finite.
    #[test]
    fn every_term_is_finite_everywhere(
        x in special_point(),
        v in special_velocity(),
        velocity in prop_oneof![Just([0.0, 0.0]), prop::array::uniform2(-1.0f64..1.0)],
        t in 0.0f64..1.0,
        tau in 0.5f64..2.0,
    ) {
        every_term_is_finite_everywhere_case(x, v, velocity, t, tau)?;
    }
}

fn every_term_is_finite_everywhere_case(
    x: [f64; 2],
    v: [f64; 2],
    velocity: [f64; 2],
    t: f64,
    tau: f64,
) -> Result<(), TestCaseError> {
    // The paper's ellipse, still or moving.
    let shape = paper_ellipse().shape().clone();
    let o = Obstacle::new("o", shape, vec![-0.5, 0.7], None, Some(velocity.to_vec())).unwrap();
    for method in all_methods() {
        let mut f = field(vec![o.clone()], method, 2);
        let mut out = [0.0; 2];
        f.add(t, &x, &v, tau, &mut out);
        prop_assert!(out.iter().all(|p| p.is_finite()), "{}: {:?}", method.name(), out);
    }
    Ok(())
}
