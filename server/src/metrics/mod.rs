//! The Prometheus endpoint (`--metrics-addr`, off by default): what `GetStats` reports and the counters the
//! server's parts keep, rendered in the OpenMetrics text format at each scrape, plus two histograms that only
//! the streams can measure.
//!
//! One source of truth: nothing is counted twice. Each counter lives where its event happens (the stream, the
//! store, the admission budgets, the Zenoh bridge) and is read at scrape time ([`collector`]); only the histograms
//! ([`crate::runs::histograms::Histograms`]) exist for the metrics alone. Observations are made on the streams' async tasks, never on the
//! real-time compute threads, and a scrape reads atomics and each cell's current snapshot.
//!
//! | metric | type | labels | what |
//! | --- | --- | --- | --- |
//! | `dmp_streams` | gauge | `cell` | streams executing in the cell (Execute, Session, ExecuteGroup) |
//! | `dmp_robots` | gauge | `cell` | robots the cell sees (its streams' and other servers' over Zenoh) |
//! | `dmp_obstacles` | gauge | `cell` | obstacles in the cell's scene |
//! | `dmp_open_streams` | gauge | | every stream open, executions and scene watches |
//! | `dmp_segments_sent_total` | counter | | segments handed to their streams (a group's once per member) |
//! | `dmp_segment_lateness_seconds` | histogram | | real-time streams: how late a segment's first point was when the segment was handed to its gRPC stream (0 when before it was due) |
//! | `dmp_obstacle_update_to_segment_seconds` | histogram | | real-time streams: from an obstacle update received (Zenoh or gRPC put or delete, an expiry) to the first segment of each stream of the cell computed with it, handed to its gRPC stream |
//! | `dmp_admissions_refused_total` | counter | `reason` | requests and streams refused, by the setting that refused them |
//! | `dmp_zenoh_malformed_payloads_total` | counter | | Zenoh payloads refused (malformed, invalid, over a limit) |
//! | `dmp_robot_states_dropped_total` | counter | | robot states dropped (stamp, workspace, speed) |
//! | `dmp_store_operations_total` | counter | `kind` | store operations: `put`, `get`, `list`, `delete` |
//! | `dmp_memory_reserved_bytes`, `dmp_memory_budget_bytes` | gauge | | the memory budget of streams and scenes |
//! | `dmp_compute_work_reserved`, `dmp_compute_work_budget` | gauge | `pool` | work units (per second for `realtime`) |
//! | `dmp_compute_jobs_running` | gauge | `pool` | computations running |
//! | `dmp_compute_jobs_abandoned_total`, `dmp_compute_jobs_failed_total` | counter | | computations skipped (client gone), failed |
//! | `dmp_process_cpu_seconds_total` | counter | | CPU time of the process, user and system |
//! | `dmp_process_resident_memory_bytes` | gauge | | resident memory |
//! | `dmp_uptime_seconds` | gauge | | since the server started |
//!
//! What the server cannot measure: the lateness at the robot (the arrival of a segment is the client's to see:
//! `dmpctl load` reports it), and the time from a perception node's put (obstacles carry no stamp of their
//! publisher; the histogram starts when the server received the update).

mod collector;
pub(crate) mod endpoint;

use std::net::SocketAddr;
use std::sync::Arc;
use std::sync::atomic::AtomicU64;

pub(crate) use collector::ServerCollector;

use crate::error::ServerError;
use crate::grpc::shared::ServiceState;

/// Serves the metrics of `state` (and of the Zenoh bridge's `malformed` counter) on `metrics_addr` when the
/// configuration sets it, until the server shuts down; returns the address bound.
pub(crate) async fn serve_configured(
    state: &Arc<ServiceState>,
    malformed: Option<Arc<AtomicU64>>,
) -> Result<Option<SocketAddr>, ServerError> {
    let Some(addr) = state.config.metrics_addr else { return Ok(None) };
    let mut registry = prometheus_client::registry::Registry::default();
    registry.register_collector(Box::new(ServerCollector::new(state.clone(), malformed)));
    Ok(Some(endpoint::serve(addr, registry, state.runs.shutdown.clone()).await?.0))
}
