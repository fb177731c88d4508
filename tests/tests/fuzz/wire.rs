//! The wire's decoders and conversions (dmp-proto): Zenoh obstacle payloads (JSON and protobuf), robot states, key
//! parsing, and every message's conversion to the engine. None may panic; whatever they accept is finite.

use proptest::prelude::*;
use proptest::test_runner::TestCaseResult;

use dmp::Isopotential;
use dmp_proto::v1;
use dmp_proto::{codec, keys, learning, obstacle, obstacle_json, payload, primitive, robot_state};

use crate::mutate::{Mutated, mutated};
use crate::runner::fuzz;
use crate::values::{
    self, demonstration, learn_parameters, obstacle as any_obstacle, robot_state as any_state,
};

/// Fails the case with `what` unless every number of `v` is finite.
pub fn all_finite(what: &str, v: &[f64]) -> TestCaseResult {
    match v.iter().position(|x| !x.is_finite()) {
        None => Ok(()),
        Some(i) => Err(TestCaseError::fail(format!("{what}[{i}] = {} was accepted", v[i]))),
    }
}

/// Encoding names a sample may carry.
const ENCODINGS: &[&str] = &[
    "application/protobuf",
    "application/protobuf;dmp.v1.Obstacle",
    "application/json",
    "text/json",
    "zenoh/bytes",
    "",
    ";",
    "application/json;x",
];

