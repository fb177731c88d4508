//! Conversions between the wire schema (`dmp_proto::v1`) and the engine or the scenario format, the client's side
//! of `server/src/convert.rs`: the same mappings, so that what the client sends is what the server reads.

use dmp::scenario::{DmpSpec, FootprintSpec, ObstacleSpec};
use dmp::{Avoidance, DmpError, InvalidInput, Method};
use dmp_proto::v1;
use serde_json::{Map, Value, json};

use crate::error::ClientError;

/// Keys of a JSON obstacle: the scenario format's (SPEC.md) plus `ttl_s` and `margin` (the server's Zenoh payload).
pub const JSON_OBSTACLE_KEYS: [&str; 9] =
    ["id", "center", "semi_axes", "exponents", "rotation", "velocity", "nested", "ttl_s", "margin"];

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
    let shape = match s.nested {
        Some(n) => v1::obstacle::Shape::Nested(v1::NestedSuperquadric {
            semi_axes: s.semi_axes.clone(),
            n: n.n,
            m: n.m,
        }),
        None => v1::obstacle::Shape::Superquadric(v1::Superquadric {
            semi_axes: s.semi_axes.clone(),
            exponents: s.exponents.clone().unwrap_or_default(),
        }),
    };
    v1::Obstacle {
        id: s.id.clone(),
        shape: Some(shape),
        center: s.center.clone(),
        rotation: s.rotation.as_ref().map(|r| r.iter().flatten().copied().collect()).unwrap_or_default(),
        velocity: s.velocity.clone().unwrap_or_default(),
        margin,
        ttl_s,
    }
}

/// An obstacle read from JSON: the scenario's object plus the Zenoh payload's `margin` and `ttl_s`.
#[derive(Debug, Clone, PartialEq)]
pub struct JsonObstacle {
    /// The scenario-format obstacle.
    pub spec: ObstacleSpec,
    /// Inflation of every semi-axis (0: none).
    pub margin: f64,
    /// Seconds to live (0: forever).
    pub ttl_s: f64,
}

impl JsonObstacle {
    /// Its message.
    pub fn to_proto(&self) -> v1::Obstacle {
        obstacle_to_proto(&self.spec, self.margin, self.ttl_s)
    }

    /// The JSON payload the server reads on `dmp/<cell>/obstacles/<id>` (what [`obstacle_from_json`] parses).
    pub fn to_json(&self) -> Value {
        let mut v = serde_json::to_value(&self.spec).unwrap_or(Value::Null);
        if let Value::Object(obj) = &mut v {
            obj.retain(|_, v| !v.is_null());
            if self.margin != 0.0 {
                obj.insert("margin".into(), self.margin.into());
            }
            if self.ttl_s != 0.0 {
                obj.insert("ttl_s".into(), self.ttl_s.into());
            }
        }
        v
    }

    /// Checks it with the engine (shape, centre, rotation, velocity, margin, ttl), as the server will; errors name
    /// the field.
    pub fn validate(&self) -> Result<(), DmpError> {
        let num = |field: &str, v: f64| {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                Err(DmpError::from(InvalidInput::new(field, "must be a finite number >= 0")))
            }
        };
        num("margin", self.margin)?;
        num("ttl_s", self.ttl_s)?;
        self.to_engine().map(drop)
    }

    /// The engine's obstacle (its centre is the one at `t = 0`), inflated by the margin.
    pub fn to_engine(&self) -> Result<dmp::Obstacle, DmpError> {
        let s = &self.spec;
        let shape = match s.nested {
            Some(n) => {
                if s.exponents.is_some() {
                    return Err(
                        InvalidInput::new("nested", "give either `exponents` or `nested`, not both").into()
                    );
                }
                let a: [f64; 3] = s.semi_axes.as_slice().try_into().map_err(|_| {
                    InvalidInput::new(
                        "semi_axes",
                        format!("the nested form is 3-D: needs 3 semi-axes, found {}", s.semi_axes.len()),
                    )
                })?;
                dmp::Shape::Nested(dmp::NestedSuperquadric::new(a, n.n, n.m)?)
            }
            None => {
                let n = s.exponents.clone().unwrap_or_else(|| vec![1.0; s.semi_axes.len()]);
                dmp::Shape::Superquadric(dmp::Superquadric::new(s.semi_axes.clone(), n)?)
            }
        };
        let shape = if self.margin > 0.0 { shape.inflated(self.margin)? } else { shape };
        dmp::Obstacle::new(s.id.clone(), shape, s.center.clone(), s.rotation.clone(), s.velocity.clone())
    }
}

/// Parses one JSON obstacle (an object of [`JSON_OBSTACLE_KEYS`]); `field` prefixes the errors (e.g.
/// `obstacles[2]`, or empty).
pub fn obstacle_from_json(value: &Value, field: &str) -> Result<JsonObstacle, ClientError> {
    let at = |name: &str| if field.is_empty() { name.to_string() } else { format!("{field}.{name}") };
    let Value::Object(obj) = value else {
        return Err(ClientError::argument(
            if field.is_empty() { "(obstacle)" } else { field },
            "must be a JSON object",
        ));
    };
    if let Some(k) = obj.keys().find(|k| !JSON_OBSTACLE_KEYS.contains(&k.as_str())) {
        return Err(ClientError::argument(
            at(k),
            format!("unknown field, expected one of {JSON_OBSTACLE_KEYS:?}"),
        ));
    }
    let number = |key: &str| -> Result<f64, ClientError> {
        match obj.get(key) {
            None | Some(Value::Null) => Ok(0.0),
            Some(v) => v.as_f64().ok_or_else(|| ClientError::argument(at(key), "must be a number")),
        }
    };
    let (margin, ttl_s) = (number("margin")?, number("ttl_s")?);
    let rest: Map<String, Value> = obj
        .iter()
        .filter(|(k, _)| !matches!(k.as_str(), "margin" | "ttl_s"))
        .map(|(k, v)| (k.clone(), v.clone()))
        .collect();
    let spec: ObstacleSpec = serde_path_to_error::deserialize(Value::Object(rest)).map_err(|e| {
        let path = e.path().to_string();
        let inner = e.into_inner().to_string();
        ClientError::argument(if path == "." { at("(obstacle)") } else { at(&path) }, inner)
    })?;
    Ok(JsonObstacle { spec, margin, ttl_s })
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
