//! The client's side of the wire. The conversions between the schema, the scenario format and the engine are
//! `dmp_proto`'s, shared with the server; what is left here is the client's own: the JSON that `dmpctl` prints of a
//! stored record.

use dmp_proto::primitive::primitive_from_proto;
use dmp_proto::v1;
use serde_json::{Value, json};

use crate::error::ClientError;

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

    #[test]
    fn records_print_their_primitive_and_refuse_a_missing_one() {
        let t: Vec<f64> = (0..=20).map(|k| k as f64 / 20.0).collect();
        let x: Vec<Vec<f64>> = t.iter().map(|t| vec![*t, 1.0 - t]).collect();
        let demo = dmp::Demonstration::new(t, x).unwrap();
        let p = dmp::learn(&demo, &dmp::LearnConfig { n_basis: 5, ..dmp::LearnConfig::paper() }).unwrap();
        let record = v1::PrimitiveRecord {
            robot_id: "r".into(),
            name: "n".into(),
            version: 2,
            created_unix_ms: 1,
            primitive: Some(dmp_proto::primitive::primitive_to_proto(&p)),
            ..Default::default()
        };
        let v = record_json(&record).unwrap();
        assert_eq!(v["version"], 2);
        assert_eq!(serde_json::from_value::<dmp::Primitive>(v["primitive"].clone()).unwrap(), p);
        let e = record_json(&v1::PrimitiveRecord { primitive: None, ..record }).unwrap_err();
        assert!(matches!(e, ClientError::Protocol(_)), "{e}");
    }

    #[test]
    fn wire_errors_are_bad_input() {
        let e = dmp_proto::obstacle_json::JsonObstacle::parse(
            &json!({"id": "e", "center": [0], "semi_axes": [1], "bogus": 1}),
            "o",
        )
        .map_err(ClientError::from)
        .unwrap_err();
        assert!(e.is_bad_input() && e.to_string().starts_with("o.bogus"), "{e}");
    }
}
