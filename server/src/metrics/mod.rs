//! The Prometheus endpoint (`--metrics-addr`, off by default): what `GetStats` reports and the counters the
//! server's parts keep, rendered in the OpenMetrics text format at each scrape, plus two histograms that only
//! the streams can measure.
//!
//! One source of truth: nothing is counted twice. Each counter lives where its event happens (the stream, the
//! store, the admission budgets, the Zenoh bridge) and is read at scrape time ([`collector`]); only the histograms
//! ([`Histograms`]) exist for the metrics alone. Observations are made on the streams' async tasks, never on the
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
pub mod endpoint;

use prometheus_client::metrics::histogram::Histogram;

pub use collector::ServerCollector;

/// The histograms that only the streams can measure (every other metric is read from counters kept elsewhere).
#[derive(Debug)]
pub struct Histograms {
    /// `dmp_segment_lateness_seconds`.
    pub segment_lateness: Histogram,
    /// `dmp_obstacle_update_to_segment_seconds`.
    pub obstacle_update_to_segment: Histogram,
}

impl Default for Histograms {
    fn default() -> Self {
        Self {
            // The first bucket (0) holds the segments handed over before their first point was due.
            segment_lateness: Histogram::new([0.0, 0.001, 0.002, 0.005, 0.01, 0.02, 0.05, 0.1, 0.25, 1.0]),
            obstacle_update_to_segment: Histogram::new([
                0.0005, 0.001, 0.002, 0.005, 0.01, 0.02, 0.05, 0.1, 0.25, 0.5, 1.0,
            ]),
        }
    }
}

impl Histograms {
    /// A real-time stream handed a segment to its gRPC stream at `now_unix_s`: its first point was due at
    /// `first_point_unix_s`, and it is the first computed with an obstacle update received at `update_unix_s`.
    pub fn handed_over(&self, now_unix_s: f64, first_point_unix_s: Option<f64>, update_unix_s: Option<f64>) {
        if let Some(due) = first_point_unix_s {
            self.segment_lateness.observe((now_unix_s - due).max(0.0));
        }
        if let Some(received) = update_unix_s {
            self.obstacle_update_to_segment.observe((now_unix_s - received).max(0.0));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_early_segment_is_on_time_and_an_update_is_measured_once() {
        let h = Histograms::default();
        // 50 ms ahead: on time (0, the first bucket), not -0.05.
        h.handed_over(100.0, Some(100.05), None);
        // 10 ms late, the first segment computed with an update received 2 ms before.
        h.handed_over(100.0, Some(99.99), Some(99.998));
        let mut registry = prometheus_client::registry::Registry::default();
        registry.register("lateness", "", h.segment_lateness.clone());
        registry.register("update", "", h.obstacle_update_to_segment.clone());
        let mut text = String::new();
        prometheus_client::encoding::text::encode(&mut text, &registry).unwrap();
        for line in [
            "lateness_count 2",
            "lateness_bucket{le=\"0.0\"} 1",
            "lateness_bucket{le=\"0.005\"} 1",
            "lateness_bucket{le=\"0.02\"} 2",
            "update_count 1",
            "update_bucket{le=\"0.001\"} 0",
            "update_bucket{le=\"0.005\"} 1",
        ] {
            assert!(text.lines().any(|l| l == line), "no `{line}` in\n{text}");
        }
    }
}
