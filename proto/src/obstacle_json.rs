//! The JSON form of an obstacle, shared by the server (Zenoh payloads) and the client (files, perception nodes):
//! the scenario format's object (SPEC.md) plus `margin` and `ttl_s`; both ways to and from its message.

use dmp::scenario::ObstacleSpec;
use serde_json::{Map, Value, json};

use crate::WireError;
use crate::v1;

/// Keys of a JSON obstacle. Its orientation is one of `rotation` (rows of R), `quaternion` (`[x, y, z, w]`, 3-D) or
/// `rpy` (roll, pitch, yaw in radians about the fixed x, y, z axes: R = Rz(yaw) Ry(pitch) Rx(roll), as ROS; 3-D).
pub const JSON_OBSTACLE_KEYS: [&str; 11] = [
    "id",
    "center",
    "semi_axes",
    "exponents",
    "rotation",
    "quaternion",
    "rpy",
    "velocity",
    "nested",
    "ttl_s",
    "margin",
];

/// How far from orthonormal a `rotation` may be (the largest entry of `R R^T - I`) and be re-orthonormalised: a
/// matrix written to 4 digits (0.7071) is about 1e-4 off. Further is a mistake, refused.
pub const ROTATION_TOLERANCE: f64 = 1e-3;

/// How far from 1 a `quaternion`'s norm may be; it is normalised.
pub const QUATERNION_TOLERANCE: f64 = 1e-3;

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
        let mut rest: Map<String, Value> = obj
            .iter()
            .filter(|(k, _)| !matches!(k.as_str(), "margin" | "ttl_s" | "quaternion" | "rpy"))
            .map(|(k, v)| (k.clone(), v.clone()))
            .collect();
        if let Some(rows) = orientation(obj).map_err(|e| WireError::new(at(&e.field), e.rule))? {
            rest.insert("rotation".into(), json!(rows));
        }
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