/// Valid obstacle payloads, the seeds of the mutations: JSON ones, then protobuf ones.
fn obstacle_seeds() -> Vec<Vec<u8>> {
    let json = [
        r#"{"center": [0.1, 0.2], "semi_axes": [0.3, 0.2], "exponents": [1, 2], "ttl_s": 2.5}"#,
        r#"{"id": "a", "center": [0.5, 0.5, 0.1], "semi_axes": [0.3, 0.2, 0.1], "nested": {"n": 1, "m": 2}}"#,
        r#"{"center": [0, 0], "semi_axes": [0.2, 0.1], "rotation": [[0, -1], [1, 0]], "velocity": [0.1, 0],
            "margin": 0.05}"#,
    ];
    let ball = v1::Obstacle {
        id: "a".into(),
        shape: Some(v1::obstacle::Shape::Solid(v1::SolidPrimitive { r#type: 2, dimensions: vec![0.1] })),
        center: vec![0.0; 3],
        ttl_s: 1.0,
        ..Default::default()
    };
    let ellipse = v1::Obstacle {
        id: String::new(),
        shape: Some(v1::obstacle::Shape::Superquadric(v1::Superquadric {
            semi_axes: vec![0.3, 0.2],
            exponents: vec![1.0, 2.0],
        })),
        center: vec![0.1, 0.2],
        rotation: vec![0.0, -1.0, 1.0, 0.0],
        velocity: vec![0.1, 0.0],
        margin: 0.01,
        ttl_s: 0.0,
    };
    let mut seeds: Vec<Vec<u8>> = json.iter().map(|s| s.as_bytes().to_vec()).collect();
    seeds.push(codec::encode(&ball));
    seeds.push(codec::encode(&ellipse));
    seeds
}

/// One obstacle payload of a fuzz case.
#[derive(Debug, Clone)]
pub enum ObstaclePayload {
    /// Any bytes.
    Raw(Vec<u8>),
    /// A valid payload, mutated.
    Mutated(Mutated),
    /// A structured message, encoded.
    Message(v1::Obstacle),
    /// A structured message as JSON (numbers JSON cannot hold become `null`).
    Json(v1::Obstacle),
}

/// The bytes of a payload.
fn payload_bytes(p: &ObstaclePayload, seeds: &[Vec<u8>]) -> Vec<u8> {
    match p {
        ObstaclePayload::Raw(b) => b.clone(),
        ObstaclePayload::Mutated(m) => m.bytes(seeds),
        ObstaclePayload::Message(o) => codec::encode(o),
        ObstaclePayload::Json(o) => obstacle_json::obstacle_to_json(o).to_string().into_bytes(),
    }
}

/// Checks an engine obstacle: finite placement and shape, and a defined potential at its centre.
fn check_engine_obstacle(o: &dmp::Obstacle) -> TestCaseResult {
    all_finite("center", o.center())?;
    all_finite("velocity", o.velocity())?;
    all_finite("semi_axes", o.shape().semi_axes())?;
    prop_assert!(o.shape().semi_axes().iter().all(|a| *a > 0.0), "non-positive semi-axis accepted: {o:?}");
    let v = o.shape().value(&vec![0.0; o.dim()]);
    prop_assert!(!v.is_nan(), "the potential at the centre is NaN: {o:?}");
    Ok(())
}

/// The checks of one obstacle payload under `encoding`, for the key's `id`.
pub fn check_obstacle_payload(encoding: &str, bytes: &[u8], id: &str) -> TestCaseResult {
    let Ok(o) = payload::decode_obstacle(encoding, bytes, id) else { return Ok(()) };
    prop_assert_eq!(&o.id, id);
    check_obstacle_message(&o)
}

/// The checks of an obstacle message: its engine form, and the JSON round trip of what the engine accepts.
pub fn check_obstacle_message(o: &v1::Obstacle) -> TestCaseResult {
    let _ = obstacle_json::obstacle_to_json(o);
    let Ok(engine) = obstacle::obstacle_to_engine(o) else { return Ok(()) };
    check_engine_obstacle(&engine)?;
    prop_assert!(o.margin.is_finite() && o.ttl_s.is_finite());
    if matches!(o.shape, Some(v1::obstacle::Shape::Solid(_))) || o.id.is_empty() {
        return Ok(());
    }
    let json = obstacle_json::obstacle_to_json(o).to_string();
    let back = obstacle_json::obstacle_from_json_bytes(json.as_bytes(), &o.id).map_err(|e| {
        TestCaseError::fail(format!("the JSON of an accepted obstacle is refused: {e}: {json}"))
    })?;
    prop_assert_eq!(&back, o, "JSON round trip of {}", json);
    Ok(())
}

fn obstacle_payload() -> impl Strategy<Value = ObstaclePayload> {
    let ids: &'static [&'static str] = &["a", "b"];
    prop_oneof![
        1 => proptest::collection::vec(any::<u8>(), 0..64).prop_map(ObstaclePayload::Raw),
        1 => "\\PC{0,40}".prop_map(|s| ObstaclePayload::Raw(s.into_bytes())),
        4 => mutated(5).prop_map(ObstaclePayload::Mutated),
        3 => any_obstacle(ids).prop_map(ObstaclePayload::Message),
        3 => any_obstacle(ids).prop_map(ObstaclePayload::Json),
    ]
}

#[test]
fn fuzz_obstacle_payloads() {
    let seeds = obstacle_seeds();
    let ids = prop_oneof![4 => Just("a".to_owned()), 1 => values::name(&["b"])];
    let strategy = (obstacle_payload(), proptest::sample::select(ENCODINGS), ids);
    fuzz("obstacle_payloads", 3000, 500, strategy, |(p, encoding, id)| {
        check_obstacle_payload(encoding, &payload_bytes(&p, &seeds), &id)
    });
}

/// The checks of one robot-state payload.
pub fn check_robot_state_payload(bytes: &[u8], id: &str) -> TestCaseResult {
    let Ok((state, footprint)) = payload::decode_robot_state(bytes, id) else { return Ok(()) };
    prop_assert_eq!(&state.robot_id, id);
    check_accepted_state(&state, footprint.as_ref())
}

fn check_accepted_state(state: &v1::RobotState, footprint: Option<&dmp::Shape>) -> TestCaseResult {
    prop_assert!(state.stamp_unix_s.is_finite());
    all_finite("position", &state.position)?;
    all_finite("velocity", &state.velocity)?;
    prop_assert!(state.velocity.is_empty() || state.velocity.len() == state.position.len());
    if let Some(f) = footprint {
        prop_assert_eq!(f.dim(), state.position.len());
        all_finite("footprint.semi_axes", f.semi_axes())?;
    }
    Ok(())
}

#[test]
fn fuzz_robot_states() {
    let ids: &'static [&'static str] = &["r1"];
    let state = v1::RobotState {
        robot_id: "r1".into(),
        stamp_unix_s: 1.7e9,
        position: vec![0.1, 0.2, 0.3],
        velocity: vec![0.0; 3],
        footprint: Some(v1::Superquadric { semi_axes: vec![0.2; 3], exponents: vec![1.0, 2.0, 1.0] }),
        ..Default::default()
    };
    let seeds =
        vec![codec::encode(&state), codec::encode(&v1::RobotState { robot_id: String::new(), ..state })];
    let strategy = prop_oneof![
        1 => proptest::collection::vec(any::<u8>(), 0..64).prop_map(|b| (b, None, None)),
        3 => mutated(seeds.len()).prop_map(|m| (Vec::new(), Some(m), None)),
        3 => any_state(ids).prop_map(|s| (Vec::new(), None, Some(s))),
    ];
    fuzz("robot_states", 3000, 500, strategy, |(raw, m, s)| {
        if let Some(s) = &s {
            if let Ok(footprint) = robot_state::check_robot_state(s) {
                check_accepted_state(s, footprint.as_ref())?;
            }
            return check_robot_state_payload(&codec::encode(s), "r1");
        }
        let bytes = m.map_or(raw, |m| m.bytes(&seeds));
        check_robot_state_payload(&bytes, "r1")
    });
}

