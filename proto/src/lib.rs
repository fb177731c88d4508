//! The wire schema of the DMP cell (`proto/dmp/v1/*.proto`), compiled without `protoc`. The same messages are the
//! gRPC payloads and the Zenoh payloads; [`codec`] is the one place that encodes and decodes them for Zenoh.

#[allow(missing_docs, clippy::all, missing_debug_implementations, rust_2018_idioms)]
pub mod v1 {
    tonic::include_proto!("dmp.v1");
}

/// The encoded file descriptor set, for gRPC server reflection.
pub const FILE_DESCRIPTOR_SET: &[u8] = tonic::include_file_descriptor_set!("dmp_descriptor");

pub mod codec;
pub mod obstacle_json;
pub mod primitive;
pub mod status;
