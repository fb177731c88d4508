//! Bad inputs give typed errors naming the field, never a panic.

use dmp::{
    DmpError, InvalidInput, LearnConfig, OrientationDemonstration, OrientationMotion, OrientationRun,
    learn_orientation, rollout_orientation,
};
use nalgebra::Vector3;

use super::fixtures::{SINGLE, new_motion};

/// The field and rule of an [`InvalidInput`], or a panic naming what came instead.
fn invalid<T: std::fmt::Debug>(r: Result<T, DmpError>) -> InvalidInput {
    match r {
        Err(DmpError::Invalid(i)) => i,
        other => panic!("expected an invalid input, got {other:?}"),
    }
}

const ID: [f64; 4] = [0.0, 0.0, 0.0, 1.0];

#[test]
fn bad_demonstrations_are_refused() {
    let t = vec![0.0, 0.5, 1.0, 1.5];
    let with = |i: usize, q: [f64; 4]| {
        let mut all = vec![ID; 4];
        all[i] = q;
        OrientationDemonstration::new(t.clone(), all)
    };
    for (what, result, field, rule) in [
        ("a norm of 1.1", with(2, [0.0, 0.0, 0.0, 1.1]), "demonstration.q[2]", "unit quaternion"),
        ("a null quaternion", with(1, [0.0; 4]), "demonstration.q[1]", "unit quaternion"),
        ("a NaN", with(3, [f64::NAN, 0.0, 0.0, 1.0]), "demonstration.q[3]", "finite"),
        ("an infinity", with(0, [0.0, f64::INFINITY, 0.0, 1.0]), "demonstration.q[0]", "finite"),
        (
            "3 quaternions for 4 times",
            OrientationDemonstration::new(t.clone(), vec![ID; 3]),
            "demonstration.q",
            "one quaternion per sample",
        ),
        (
            "2 samples",
            OrientationDemonstration::new(vec![0.0, 1.0], vec![ID; 2]),
            "demonstration.t",
            "at least 3",
        ),
        (
            "a time going back",
            OrientationDemonstration::new(vec![0.0, 1.0, 0.5], vec![ID; 3]),
            "demonstration.t[2]",
            "increasing",
        ),
        (
            "a NaN time",
            OrientationDemonstration::new(vec![0.0, f64::NAN, 1.0], vec![ID; 3]),
            "demonstration.t[1]",
            "finite",
        ),
    ] {
        let e = invalid(result);
        assert_eq!(e.field, field, "{what}: {e}");
        assert!(e.rule.contains(rule), "{what}: {e}");
    }
}

#[test]
fn bad_learning_settings_are_refused() {
    let demo = OrientationDemonstration::new(vec![0.0, 0.5, 1.0], vec![ID; 3]).unwrap();
    let config = LearnConfig { k: vec![1.0, 2.0], ..LearnConfig::paper() };
    assert_eq!(invalid(learn_orientation(&demo, &config)).field, "dmp.K");
    let config = LearnConfig { n_basis: 0, ..LearnConfig::paper() };
    assert!(invalid(learn_orientation(&demo, &config)).field.starts_with("dmp."));
}

#[test]
fn bad_motions_and_steps_are_refused() {
    let p = &*SINGLE;
    for (what, result, field) in [
        ("a non-unit start", OrientationMotion::new([0.0, 0.0, 0.5, 0.5], ID, 1.0), "start"),
        ("a NaN goal", OrientationMotion::new(ID, [0.0, 0.0, 0.0, f64::NAN], 1.0), "goal"),
        ("a null tau", OrientationMotion::new(ID, ID, 0.0), "tau"),
        ("an infinite tau", OrientationMotion::new(ID, ID, f64::INFINITY), "tau"),
    ] {
        let e = result.expect_err(what);
        assert_eq!(e.field, field, "{what}: {e}");
    }
    let m = new_motion(p);
    for (what, dt, steps, field) in [
        ("a null step", 0.0, 10, "rollout.dt"),
        ("a NaN step", f64::NAN, 10, "rollout.dt"),
        ("too many steps", 1e-3, 2_000_000, "rollout.duration"),
        ("an unstable step", 0.5, 10, "rollout.dt"),
    ] {
        let e = invalid(rollout_orientation(p, &m, dt, steps));
        assert_eq!(e.field, field, "{what}: {e}");
    }
    let bad_tau = OrientationMotion { tau: -1.0, ..m.clone() };
    assert_eq!(invalid(OrientationRun::new(p, &bad_tau)).field, "tau");
    let spin = Vector3::new(f64::NAN, 0.0, 0.0);
    assert_eq!(invalid(OrientationRun::moving(p, &m, spin)).field, "omega");
    let mut broken = p.clone();
    broken.goal = [0.0, 0.0, 0.0, 2.0];
    assert_eq!(invalid(OrientationRun::new(&broken, &m)).field, "goal");
    broken = p.clone();
    broken.dmp.goal = vec![0.1, 0.0, 0.0];
    assert_eq!(invalid(OrientationRun::new(&broken, &m)).field, "dmp.goal");
}
