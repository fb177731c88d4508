//! The JSON form of an obstacle, shared by the server (Zenoh payloads) and the client (files, perception nodes):
//! the scenario format's object (SPEC.md) plus `margin` and `ttl_s`; both ways to and from its message.

use dmp::scenario::ObstacleSpec;
use serde_json::{Map, Value, json};

use crate::WireError;
use crate::v1;

/// Keys of a JSON obstacle.
pub const JSON_OBSTACLE_KEYS: [&str; 9] =
    ["id", "center", "semi_axes", "exponents", "rotation", "velocity", "nested", "ttl_s", "margin"];

/// An obstacle read from JSON.
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
    /// Parses one object of [`JSON_OBSTACLE_KEYS`]; an unknown key, a wrong type or a missing field is an error
    /// naming it, prefixed by `field` (e.g. `obstacles[2]`, or empty).
    pub fn parse(value: &Value, field: &str) -> Result<Self, WireError> {
        let at = |name: &str| if field.is_empty() { name.to_string() } else { format!("{field}.{name}") };
        let Value::Object(obj) = value else {
            return Err(WireError::new(
                if field.is_empty() { "(obstacle)" } else { field },
                "must be a JSON object",
            ));
        };
        if let Some(k) = obj.keys().find(|k| !JSON_OBSTACLE_KEYS.contains(&k.as_str())) {
            return Err(WireError::new(
                at(k),
                format!("unknown field, expected one of {JSON_OBSTACLE_KEYS:?}"),
            ));
        }
        let number = |key: &str| match obj.get(key) {
            None | Some(Value::Null) => Ok(0.0),
            Some(v) => v.as_f64().ok_or_else(|| WireError::new(at(key), "must be a number")),
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
            WireError::new(if path == "." { at("(obstacle)") } else { at(&path) }, inner)
        })?;
        Ok(Self { spec, margin, ttl_s })
    }

    /// Its message.
    pub fn to_proto(&self) -> v1::Obstacle {
        let s = &self.spec;
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
            margin: self.margin,
            ttl_s: self.ttl_s,
        }
    }

    /// The JSON payload (what [`JsonObstacle::parse`] reads).
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

    /// The engine's obstacle (centre at `t = 0`), inflated by the margin; errors name the field of the JSON.
    pub fn to_engine(&self) -> Result<dmp::Obstacle, WireError> {
        let o = self.spec.to_obstacle()?;
        Ok(if self.margin > 0.0 { o.inflated(self.margin)? } else { o })
    }

    /// Checks it with the engine as the server will (shape, centre, rotation, velocity, margin, ttl).
    pub fn validate(&self) -> Result<(), WireError> {
        for (field, v) in [("margin", self.margin), ("ttl_s", self.ttl_s)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(WireError::new(field, "must be a finite number >= 0"));
            }
        }
        self.to_engine().map(drop)
    }
}

/// The obstacle message of a scenario obstacle, with a margin and a time to live (0: none).
pub fn obstacle_to_proto(spec: &ObstacleSpec, margin: f64, ttl_s: f64) -> v1::Obstacle {
    JsonObstacle { spec: spec.clone(), margin, ttl_s }.to_proto()
}

/// Parses a JSON payload (the scenario format's obstacle, plus `margin` and `ttl_s`) into the obstacle message;
/// `id_from_key` names it when the JSON has no `id`.
pub fn obstacle_from_json_bytes(bytes: &[u8], id_from_key: &str) -> Result<v1::Obstacle, WireError> {
    let mut value: Value =
        serde_json::from_slice(bytes).map_err(|e| WireError::new("payload", e.to_string()))?;
    if let Value::Object(obj) = &mut value {
        obj.entry("id").or_insert_with(|| id_from_key.into());
    }
    Ok(JsonObstacle::parse(&value, "")?.to_proto())
}

