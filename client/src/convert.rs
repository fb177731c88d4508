//! Conversions between the wire schema (`dmp_proto::v1`) and the engine or the scenario format, the client's side
//! of `server/src/convert.rs`: the same mappings, so that what the client sends is what the server reads.

use dmp::scenario::{DmpSpec, FootprintSpec, ObstacleSpec};
use dmp::{Avoidance, Method};
use dmp_proto::v1;
use serde_json::{Map, Value, json};

use crate::error::ClientError;

pub use dmp_proto::obstacle_json::{JSON_OBSTACLE_KEYS, JsonObstacle};
pub use dmp_proto::primitive::{primitive_from_proto, primitive_to_proto};

/// The learning parameters of a scenario's `dmp` section (`D = null` sends no damping: critical).
pub fn learn_parameters(spec: &DmpSpec) -> v1::LearnParameters {
    v1::LearnParameters {
        n_basis: spec.n as u32,
        k: spec.k.to_vec(),
        d: spec.d.as_ref().map(|d| d.to_vec()).unwrap_or_default(),
        alpha: spec.alpha,
    }
}

/// The avoidance message of the engine's avoidance; `point_samples` is the boundary sample count of the point
/// methods.
pub fn avoidance_to_proto(a: &Avoidance, point_samples: usize) -> v1::Avoidance {
    use v1::avoidance as pa;
    let method = match a.method {
        Method::None => pa::Method::None(pa::None {}),
        Method::StaticPoint(p) => pa::Method::StaticPoint(pa::StaticPoint { eta: p.eta, p0: p.p0 }),
        Method::DynamicPoint(p) => {
            pa::Method::DynamicPoint(pa::DynamicPoint { lambda: p.lambda, beta: p.beta })
        }
        Method::SteeringAngle(p) => {
            pa::Method::SteeringAngle(pa::SteeringAngle { gamma: p.gamma, beta: p.beta })
        }
        Method::StaticVolumetric(p) => {
            pa::Method::StaticVolumetric(pa::StaticVolumetric { a: p.a, eta: p.eta })
        }
        Method::DynamicVolumetric(p) => pa::Method::DynamicVolumetric(pa::DynamicVolumetric {
            lambda: p.lambda,
            beta: p.beta,
            eta: p.eta,
        }),
    };
    v1::Avoidance {
        method: Some(method),
        ignore_obstacle_velocity: !a.relative_velocity,
        point_samples: point_samples as u32,
    }
}

/// The message of a robot's footprint.
pub fn footprint_to_proto(f: &FootprintSpec) -> v1::Superquadric {
    v1::Superquadric { semi_axes: f.semi_axes.clone(), exponents: f.exponents.clone().unwrap_or_default() }
}

/// The obstacle message of a scenario obstacle, with a margin and a time to live (0: none).
pub fn obstacle_to_proto(s: &ObstacleSpec, margin: f64, ttl_s: f64) -> v1::Obstacle {
    JsonObstacle { spec: s.clone(), margin, ttl_s }.to_proto()
}

/// Parses one JSON obstacle (an object of [`JSON_OBSTACLE_KEYS`]); `field` prefixes the errors (e.g.
/// `obstacles[2]`, or empty).
pub fn obstacle_from_json(value: &Value, field: &str) -> Result<JsonObstacle, ClientError> {
    JsonObstacle::parse(value, field).map_err(|e| ClientError::argument(e.field, e.rule))
}

