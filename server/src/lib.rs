//! The DMP cell's server: a thin adapter around the `dmp` engine. It stores learned primitives per robot (redb),
//! takes obstacle updates over Zenoh (and gRPC), and streams trajectory segments over gRPC to many robots at once.
//!
//! | concept | module |
//! | --- | --- |
//! | configuration (file, then flags) | [`config`], [`cli`] |
//! | wall time and pacing, injected | [`clock`] |
//! | the limits of the configuration on the wire's conversions (which are `dmp_proto`'s) | [`convert`] |
//! | errors and their gRPC status | [`error`] |
//! | the cells a server serves, each with its own scene | [`cells`] |
//! | one cell: its obstacles (versioned) and its robots' states | [`cell`] |
//! | shared state of the services | [`state`] |
//! | the embedded store of primitives (redb) | [`store`] |
//! | obstacles nobody updates any more: stale, dropped, or holding the robots | [`staleness`] |
//! | robots' states: local scene and `dmp/<cell>/robots/<id>/state` | [`robots`] |
//! | which robot states from outside a cell takes (stamp, workspace, speed) | [`state_admission`] |
//! | one stream per executing robot of a cell, and taking over | [`executing`] |
//! | the Zenoh session and the subscribers that feed the scene | [`zenoh_bridge`] |
//! | ROS 2 over rmw_zenoh: MoveIt's collision objects and tracked obstacles into the scene | [`ros2`] |
//! | the gRPC services, one file each | [`services`] |
//! | served runs: the engine's execution paced into gRPC streams | [`executor`] |
//! | many streams' segments in one write on a connection | [`write_batching`] |
//! | a connection's streams and requests, and its idle timeout | [`connection`] |
//! | who may open a stream: pools, per connection, per client | [`stream_permits`] |
//! | the server's memory budget and its reservations | [`memory`] |
//! | traces to OpenTelemetry (`--otlp-endpoint`) | [`telemetry`] |
//! | several servers on one Zenoh network: discovery, replicated primitives | [`plant`] |
//! | the Prometheus endpoint: the counters above and two histograms, at each scrape | [`metrics`] |

pub mod access;
pub mod cell;
pub mod cells;
pub mod cli;
pub mod clock;
pub mod compute;
pub mod config;
pub mod connection;
pub mod convert;
pub mod error;
pub mod executing;
pub mod executor;
pub mod exposure;
pub mod memory;
pub mod metrics;
pub mod plant;
pub mod robots;
pub mod ros2;
pub mod run;
pub mod services;
pub mod staleness;
pub mod state;
pub mod state_admission;
pub mod store;
pub mod stream_permits;
pub mod telemetry;
pub mod tls;
pub mod write_batching;
pub mod zenoh_bridge;
pub mod zenoh_threads;
