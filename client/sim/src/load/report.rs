//! The JSON object `dmpctl load` prints.

use serde::Serialize;

use super::stats::{Percentiles, SignedPercentiles};

/// How lateness is measured (said in the report).
pub(crate) const LATENESS_DEFINITION: &str = "lateness_ms: per segment, arrival at the robot minus the due time of its \
     first point, clamped at 0 (an early segment counts 0); arrival_minus_due_ms: the same, signed (negative: \
     early). A setpoint is on time when the segment that carries it in the end (the latest one covering its \
     time) arrived before it was due; expected setpoints that never arrived are not on time.";

/// One kind of error and how often it happened.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct ErrorCount {
    /// The message.
    pub message: String,
    /// Occurrences.
    pub count: u64,
    /// The first robot it happened to, if a robot's.
    pub robot: Option<String>,
}

/// The outcome of a load run.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct LoadReport {
    /// Robots asked for.
    pub robots: usize,
    /// Cells (of `cell_size` robots).
    pub cells: usize,
    /// Robots per cell.
    pub cell_size: usize,
    /// Setpoints per second per robot.
    pub rate_hz: f64,
    /// Segment length.
    pub segment_ms: f64,
    /// Length of the measurement, from the first start to the stops.
    pub duration_s: f64,
    /// Scene updates per second (over Zenoh).
    pub scene_updates_hz: f64,
    /// Dimension of the motions (of the position, for pose robots).
    pub dim: usize,
    /// Pose robots at the Panda profile (`--pose`).
    pub pose: bool,
    /// The primitives' time scale (a new goal every tau).
    pub tau_s: f64,
    /// HTTP/2 connections to the server.
    pub connections: usize,
    /// Seconds the robots' starts are spread over.
    pub stagger_s: f64,
    /// Seconds to set up (connections, obstacles, primitives).
    pub setup_s: f64,
    /// Sessions that opened.
    pub streams_started: u64,
    /// Robots whose setup or stream failed.
    pub streams_failed: u64,
    /// Setpoints due during the measurement (rate x time each robot's stream was open, from its first due
    /// setpoint to the end, summed).
    pub setpoints_expected: u64,
    /// Of which on time.
    pub setpoints_on_time: u64,
    /// Their share, percent.
    pub setpoints_on_time_percent: f64,
    /// Segments whose first point was due during the measurement.
    pub segments: u64,
    /// Of which arrived after their first point was due.
    pub late_segments: u64,
    /// Of the late ones, the streams' first segments (due at the stream's start, so late by the transport time).
    pub late_first_segments: u64,
    /// Segments that replaced points of earlier ones (after a goal change or a scene update).
    pub superseding_segments: u64,
    /// Segments with status STALLED.
    pub stalled_segments: u64,
    /// Segments with status COLLISION.
    pub collision_segments: u64,
    /// Goal changes sent.
    pub retargets: u64,
    /// What the lateness figures are.
    pub lateness_definition: &'static str,
    /// Lateness of the segments, clamped at 0.
    pub lateness_ms: Percentiles,
    /// Lateness of the superseding segments, clamped at 0.
    pub superseding_lateness_ms: Percentiles,
    /// Late segments by the second they arrived in, from the first robot's start (the last second also counts
    /// the stops).
    pub late_segments_per_second: Vec<u64>,
    /// Arrival minus due time of the segments, signed.
    pub arrival_minus_due_ms: SignedPercentiles,
    /// Scene updates put over Zenoh.
    pub scene_updates_sent: u64,
    /// Updates no segment of their cell accounted for before the cell's next update or the end.
    pub scene_updates_unanswered: u64,
    /// From a Zenoh obstacle update to the first segment, at a robot of the cell, computed with the new scene.
    pub scene_update_latency_ms: Percentiles,
    /// Server CPU over the measurement, percent of one core.
    pub server_cpu_percent: Option<f64>,
    /// Server resident memory at the end of the measurement, MiB.
    pub server_rss_mib: Option<f64>,
    /// At its beginning.
    pub server_rss_mib_start: Option<f64>,
    /// Largest sample.
    pub server_rss_mib_max: Option<f64>,
    /// Once a second.
    pub server_rss_mib_series: Vec<f64>,
    /// Most streams open at a sample.
    pub server_open_streams_max: Option<u32>,
    /// Segments the server sent during the measurement.
    pub server_segments_sent: Option<u64>,
    /// This load generator's CPU over the measurement, percent of one core (Linux).
    pub generator_cpu_percent: Option<f64>,
    /// Each server's part: one with `--server`; with `--via-zenoh-discovery` one per server found (the
    /// `server_*` figures above are then the first server's).
    pub servers: Vec<ServerPart>,
    /// What went wrong, most frequent first.
    pub errors: Vec<ErrorCount>,
}

/// One server's part of a load run.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct ServerPart {
    /// Its plant id (empty with `--server`).
    pub server_id: String,
    /// Its gRPC address.
    pub grpc_address: String,
    /// The load's cells it serves.
    pub cells: Vec<String>,
    /// Its robots.
    pub robots: usize,
    /// Setpoints due from it.
    pub setpoints_expected: u64,
    /// Of which on time.
    pub setpoints_on_time: u64,
    /// Their share, percent.
    pub setpoints_on_time_percent: f64,
    /// Lateness of its segments, clamped at 0.
    pub lateness_ms: Percentiles,
    /// Its CPU over the measurement, percent of one core.
    pub cpu_percent: Option<f64>,
    /// Its largest resident memory sample, MiB.
    pub rss_mib_max: Option<f64>,
    /// Segments it sent during the measurement.
    pub segments_sent: Option<u64>,
}

/// A share in percent, floored to two decimals (0 of nothing).
pub(crate) fn percent(part: u64, whole: u64) -> f64 {
    if whole > 0 { (1e4 * part as f64 / whole as f64).floor() / 1e2 } else { 0.0 }
}