/// The rotation's rows from whichever of `rotation`, `quaternion` or `rpy` the object has (at most one): a
/// quaternion normalised, a matrix within [`ROTATION_TOLERANCE`] of orthonormal re-orthonormalised. `None` when it
/// has none, or a `rotation` that is not a square matrix of numbers (the deserialiser names what is wrong).
fn orientation(obj: &Map<String, Value>) -> Result<Option<Vec<Vec<f64>>>, WireError> {
    let given: Vec<&str> =
        ["rotation", "quaternion", "rpy"].into_iter().filter(|k| obj.contains_key(*k)).collect();
    if given.len() > 1 {
        return Err(WireError::new(
            given[1],
            format!("give one orientation: `{}` and `{}` are both given", given[0], given[1]),
        ));
    }
    let numbers = |key: &str, n: usize, form: &str| -> Result<Vec<f64>, WireError> {
        let v: Option<Vec<f64>> = obj[key]
            .as_array()
            .filter(|a| a.len() == n)
            .and_then(|a| a.iter().map(Value::as_f64).collect::<Option<Vec<f64>>>())
            .filter(|v| v.iter().all(|x| x.is_finite()));
        v.ok_or_else(|| WireError::new(key, format!("must be {n} finite numbers, {form}")))
    };
    let three_d = |key: &str| match obj.get("center").and_then(Value::as_array) {
        Some(c) if c.len() != 3 => Err(WireError::new(
            key,
            format!("is for 3-D obstacles; this one has {} dimensions (use `rotation`)", c.len()),
        )),
        _ => Ok(()),
    };
    match given.first().copied() {
        Some("quaternion") => {
            let q = numbers("quaternion", 4, "[x, y, z, w]")?;
            three_d("quaternion")?;
            let norm = q.iter().map(|x| x * x).sum::<f64>().sqrt();
            if (norm - 1.0).abs() > QUATERNION_TOLERANCE {
                return Err(WireError::new(
                    "quaternion",
                    format!(
                        "must be a unit quaternion [x, y, z, w]: its norm is {norm}, not within {QUATERNION_TOLERANCE} of 1"
                    ),
                ));
            }
            let [x, y, z, w] = [q[0] / norm, q[1] / norm, q[2] / norm, q[3] / norm];
            Ok(Some(vec![
                vec![1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - z * w), 2.0 * (x * z + y * w)],
                vec![2.0 * (x * y + z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - x * w)],
                vec![2.0 * (x * z - y * w), 2.0 * (y * z + x * w), 1.0 - 2.0 * (x * x + y * y)],
            ]))
        }
        Some("rpy") => {
            let a = numbers("rpy", 3, "[roll, pitch, yaw] in radians")?;
            three_d("rpy")?;
            let ((sr, cr), (sp, cp), (sy, cy)) = (a[0].sin_cos(), a[1].sin_cos(), a[2].sin_cos());
            Ok(Some(vec![
                vec![cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                vec![sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                vec![-sp, cp * sr, cp * cr],
            ]))
        }
        Some(_) => {
            let Some(rows) = serde_json::from_value::<Vec<Vec<f64>>>(obj["rotation"].clone())
                .ok()
                .filter(|r| r.iter().all(|row| row.len() == r.len() && row.iter().all(|x| x.is_finite())))
            else {
                return Ok(None);
            };
            let off = off_orthonormal(&rows);
            if off > ROTATION_TOLERANCE {
                return Err(WireError::new(
                    "rotation",
                    format!(
                        "must be orthonormal: R R^T differs from I by {off:.2e}, more than {ROTATION_TOLERANCE} (a \
                         matrix to 4 digits is accepted and re-orthonormalised; or give `quaternion` or `rpy`)"
                    ),
                ));
            }
            // A matrix the engine takes as orthonormal stays as written (a message written to JSON and read again is
            // the same message); only one further off is re-orthonormalised.
            Ok(Some(if off > dmp::ranges::ROTATION_TOLERANCE { orthonormalised(rows) } else { rows }))
        }
        None => Ok(None),
    }
}

/// The largest entry of `R R^T - I`.
fn off_orthonormal(r: &[Vec<f64>]) -> f64 {
    let mut off: f64 = 0.0;
    for (i, a) in r.iter().enumerate() {
        for (j, b) in r.iter().enumerate() {
            let dot: f64 = a.iter().zip(b).map(|(x, y)| x * y).sum();
            off = off.max((dot - if i == j { 1.0 } else { 0.0 }).abs());
        }
    }
    off
}

/// The rows made orthonormal (Gram-Schmidt, twice for accuracy), keeping their order and direction: a matrix
/// close to a rotation becomes the rotation it was meant to be, to rounding.
fn orthonormalised(mut r: Vec<Vec<f64>>) -> Vec<Vec<f64>> {
    for _ in 0..2 {
        for i in 0..r.len() {
            for j in 0..i {
                let dot: f64 = r[i].iter().zip(&r[j]).map(|(x, y)| x * y).sum();
                let rj = r[j].clone();
                r[i].iter_mut().zip(&rj).for_each(|(x, y)| *x -= dot * y);
            }
            let norm = r[i].iter().map(|x| x * x).sum::<f64>().sqrt();
            if norm > 0.0 {
                r[i].iter_mut().for_each(|x| *x /= norm);
            }
        }
    }
    r
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

    fn parsed(json: &str) -> Result<JsonObstacle, WireError> {
        JsonObstacle::parse(&serde_json::from_str(json).unwrap(), "obstacles[0]")
    }

    fn rotation_of(json: &str) -> Vec<Vec<f64>> {
        let o = parsed(json).unwrap();
        o.validate().unwrap();
        o.spec.rotation.unwrap()
    }

    fn assert_close(a: &[Vec<f64>], b: &[Vec<f64>]) {
        for (ra, rb) in a.iter().zip(b) {
            for (x, y) in ra.iter().zip(rb) {
                assert!((x - y).abs() < 1e-12, "{a:?} != {b:?}");
            }
        }
    }

    #[test]
    fn a_quaternion_and_roll_pitch_yaw_give_the_same_rotation() {
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let base = r#""id": "b", "center": [0, 0, 0], "semi_axes": [0.3, 0.2, 0.1]"#;
        // 90 degrees about z.
        let expected = vec![vec![0.0, -1.0, 0.0], vec![1.0, 0.0, 0.0], vec![0.0, 0.0, 1.0]];
        assert_close(&rotation_of(&format!(r#"{{{base}, "quaternion": [0, 0, {h}, {h}]}}"#)), &expected);
        assert_close(
            &rotation_of(&format!(r#"{{{base}, "rpy": [0, 0, {}]}}"#, std::f64::consts::FRAC_PI_2)),
            &expected,
        );
        // Not quite unit (to 4 digits): normalised.
        assert_close(
            &rotation_of(&format!(r#"{{{base}, "quaternion": [0, 0, 0.7071, 0.7071]}}"#)),
            &expected,
        );
        // roll, then pitch, then yaw about the fixed axes, as ROS: R = Rz(yaw) Ry(pitch) Rx(roll).
        let (r, p, y) = (0.1_f64, -0.4_f64, 1.2_f64);
        let q = |ax: [f64; 3], a: f64| {
            let s = (a / 2.0).sin();
            [ax[0] * s, ax[1] * s, ax[2] * s, (a / 2.0).cos()]
        };
        let mul = |a: [f64; 4], b: [f64; 4]| {
            [
                a[3] * b[0] + a[0] * b[3] + a[1] * b[2] - a[2] * b[1],
                a[3] * b[1] - a[0] * b[2] + a[1] * b[3] + a[2] * b[0],
                a[3] * b[2] + a[0] * b[1] - a[1] * b[0] + a[2] * b[3],
                a[3] * b[3] - a[0] * b[0] - a[1] * b[1] - a[2] * b[2],
            ]
        };
        let qq = mul(mul(q([0.0, 0.0, 1.0], y), q([0.0, 1.0, 0.0], p)), q([1.0, 0.0, 0.0], r));
        assert_close(
            &rotation_of(&format!(r#"{{{base}, "rpy": [{r}, {p}, {y}]}}"#)),
            &rotation_of(&format!(
                r#"{{{base}, "quaternion": [{}, {}, {}, {}]}}"#,
                qq[0], qq[1], qq[2], qq[3]
            )),
        );
    }

    #[test]
    fn a_rotation_to_four_digits_is_accepted_and_made_orthonormal() {
        let o = rotation_of(
            r#"{"id": "b", "center": [0, 0], "semi_axes": [0.3, 0.2], "rotation": [[0.7071, -0.7071], [0.7071, 0.7071]]}"#,
        );
        assert!(off_orthonormal(&o) < 1e-12, "{o:?}");
        assert!((o[0][0] - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-12, "{o:?}");
        let e = parsed(r#"{"id": "b", "center": [0, 0], "semi_axes": [0.3, 0.2], "rotation": [[0.8, -0.6], [0.7, 0.7]]}"#)
            .unwrap_err();
        assert_eq!(e.field, "obstacles[0].rotation");
        assert!(e.rule.contains("must be orthonormal") && e.rule.contains("more than 0.001"), "{}", e.rule);
    }

    #[test]
    fn one_orientation_at_most_and_each_checked() {
        let base = r#""id": "b", "center": [0, 0, 0], "semi_axes": [0.3, 0.2, 0.1]"#;
        let e = parsed(&format!(r#"{{{base}, "rpy": [0, 0, 1], "quaternion": [0, 0, 0, 1]}}"#)).unwrap_err();
        assert_eq!(e.field, "obstacles[0].rpy");
        assert!(e.rule.contains("give one orientation"), "{}", e.rule);
        let e = parsed(&format!(r#"{{{base}, "quaternion": [0, 0, 0, 2]}}"#)).unwrap_err();
        assert!(e.field.ends_with("quaternion") && e.rule.contains("norm is 2"), "{}", e.rule);
        let e = parsed(&format!(r#"{{{base}, "rpy": [0, 1]}}"#)).unwrap_err();
        assert!(e.rule.contains("3 finite numbers"), "{}", e.rule);
        let e = parsed(r#"{"id": "b", "center": [0, 0], "semi_axes": [0.3, 0.2], "rpy": [0, 0, 1]}"#)
            .unwrap_err();
        assert!(e.rule.contains("3-D obstacles"), "{}", e.rule);
    }

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
