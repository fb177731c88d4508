//! The wire of the DMP cell, in one place: the schema (`proto/dmp/v1/*.proto`, compiled without `protoc`), whose
//! messages are both the gRPC payloads and the Zenoh payloads; the Zenoh key expressions; the session builder; and
//! the conversions between the messages, their JSON forms and the engine, both ways, with one error
//! ([`WireError`]) naming the field and the rule.
//!
//! | concept | module |
//! | --- | --- |
//! | the generated messages and services (clients; servers with the feature `server`) | [`v1`] |
//! | field numbers of the messages, from the schema | [`tags`] |
//! | encoding Zenoh payloads | [`codec`] |
//! | Zenoh key expressions, the rule for names in keys | [`keys`] |
//! | decoding Zenoh payloads by encoding | [`payload`] |
//! | the Zenoh session configuration (feature `zenoh`) | `zenoh_session` |
//! | numeric field checks | [`check`] |
//! | obstacle message -> engine | [`obstacle`] |
//! | the JSON obstacle <-> message | [`obstacle_json`] |
//! | superquadrics, ROS solids, footprints | [`shape`] |
//! | avoidance <-> message | [`avoidance`] |
//! | primitives <-> message | [`primitive`] |
//! | demonstrations and learning parameters <-> message | [`learning`] |
//! | a robot's state, checked | [`robot_state`] |
//! | a segment read lazily | [`segment_view`] |

#![warn(missing_docs)]
#![warn(unreachable_pub)]

/// The schema's package `dmp.v1`, generated: its messages, a client of each service and, with the feature `server`,
/// the trait each service's server implements (`*_service_server`).
#[allow(missing_docs, clippy::all, missing_debug_implementations, rust_2018_idioms)]
pub mod v1 {
    tonic::include_proto!("dmp.v1");
}

/// The encoded file descriptor set, for gRPC server reflection (feature `server`).
#[cfg(feature = "server")]
pub const FILE_DESCRIPTOR_SET: &[u8] = tonic::include_file_descriptor_set!("dmp_descriptor");

pub mod avoidance;
pub mod check;
pub mod codec;
mod error;
pub mod keys;
pub mod learning;
pub mod limits;
pub mod obstacle;
pub mod obstacle_json;
pub mod payload;
pub mod primitive;
pub mod robot_state;
pub mod segment_view;
pub mod shape;
pub mod status;
pub mod tags;
#[cfg(feature = "zenoh")]
pub mod zenoh_session;

pub use error::WireError;

#[cfg(test)]
mod accepted_inputs;