/// The checks of a key and a name: parsing never panics, and valid names make keys that parse back to them.
pub fn check_key(key: &str, cell: &str, id: &str) -> TestCaseResult {
    let _ = keys::parse_obstacle_key(key);
    let _ = keys::parse_robot_state_key(key);
    let _ = keys::check_name("cell", key);
    if keys::check_name("cell", cell).is_ok() && keys::check_name("id", id).is_ok() {
        let names = keys::KeyNames { cell, id };
        let (obstacle, state) = (keys::obstacle_key(cell, id), keys::robot_state_key(cell, id));
        prop_assert_eq!(keys::parse_obstacle_key(&obstacle), Some(names));
        prop_assert_eq!(keys::parse_robot_state_key(&state), Some(names));
    }
    Ok(())
}

#[test]
fn fuzz_keys() {
    let key = prop_oneof![
        "\\PC{0,30}",
        "dmp/[a-z*/]{0,4}/(obstacles|robots)/[a-z/*]{0,4}(/state)?",
        "[dmp/obstacles]{0,20}",
    ];
    let strategy = (key, values::name(&["c1"]), values::name(&["a"]));
    fuzz("keys", 2000, 1000, strategy, |(key, cell, id)| check_key(&key, &cell, &id));
}

/// The checks of a primitive message: an accepted one is finite and has consistent sizes.
pub fn check_primitive(m: &v1::Primitive) -> TestCaseResult {
    let Ok(p) = primitive::primitive_from_proto(m) else { return Ok(()) };
    for (what, v) in [("k", &p.k), ("d", &p.d), ("start", &p.start), ("goal", &p.goal)] {
        all_finite(what, v)?;
        prop_assert_eq!(v.len(), p.dim, "{} of a primitive of dimension {}", what, p.dim);
    }
    prop_assert!(p.alpha.is_finite() && p.tau.is_finite());
    prop_assert_eq!(p.weights.len(), p.dim);
    for w in &p.weights {
        all_finite("weights", w)?;
        prop_assert_eq!(w.len(), p.n_basis + 1);
    }
    prop_assert_eq!(primitive::primitive_from_proto(&primitive::primitive_to_proto(&p)).ok(), Some(p));
    Ok(())
}

/// The checks of a demonstration message and learning parameters.
pub fn check_demonstration(d: &v1::Demonstration, params: Option<&v1::LearnParameters>) -> TestCaseResult {
    let _ = learning::learn_config_from_proto(params);
    let Ok(demo) = learning::demonstration_from_proto(d) else { return Ok(()) };
    all_finite("t", demo.times())?;
    prop_assert!(demo.times().windows(2).all(|w| w[0] < w[1]));
    for row in demo.positions() {
        all_finite("positions", row)?;
        prop_assert_eq!(row.len(), demo.dim());
    }
    Ok(())
}