/// The JSON of an obstacle message, in the scenario format where it has one (a solid primitive is written as
/// `"solid": {"type": "BOX", "dimensions": [..]}`, which [`JsonObstacle::parse`] does not read).
pub fn obstacle_to_json(o: &v1::Obstacle) -> Value {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_round_trips() {
        let v: Value = serde_json::from_str(
            r#"{"id": "b", "center": [0.1, 0.2], "semi_axes": [0.3, 0.2], "ttl_s": 2.5}"#,
        )
        .unwrap();
        let o = JsonObstacle::parse(&v, "").unwrap();
        assert_eq!((o.ttl_s, o.margin), (2.5, 0.0));
        assert_eq!(JsonObstacle::parse(&o.to_json(), "").unwrap(), o);
        assert_eq!(o.to_proto().ttl_s, 2.5);
        o.validate().unwrap();
        let bad: Value =
            serde_json::from_str(r#"{"id": "b", "center": [0.1], "semi_axes": [0.3], "bogus": 1}"#).unwrap();
        assert_eq!(JsonObstacle::parse(&bad, "obstacles[1]").unwrap_err().field, "obstacles[1].bogus");
        let neg: Value =
            serde_json::from_str(r#"{"id": "b", "center": [0.1, 0.2], "semi_axes": [-0.3, 0.2]}"#).unwrap();
        assert!(
            JsonObstacle::parse(&neg, "")
                .unwrap()
                .validate()
                .unwrap_err()
                .to_string()
                .contains("semi_axes[0]")
        );
    }

    #[test]
    fn json_obstacles_parse_validate_and_convert() {
        let v = json!({"id": "e", "center": [0.5, 0.5], "semi_axes": [0.3, 0.2], "exponents": [1, 2],
                       "rotation": [[0.0, -1.0], [1.0, 0.0]], "ttl_s": 2.5});
        let o = JsonObstacle::parse(&v, "").unwrap();
        o.validate().unwrap();
        assert_eq!(o.ttl_s, 2.5);
        let m = o.to_proto();
        assert_eq!(m.rotation, vec![0.0, -1.0, 1.0, 0.0]);
        assert_eq!(m.ttl_s, 2.5);
        // The JSON written back parses to the same obstacle, and the message's JSON has the same keys.
        assert_eq!(JsonObstacle::parse(&o.to_json(), "").unwrap(), o);
        assert_eq!(JsonObstacle::parse(&obstacle_to_json(&m), "").unwrap(), o);
        assert_eq!(obstacle_to_proto(&o.spec, o.margin, o.ttl_s), m);

        let e = JsonObstacle::parse(
            &json!({"id": "e", "center": [0], "semi_axes": [1], "bogus": 1}),
            "obstacles[1]",
        )
        .unwrap_err();
        assert!(e.to_string().contains("obstacles[1].bogus"), "{e}");
        let e = JsonObstacle::parse(&json!({"id": "e", "center": [0, 0]}), "").unwrap_err();
        assert!(e.to_string().contains("semi_axes"), "{e}");
        let bad =
            JsonObstacle::parse(&json!({"id": "e", "center": [0, 0], "semi_axes": [-1, 1]}), "").unwrap();
        assert!(bad.validate().unwrap_err().to_string().contains("semi_axes[0]"));
    }

    #[test]
    fn json_payloads_follow_the_scenario_format() {
        let o = obstacle_from_json_bytes(
            br#"{"center": [0.1, 0.2], "semi_axes": [0.3, 0.2], "exponents": [1, 2], "ttl_s": 2.5}"#,
            "box1",
        )
        .unwrap();
        assert_eq!(o.id, "box1");
        assert_eq!(o.ttl_s, 2.5);
        crate::obstacle::obstacle_to_engine(&o).unwrap();
        let e = obstacle_from_json_bytes(br#"{"center": [0.1], "semi_axes": [0.3], "bogus": 1}"#, "x")
            .unwrap_err();
        assert!(e.to_string().contains("bogus"), "{e}");
        let o =
            obstacle_from_json_bytes(br#"{"center": [0.1, 0.2], "semi_axes": [-0.3, 0.2]}"#, "x").unwrap();
        let e = crate::obstacle::obstacle_to_engine(&o).unwrap_err();
        assert!(e.to_string().contains("semi_axes[0]"), "{e}");
        assert_eq!(obstacle_from_json_bytes(b"{", "x").unwrap_err().field, "payload");
    }
}
