//! The gRPC services, one file each, what a streamed execution asks for (`stream_request.rs`), a session's
//! commands checked (`session_commands.rs`), and a held tool from the wire (`tool.rs`).

pub mod motion;
mod motion_resolve;
pub mod primitives;
pub mod robots;
pub mod scene;
pub mod server;
pub(crate) mod session_commands;
mod stream_request;
pub mod tool;
