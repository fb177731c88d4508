//! Decoding the Zenoh payloads of the keys ([`crate::keys`]) by their encoding's name, with the id the key names.
//! Kept free of Zenoh's types: a caller passes the sample's encoding as a string.

use crate::obstacle_json::obstacle_from_json_bytes;
use crate::robot_state::check_robot_state;
use crate::{WireError, codec, v1};

/// Largest obstacle or robot-state payload accepted (larger ones are refused).
pub const MAX_PAYLOAD_BYTES: usize = 1 << 20;

/// Encoding names of a JSON payload.
pub const JSON_ENCODINGS: [&str; 2] = ["application/json", "text/json"];

/// Decodes an obstacle payload whose key names `id_from_key`.
///
/// Encoding [`codec::PROTOBUF_ENCODING`]: a `dmp.v1.Obstacle`; a JSON encoding ([`JSON_ENCODINGS`]): the JSON
/// obstacle ([`obstacle_from_json_bytes`]); any other (or none): JSON, then protobuf, except that a payload starting
/// with `{` is only JSON (so that bad JSON is reported as such). A schema after `;` in the encoding's name
/// (`application/protobuf;dmp.v1.Obstacle`) is ignored. An id in the payload must equal the key's.
pub fn decode_obstacle(encoding: &str, bytes: &[u8], id_from_key: &str) -> Result<v1::Obstacle, WireError> {
    check_size(bytes)?;
    let protobuf = |bytes: &[u8]| {
        codec::decode::<v1::Obstacle>(bytes)
            .map_err(|e| WireError::new("payload", format!("not a protobuf dmp.v1.Obstacle: {e}")))
    };
    let name = encoding.split(';').next().unwrap_or_default();
    let mut o = if name == codec::PROTOBUF_ENCODING {
        protobuf(bytes)?
    } else if JSON_ENCODINGS.contains(&name) {
        obstacle_from_json_bytes(bytes, id_from_key)?
    } else {
        match obstacle_from_json_bytes(bytes, id_from_key) {
            Ok(o) => o,
            Err(e) if bytes.trim_ascii_start().starts_with(b"{") => return Err(e),
            Err(json) => codec::decode::<v1::Obstacle>(bytes).map_err(|pb| {
                WireError::new(
                    "payload",
                    format!("neither a JSON obstacle ({json}) nor a protobuf dmp.v1.Obstacle ({pb})"),
                )
            })?,
        }
    };
    if o.id.is_empty() {
        o.id = id_from_key.to_owned();
    } else if o.id != id_from_key {
        return Err(WireError::new("id", format!("`{}` differs from the key's `{id_from_key}`", o.id)));
    }
    Ok(o)
}

/// Decodes a robot-state payload (protobuf `dmp.v1.RobotState`) whose key names `id_from_key`, and checks it
/// ([`check_robot_state`]); returns it with its footprint. An empty `robot_id` takes the key's.
pub fn decode_robot_state(
    bytes: &[u8],
    id_from_key: &str,
) -> Result<(v1::RobotState, Option<dmp::Shape>), WireError> {
    check_size(bytes)?;
    let mut state = codec::decode::<v1::RobotState>(bytes)
        .map_err(|e| WireError::new("payload", format!("not a protobuf dmp.v1.RobotState: {e}")))?;
    if state.robot_id.is_empty() {
        state.robot_id = id_from_key.to_owned();
    } else if state.robot_id != id_from_key {
        return Err(WireError::new(
            "robot_id",
            format!("`{}` differs from the key's `{id_from_key}`", state.robot_id),
        ));
    }
    let footprint = check_robot_state(&state)?;
    Ok((state, footprint))
}

fn check_size(bytes: &[u8]) -> Result<(), WireError> {
    if bytes.len() > MAX_PAYLOAD_BYTES {
        return Err(WireError::new(
            "payload",
            format!("{} bytes, more than the limit of {MAX_PAYLOAD_BYTES}", bytes.len()),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The name of Zenoh's default encoding (a sample put without one).
    const UNSET: &str = "zenoh/bytes";
    const JSON: &str = "application/json";
    const PROTOBUF: &str = codec::PROTOBUF_ENCODING;

    fn ball(id: &str) -> v1::Obstacle {
        v1::Obstacle {
            id: id.into(),
            shape: Some(v1::obstacle::Shape::Solid(v1::SolidPrimitive { r#type: 2, dimensions: vec![0.1] })),
            center: vec![0.0; 3],
            ..Default::default()
        }
    }

    #[test]
    fn payloads_are_decoded_by_encoding() {
        let json = br#"{"center": [0, 0], "semi_axes": [0.2, 0.1], "ttl_s": 1}"#;
        let o = decode_obstacle(JSON, json, "a").unwrap();
        assert_eq!((o.id.as_str(), o.ttl_s), ("a", 1.0));
        let o = decode_obstacle(UNSET, json, "a").unwrap();
        assert_eq!(o.id, "a");
        let pb = codec::encode(&ball("b"));
        assert_eq!(decode_obstacle(PROTOBUF, &pb, "b").unwrap().id, "b");
        assert_eq!(decode_obstacle("application/protobuf;dmp.v1.Obstacle", &pb, "b").unwrap().id, "b");
        assert_eq!(decode_obstacle(UNSET, &pb, "b").unwrap().id, "b");
        let e = decode_obstacle(PROTOBUF, &pb, "c").unwrap_err();
        assert!(e.to_string().starts_with("id:"), "{e}");
        let e = decode_obstacle(UNSET, b"{\"center\": [0,", "a").unwrap_err();
        assert!(e.to_string().contains("EOF"), "bad JSON is reported as JSON: {e}");
        assert!(decode_obstacle(PROTOBUF, json, "a").is_err());
        assert!(decode_obstacle(UNSET, &vec![b' '; MAX_PAYLOAD_BYTES + 1], "a").is_err());
    }

    #[test]
    fn robot_states_take_the_key_id() {
        let state = v1::RobotState { position: vec![0.0; 2], ..Default::default() };
        let (s, footprint) = decode_robot_state(&codec::encode(&state), "r2").unwrap();
        assert_eq!(s.robot_id, "r2");
        assert!(footprint.is_none());
        let other = v1::RobotState { robot_id: "r1".into(), ..state };
        assert_eq!(decode_robot_state(&codec::encode(&other), "r2").unwrap_err().field, "robot_id");
        assert_eq!(decode_robot_state(b"garbage", "r2").unwrap_err().field, "payload");
    }
}
