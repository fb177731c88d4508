//! The gRPC services, one file each.

pub mod motion;
pub mod primitives;
pub mod scene;
pub mod server;
