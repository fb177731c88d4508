//! The gRPC services, one file each.

pub mod primitives;
pub mod scene;
pub mod motion;
