//! The client side of the DMP cell: the `dmpctl` command line and what it is built from.
//!
//! | concept | module |
//! | --- | --- |
//! | reading scenario files, errors at the field | [`scenario_file`] |
//! | offline runs and timing | [`offline`] |
//! | output files | [`outputs`] |
//! | figures | [`plot`] |
//! | the gRPC client of the server's three services | [`grpc`] |
//! | the JSON of a stored record (the wire's conversions are `dmp_proto`'s) | [`convert`] |
//! | the setpoints in force after a stream of segments (supersession) | [`setpoints`] |
//! | publishing obstacles over Zenoh (perception nodes) | [`zenoh_pub`] |
//! | demonstrations from CSV | [`demo_csv`] |
//! | the server-side commands of `dmpctl` | [`remote`] |
//! | `scenario run` through the server | [`remote_scenario`] |
//! | simulated robots (`dmpctl sim`) | [`sim`] |
//! | the load generator (`dmpctl load`) | [`load`] |
//! | the command line | [`cli`] |

pub mod cli;
pub mod convert;
pub mod demo_csv;
pub mod error;
pub mod grpc;
pub mod load;
pub mod offline;
pub mod outputs;
pub mod plot;
pub mod remote;
pub mod remote_scenario;
pub mod scenario_file;
pub mod setpoints;
pub mod sim;
pub mod zenoh_pub;

pub use error::ClientError;
pub use grpc::DmpClient;
pub use setpoints::Setpoints;