/// The checks of an avoidance message: converting never panics, and a validated method has finite gains.
pub fn check_avoidance(a: Option<&v1::Avoidance>, dim: usize) -> TestCaseResult {
    let Ok((avoidance, samples)) = dmp_proto::avoidance::avoidance_from_proto(a, dmp::Avoidance::NONE) else {
        return Ok(());
    };
    prop_assert!((1..=dmp_proto::avoidance::MAX_POINT_SAMPLES).contains(&samples));
    if avoidance.method.validate("avoidance", dim).is_ok() {
        let back = dmp_proto::avoidance::avoidance_to_proto(&avoidance, samples);
        let gains: Vec<f64> = match back.method {
            Some(v1::avoidance::Method::StaticPoint(p)) => vec![p.eta, p.p0],
            Some(v1::avoidance::Method::DynamicPoint(p)) => vec![p.lambda, p.beta],
            Some(v1::avoidance::Method::SteeringAngle(p)) => vec![p.gamma, p.beta],
            Some(v1::avoidance::Method::StaticVolumetric(p)) => vec![p.a, p.eta],
            Some(v1::avoidance::Method::DynamicVolumetric(p)) => vec![p.lambda, p.beta, p.eta],
            Some(v1::avoidance::Method::None(_)) | None => vec![],
        };
        all_finite("gains", &gains)?;
    }
    Ok(())
}

/// A message of some v1 type from raw or mutated bytes, decoded as every type and converted.
pub fn check_any_message(bytes: &[u8]) -> TestCaseResult {
    if let Ok(m) = codec::decode::<v1::Primitive>(bytes) {
        check_primitive(&m)?;
    }
    if let Ok(m) = codec::decode::<v1::LearnRequest>(bytes)
        && let Some(d) = &m.demonstration
    {
        check_demonstration(d, m.parameters.as_ref())?;
    }
    if let Ok(m) = codec::decode::<v1::Obstacle>(bytes) {
        check_obstacle_message(&m)?;
    }
    if let Ok(m) = codec::decode::<v1::MotionSpec>(bytes) {
        check_avoidance(m.avoidance.as_ref(), m.start.len())?;
        for o in &m.extra_obstacles {
            check_obstacle_message(o)?;
        }
    }
    if let Ok(m) = codec::decode::<v1::SessionRequest>(bytes)
        && let Some(v1::session_request::Message::State(s)) = &m.message
        && let Ok(f) = robot_state::check_robot_state(s)
    {
        check_accepted_state(s, f.as_ref())?;
    }
    Ok(())
}

#[test]
fn fuzz_messages_to_engine() {
    let seeds: Vec<Vec<u8>> = vec![
        codec::encode(&primitive::primitive_to_proto(
            &dmp::Primitive::straight_line(5, 4.0, vec![100.0; 2], None, 1.0, vec![0.0; 2], vec![1.0, 0.5])
                .expect("a line"),
        )),
        codec::encode(&v1::LearnRequest {
            robot_id: "r".into(),
            name: "p".into(),
            demonstration: Some(v1::Demonstration {
                t: vec![0.0, 0.5, 1.0],
                positions: vec![0.0, 0.5, 1.0],
                dim: 1,
                ..Default::default()
            }),
            parameters: Some(v1::LearnParameters { n_basis: 5, k: vec![100.0], d: vec![], alpha: 4.0 }),
        }),
    ];
    let strategy = prop_oneof![
        2 => values::primitive().prop_map(|p| Case::Primitive(Box::new(p))),
        2 => (demonstration(), learn_parameters()).prop_map(|(d, p)| Case::Demonstration(d, p)),
        2 => (values::avoidance(), 1..=3usize).prop_map(|(a, d)| Case::Avoidance(a, d)),
        1 => proptest::collection::vec(any::<u8>(), 0..64).prop_map(Case::Bytes),
        2 => mutated(seeds.len()).prop_map(Case::Mutated),
    ];
    fuzz("messages_to_engine", 3000, 500, strategy, |case| match case {
        Case::Primitive(p) => check_primitive(&p),
        Case::Demonstration(d, p) => check_demonstration(&d, p.as_ref()),
        Case::Avoidance(a, d) => check_avoidance(a.as_ref(), d),
        Case::Bytes(b) => check_any_message(&b),
        Case::Mutated(m) => check_any_message(&m.bytes(&seeds)),
    });
}

/// One case of the message conversions.
#[derive(Debug, Clone)]
pub enum Case {
    /// A primitive message.
    Primitive(Box<v1::Primitive>),
    /// A demonstration and learning parameters.
    Demonstration(v1::Demonstration, Option<v1::LearnParameters>),
    /// An avoidance in a dimension.
    Avoidance(Option<v1::Avoidance>, usize),
    /// Any bytes, decoded as every message.
    Bytes(Vec<u8>),
    /// A valid encoding, mutated.
    Mutated(Mutated),
}
