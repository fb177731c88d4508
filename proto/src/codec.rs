//! Encoding of Zenoh payloads: protobuf (encoding `application/protobuf`) is the schema's native form.

use prost::Message;

/// Zenoh encoding name of protobuf payloads.
pub const PROTOBUF_ENCODING: &str = "application/protobuf";

/// Encodes a message.
pub fn encode<M: Message>(m: &M) -> Vec<u8> {
    m.encode_to_vec()
}

/// Decodes a message.
pub fn decode<M: Message + Default>(bytes: &[u8]) -> Result<M, prost::DecodeError> {
    M::decode(bytes)
}
