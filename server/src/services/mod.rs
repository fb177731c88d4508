//! The gRPC services, one file each, and what a streamed execution asks for (`stream_request.rs`).

pub mod motion;
pub mod primitives;
pub mod scene;
pub mod server;
mod stream_request;
