//! `q` and `-q` are the same orientation: flipped demonstration samples, a goal or a start given as `-q`, and no
//! 360° detour.

use std::f64::consts::FRAC_PI_2;

use dmp::orientation::quaternion::angle_between;
use dmp::{LearnConfig, OrientationDemonstration, learn_orientation};
use nalgebra::UnitQuaternion;

use super::fixtures::{SINGLE, changing_axis, motion, new_motion, run, samples, times, travelled};

fn opposite(q: &UnitQuaternion<f64>) -> UnitQuaternion<f64> {
    UnitQuaternion::new_unchecked(-q.into_inner())
}

#[test]
fn flipped_demonstration_samples_are_learned_as_the_others() {
    let q = samples(changing_axis);
    // A recorder that keeps w >= 0, and one that flips every seventh sample and the goal.
    let positive_w: Vec<[f64; 4]> = q.iter().map(|q| if q[3] < 0.0 { q.map(|v| -v) } else { *q }).collect();
    let last = q.len() - 1;
    let flipped: Vec<[f64; 4]> =
        q.iter().enumerate().map(|(i, q)| if i % 7 == 3 || i == last { q.map(|v| -v) } else { *q }).collect();
    let learn = |q: Vec<[f64; 4]>| {
        learn_orientation(&OrientationDemonstration::new(times(), q).unwrap(), &LearnConfig::paper()).unwrap()
    };
    let reference = learn(q.clone());
    for (name, other) in [("w >= 0", learn(positive_w)), ("every seventh flipped", learn(flipped))] {
        assert_eq!(other.dmp, reference.dmp, "{name}");
        let goal = other.goal_orientation().unwrap();
        assert!(angle_between(&goal, &reference.goal_orientation().unwrap()) < 1e-12, "{name}");
    }
}

#[test]
fn a_goal_and_its_opposite_give_the_same_motion() {
    let p = &*SINGLE;
    for m in [dmp::OrientationMotion::of(p).unwrap(), new_motion(p)] {
        let a = run(p, &m, 2.0 * m.tau);
        let b = run(p, &motion(m.start, opposite(&m.goal), m.tau), 2.0 * m.tau);
        assert_eq!(a, b);
    }
}

#[test]
fn no_run_turns_the_long_way() {
    // The demonstration turns 90°; every sign of its start and goal turns about 90° too, not 270°.
    let p = &*SINGLE;
    let (start, goal) = (p.start_orientation().unwrap(), p.goal_orientation().unwrap());
    for (name, s, g) in [
        ("as learned", start, goal),
        ("goal as -q", start, opposite(&goal)),
        ("start as -q", opposite(&start), goal),
        ("both as -q", opposite(&start), opposite(&goal)),
    ] {
        let tr = run(p, &motion(s, g, p.dmp.tau), 2.0 * p.dmp.tau);
        let turned = travelled(&tr);
        eprintln!("{name}: turned {:.3}° for a direct angle of 90°", turned.to_degrees());
        assert!((turned - FRAC_PI_2).abs() <= 0.01 * FRAC_PI_2, "{name}: {}°", turned.to_degrees());
        assert!(angle_between(&tr.orientation(tr.len() - 1), &g).to_degrees() <= 0.1, "{name}");
    }
}
