//! The JSON form of an obstacle, shared by the server (Zenoh payloads) and the client (files, perception nodes):
//! the scenario format's object (SPEC.md) plus `margin` and `ttl_s`.

use dmp::scenario::ObstacleSpec;
use dmp::{DmpError, InvalidInput};
use serde_json::{Map, Value};

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
    pub fn parse(value: &Value, field: &str) -> Result<Self, InvalidInput> {
        let at = |name: &str| if field.is_empty() { name.to_string() } else { format!("{field}.{name}") };
        let Value::Object(obj) = value else {
            return Err(InvalidInput::new(
                if field.is_empty() { "(obstacle)" } else { field },
                "must be a JSON object",
            ));
        };
        if let Some(k) = obj.keys().find(|k| !JSON_OBSTACLE_KEYS.contains(&k.as_str())) {
            return Err(InvalidInput::new(
                at(k),
                format!("unknown field, expected one of {JSON_OBSTACLE_KEYS:?}"),
            ));
        }
        let number = |key: &str| match obj.get(key) {
            None | Some(Value::Null) => Ok(0.0),
            Some(v) => v.as_f64().ok_or_else(|| InvalidInput::new(at(key), "must be a number")),
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
            InvalidInput::new(if path == "." { at("(obstacle)") } else { at(&path) }, inner)
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

    /// The engine's obstacle (centre at `t = 0`), inflated by the margin; errors name the field.
    pub fn to_engine(&self) -> Result<dmp::Obstacle, DmpError> {
        let o = self.spec.to_obstacle()?;
        if self.margin > 0.0 { o.inflated(self.margin) } else { Ok(o) }
    }

    /// Checks it with the engine as the server will (shape, centre, rotation, velocity, margin, ttl).
    pub fn validate(&self) -> Result<(), DmpError> {
        for (field, v) in [("margin", self.margin), ("ttl_s", self.ttl_s)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(InvalidInput::new(field, "must be a finite number >= 0").into());
            }
        }
        self.to_engine().map(drop)
    }
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
}