/// The JSON of an obstacle message, in the scenario format where it has one (a solid primitive is written as
/// `"solid": {"type": "BOX", "dimensions": [..]}`).
pub fn obstacle_json(o: &v1::Obstacle) -> Value {
    let mut m = Map::new();
    m.insert("id".into(), o.id.clone().into());
    m.insert("center".into(), json!(o.center));
    match &o.shape {
        Some(v1::obstacle::Shape::Superquadric(s)) => {
            m.insert("semi_axes".into(), json!(s.semi_axes));
            if !s.exponents.is_empty() {
                m.insert("exponents".into(), json!(s.exponents));
            }
        }
        Some(v1::obstacle::Shape::Nested(n)) => {
            m.insert("semi_axes".into(), json!(n.semi_axes));
            m.insert("nested".into(), json!({"n": n.n, "m": n.m}));
        }
        Some(v1::obstacle::Shape::Solid(s)) => {
            let kind = v1::solid_primitive::Type::try_from(s.r#type)
                .map(|t| t.as_str_name().to_string())
                .unwrap_or_else(|_| s.r#type.to_string());
            m.insert("solid".into(), json!({"type": kind, "dimensions": s.dimensions}));
        }
        None => {}
    }
    let d = o.center.len();
    if !o.rotation.is_empty() && d > 0 {
        let rows: Vec<Vec<f64>> = o.rotation.chunks(d).map(<[f64]>::to_vec).collect();
        m.insert("rotation".into(), json!(rows));
    }
    if !o.velocity.is_empty() {
        m.insert("velocity".into(), json!(o.velocity));
    }
    if o.margin != 0.0 {
        m.insert("margin".into(), o.margin.into());
    }
    if o.ttl_s != 0.0 {
        m.insert("ttl_s".into(), o.ttl_s.into());
    }
    Value::Object(m)
}

/// The JSON of a stored record: identity, and the primitive in the engine's serde form (which round-trips).
pub fn record_json(r: &v1::PrimitiveRecord) -> Result<Value, ClientError> {
    let p =
        r.primitive.as_ref().ok_or_else(|| ClientError::Protocol("a record without its primitive".into()))?;
    let prim =
        primitive_from_proto(p).map_err(|e| ClientError::Protocol(format!("record primitive: {e}")))?;
    Ok(json!({
        "robot_id": r.robot_id,
        "name": r.name,
        "version": r.version,
        "created_unix_ms": r.created_unix_ms,
        "primitive": prim,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn learned() -> dmp::Primitive {
        let t: Vec<f64> = (0..=100).map(|k| k as f64 / 100.0).collect();
        let x: Vec<Vec<f64>> = t.iter().map(|t| vec![t.sin(), t * t, 1.0 - t]).collect();
        let demo = dmp::Demonstration::new(t, x).unwrap();
        dmp::learn(&demo, &dmp::LearnConfig { n_basis: 7, ..dmp::LearnConfig::paper() }).unwrap()
    }

    #[test]
    fn primitives_round_trip_through_the_message() {
        let p = learned();
        let m = primitive_to_proto(&p);
        assert_eq!(m.weights.len(), 3 * 8);
        // Row-major: row p holds the N + 1 weights of dimension p.
        assert_eq!(m.weights[8..16], p.weights[1][..]);
        assert_eq!(primitive_from_proto(&m).unwrap(), p);
        // And through the bytes.
        let bytes = dmp_proto::codec::encode(&m);
        let back: v1::Primitive = dmp_proto::codec::decode(&bytes).unwrap();
        assert_eq!(primitive_from_proto(&back).unwrap(), p);
    }

    #[test]
    fn bad_primitive_messages_name_the_field() {
        let mut m = primitive_to_proto(&learned());
        m.weights.pop();
        assert!(primitive_from_proto(&m).unwrap_err().to_string().contains("weights"));
        let mut m = primitive_to_proto(&learned());
        m.k[2] = -1.0;
        assert!(primitive_from_proto(&m).unwrap_err().to_string().contains("k[2]"));
        let mut m = primitive_to_proto(&learned());
        m.dim = 0;
        assert!(primitive_from_proto(&m).unwrap_err().to_string().contains("dim"));
    }

    #[test]
    fn json_obstacles_parse_validate_and_convert() {
        let v = json!({"id": "e", "center": [0.5, 0.5], "semi_axes": [0.3, 0.2], "exponents": [1, 2],
                       "rotation": [[0.0, -1.0], [1.0, 0.0]], "ttl_s": 2.5});
        let o = obstacle_from_json(&v, "").unwrap();
        o.validate().unwrap();
        assert_eq!(o.ttl_s, 2.5);
        let m = o.to_proto();
        assert_eq!(m.rotation, vec![0.0, -1.0, 1.0, 0.0]);
        assert_eq!(m.ttl_s, 2.5);
        // The JSON written back parses to the same obstacle, and the message's JSON has the same keys.
        assert_eq!(obstacle_from_json(&o.to_json(), "").unwrap(), o);
        assert_eq!(obstacle_from_json(&obstacle_json(&m), "").unwrap(), o);

        let e = obstacle_from_json(
            &json!({"id": "e", "center": [0], "semi_axes": [1], "bogus": 1}),
            "obstacles[1]",
        )
        .unwrap_err();
        assert!(e.to_string().contains("obstacles[1].bogus") && e.is_bad_input(), "{e}");
        let e = obstacle_from_json(&json!({"id": "e", "center": [0, 0]}), "").unwrap_err();
        assert!(e.to_string().contains("semi_axes"), "{e}");
        let bad =
            obstacle_from_json(&json!({"id": "e", "center": [0, 0], "semi_axes": [-1, 1]}), "").unwrap();
        assert!(bad.validate().unwrap_err().to_string().contains("semi_axes[0]"));
    }

    #[test]
    fn avoidance_maps_every_method() {
        let a: Avoidance = serde_json::from_value(
            json!({"method": "dynamic_volumetric", "lambda": 10, "beta": 2, "eta": 0.5}),
        )
        .unwrap();
        let m = avoidance_to_proto(&a, 50);
        assert_eq!(
            m.method,
            Some(v1::avoidance::Method::DynamicVolumetric(v1::avoidance::DynamicVolumetric {
                lambda: 10.0,
                beta: 2.0,
                eta: 0.5
            }))
        );
        assert!(!m.ignore_obstacle_velocity);
        let none = avoidance_to_proto(&Avoidance::NONE, 50);
        assert_eq!(none.method, Some(v1::avoidance::Method::None(v1::avoidance::None {})));
    }
}
