//! The DMP cell's server: a thin adapter around the `dmp` engine. It stores learned primitives per robot (redb),
//! takes obstacle updates over Zenoh (and gRPC), and streams trajectory segments over gRPC to many robots at once.
//!
//! The modules form layers; each imports only from the layers above it in this table, never from below.
//!
//! | layer | module | what it holds |
//! | --- | --- | --- |
//! | foundations | [`error`], [`clock`], [`memory`], [`config`], [`wire`] | typed errors and their gRPC status, the injected clock, the memory budget, the configuration (file, then flags), the configuration's bounds on the wire's conversions |
//! | who and where | [`access`], [`store`], [`connections`] | identities and roles, the embedded store of primitives and robot records, what the server knows of each gRPC connection (its streams, its batched writes, its stream permits) |
//! | the cells' state | [`cells`] | each cell's obstacles and robot states, staleness, which robot states it takes, the robots' state bus, and which server of a plant serves a cell |
//! | runs | [`runs`] | served runs: the engine's execution paced into streams, on the compute pools, admitted by cost |
//! | the plant | [`plant`] | several servers on one Zenoh network: discovery, replicated primitives, fail-over |
//! | transports | [`grpc`], [`zenoh_bridge`], [`ros2`], [`metrics`], [`telemetry`] | the gRPC services, the Zenoh bridge that feeds the scenes, ROS 2 over rmw_zenoh, Prometheus, OpenTelemetry |
//! | assembly | [`server`] | starting the parts above in order, and running until shutdown |

// The server's docs are for its maintainers: they link to the crate's private modules on purpose.
#![allow(rustdoc::private_intra_doc_links)]
#![warn(missing_docs)]
#![warn(unreachable_pub)]

pub mod clock;
pub mod config;

pub(crate) mod error;
pub(crate) mod memory;
pub(crate) mod wire;

pub mod access;
pub(crate) mod connections;
pub mod store;

pub mod cells;

pub mod runs;

pub(crate) mod plant;

pub(crate) mod grpc;
pub(crate) mod metrics;
pub mod ros2;
pub mod telemetry;
pub mod zenoh_bridge;

pub mod server;

pub use server::{ServerHandle, run, start};
