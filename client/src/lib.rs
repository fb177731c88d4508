//! The client library of the DMP cell, for robot drivers and perception nodes: tonic, the schema and tokio.
//!
//! | concept | module |
//! | --- | --- |
//! | the gRPC client of the server's services | [`grpc`] |
//! | TLS and tokens for a secured server | [`connect`] |
//! | the setpoints in force after a stream of segments (supersession) | [`setpoints`] |
//! | the JSON of a stored record (the wire's conversions are `dmp_proto`'s) | [`convert`] |
//! | publishing obstacles over Zenoh (perception nodes; feature `zenoh`) | `zenoh_pub` |
//! | finding a cell's server in a plant of servers, over Zenoh (feature `zenoh`) | `discovery` |
//! | a session that resumes on the cell's new server when its server goes (fail-over; feature `zenoh`) | `resume` |
//! | errors | [`error`] |
//!
//! The `dmpctl` command line is the `dmpctl` crate; simulated robots and the load generator are `dmp-sim`; figures
//! are `dmp-plot`.

pub mod connect;
pub mod convert;
#[cfg(feature = "zenoh")]
pub mod discovery;
pub mod error;
pub mod grpc;
#[cfg(feature = "zenoh")]
pub mod resume;
pub mod session;
pub mod setpoints;
#[cfg(feature = "zenoh")]
pub mod zenoh_pub;

pub use error::ClientError;
pub use grpc::DmpClient;
pub use setpoints::Setpoints;
