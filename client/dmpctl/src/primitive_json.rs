//! The JSON that `dmpctl show` prints of a stored primitive record. The conversions between the schema, the
//! scenario format and the engine are `dmp_proto`'s, shared with the server.

use dmp_client::ClientError;
use dmp_proto::primitive::primitive_from_proto;
use dmp_proto::v1;
use serde_json::{Value, json};

/// The JSON of a stored record: identity, and the primitive in the engine's serde form (which round-trips).
pub(crate) fn record_json(r: &v1::PrimitiveRecord) -> Result<Value, ClientError> {
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
}
