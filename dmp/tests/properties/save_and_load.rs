//! Save and load.

use dmp::{Motion, Primitive};
use proptest::prelude::*;

use crate::fixtures::{PAPER, config, dynamic_volumetric, field, paper_ellipse, run};

fn assert_same_bits(a: &[f64], b: &[f64]) {
    assert_eq!(a.len(), b.len());
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        assert_eq!(x.to_bits(), y.to_bits(), "entry {i}: {x} vs {y}");
    }
}

fn save_and_load(p: &Primitive) -> Primitive {
    let json = serde_json::to_string(p).unwrap();
    let q: Primitive = serde_json::from_str(&json).unwrap();
    q.validate().unwrap();
    q
}

#[test]
fn a_saved_and_loaded_primitive_replays_bit_for_bit() {
    let p = PAPER.clone();
    let q = save_and_load(&p);
    assert_eq!(p, q);
    for w in [&p.weights, &q.weights] {
        assert!(w.iter().flatten().any(|w| w.fract() != 0.0), "weights with nothing to lose");
    }
    let m = Motion::of(&p);
    let make = || field(vec![paper_ellipse()], dynamic_volumetric(10.0, 2.0, 0.5), 2);
    let a = run(&p, &m, &make(), 1e-3, 1.0);
    let b = run(&q, &Motion::of(&q), &make(), 1e-3, 1.0);
    assert_same_bits(&a.trajectory.x, &b.trajectory.x);
    assert_same_bits(&a.trajectory.xd, &b.trajectory.xd);
    assert_same_bits(&a.trajectory.xdd, &b.trajectory.xdd);
}

#[test]
fn a_loaded_primitive_that_breaks_a_rule_is_refused() {
    let json = serde_json::to_value(&*PAPER).unwrap();
    let broken = |path: &str, value: serde_json::Value| {
        let mut j = json.clone();
        *j.pointer_mut(path).unwrap() = value;
        serde_json::from_value::<Primitive>(j).unwrap()
    };
    assert!(broken("/format_version", 2.into()).validate().is_err());
    assert!(broken("/tau", (-1.0).into()).validate().is_err());
    assert!(broken("/weights/1", serde_json::json!([1.0, 2.0])).validate().is_err());
    assert!(broken("/k", serde_json::json!([1050.0])).validate().is_err());
    assert!(broken("/dim", 3.into()).validate().is_err());
    let mut extra = json.clone();
    extra["comment"] = "hello".into();
    assert!(serde_json::from_value::<Primitive>(extra).is_err());
}

/// Any finite double: normal, subnormal or zero, of either sign.
fn any_finite() -> impl Strategy<Value = f64> {
    prop::num::f64::POSITIVE
        | prop::num::f64::NEGATIVE
        | prop::num::f64::NORMAL
        | prop::num::f64::SUBNORMAL
        | prop::num::f64::ZERO
}

proptest! {
    #![proptest_config(config(64))]

    /// Any finite weights and gains survive a JSON round trip exactly.
    #[test]
    fn every_finite_number_survives_a_json_round_trip(
        weights in prop::collection::vec(any_finite(), 3 * 11),
        k in prop::array::uniform3(1e-3f64..1e6),
        tau in 1e-3f64..1e3,
    ) {
        every_finite_number_survives_a_json_round_trip_case(weights, k, tau)?;
    }
}

fn every_finite_number_survives_a_json_round_trip_case(
    weights: Vec<f64>,
    k: [f64; 3],
    tau: f64,
) -> Result<(), TestCaseError> {
    let mut p =
        Primitive::straight_line(10, 4.0, k.to_vec(), None, tau, vec![0.1, -0.2, 0.3], vec![1.0, 2.0, 3.0])
            .unwrap();
    p.weights = weights.chunks(11).map(|c| c.to_vec()).collect();
    let q = save_and_load(&p);
    for (a, b) in p.weights.iter().flatten().zip(q.weights.iter().flatten()) {
        prop_assert_eq!(a.to_bits(), b.to_bits());
    }
    prop_assert_eq!(p, q);
    Ok(())
}
