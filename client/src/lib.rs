//! The client library of the DMP cell, for robot drivers and perception nodes: tonic, the schema and tokio.
//!
//! | concept | module |
//! | --- | --- |
//! | the gRPC client of the server's services | [`grpc`] |
//! | an open session: its commands and its segments | `session` ([`grpc::Session`]) |
//! | the streams a call returns | `streams` ([`grpc::SegmentStream`] ...) |
//! | TLS and tokens for a secured server | [`connect`] |
//! | whether an `http://` server speaks TLS (the hint to use `https://`) | [`tls_probe`] |
//! | the setpoints in force after a stream of segments (supersession) | [`setpoints`] |
//! | publishing obstacles over Zenoh (perception nodes; feature `zenoh`) | `zenoh_pub` |
//! | finding a cell's server in a plant of servers, over Zenoh (feature `zenoh`) | `discovery` |
//! | a session that resumes on the cell's new server when its server goes (fail-over; feature `zenoh`) | `resume` |
//! | errors | `error` ([`ClientError`]) |
//!
//! The modules form layers, each using only those below it: `error`; then `streams`, [`connect`], [`tls_probe`]
//! and [`setpoints`]; `session`; [`grpc`]; then, with Zenoh, `discovery` and `zenoh_pub`, and `resume` on top.
//! Without the feature `zenoh` the crate needs neither Zenoh nor nalgebra: a robot driver compiles the gRPC client,
//! the schema and tokio.
//!
//! The `dmpctl` command line is the `dmpctl` crate; simulated robots and the load generator are `dmp-sim`; figures
//! are `dmp-plot`.

#![warn(missing_docs)]
#![warn(unreachable_pub)]

pub mod connect;
#[cfg(feature = "zenoh")]
pub mod discovery;
mod error;
pub mod grpc;
#[cfg(feature = "zenoh")]
pub mod resume;
mod session;
pub mod setpoints;
mod streams;
pub mod tls_probe;
#[cfg(feature = "zenoh")]
pub mod zenoh_pub;

pub use error::{ClientError, without_source_paths};
pub use grpc::DmpClient;
pub use setpoints::Setpoints;
