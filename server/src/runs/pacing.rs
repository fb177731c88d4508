//! Real-time pacing: how far ahead of the wall clock segments are computed, how often a stream wakes, how soon the
//! first point is due, and the margin of a rollback. Why each value was chosen, with the figures, is in
//! BENCHMARKS.md.

use std::time::Duration;

use dmp::Stepping;

use crate::connections::write_batching::Urgency;

/// How a stream is paced and bounded.
#[derive(Debug, Clone)]
pub struct StreamConfig {
    /// Output and internal steps.
    pub stepping: Stepping,
    /// Points per segment.
    pub segment_points: usize,
    /// Real time (true) or as fast as the client reads.
    pub realtime: bool,
    /// Real-time: how far ahead of the wall clock segments are computed.
    pub lookahead: Duration,
    /// The run ends at this time (seconds of run time).
    pub max_duration: f64,
    /// The connection's urgency (a superseding segment is written at once), when it batches its writes.
    pub urgency: Option<Urgency>,
}

/// Real time: how far beyond the lookahead one wake-up computes (the producer sleeps about this long between two
/// wake-ups), with few streams. A longer refill means fewer wake-ups (each costs a timer, the cell-mates' states, a
/// state published and a write to the connection) but longer ones, which a change must wait behind.
pub const MIN_REFILL: Duration = Duration::from_millis(30);

/// Real time: the longest refill, with many streams (and what buffers and histories are sized for).
pub const MAX_REFILL: Duration = Duration::from_millis(60);

/// Stream wake-ups per second beyond which refills grow (from [`MIN_REFILL`] at 300 streams to [`MAX_REFILL`]
/// at 600).
pub const WAKE_UPS_PER_SECOND: f64 = 10_000.0;

/// Real time: how long after the request the run's first point is due.
pub const FIRST_POINT_DELAY: Duration = Duration::from_millis(20);

/// Margin added to the robot's current time when a change rolls the run back: the superseding segment must reach
/// the robot before its first point is due, also on a busy host that delays a task by several milliseconds.
pub const ROLLBACK_MARGIN: Duration = Duration::from_millis(10);

/// The refill of a wake-up while the server carries `streams` streams: wake-ups stay under
/// [`WAKE_UPS_PER_SECOND`] as long as the refill can grow.
pub fn refill(streams: usize) -> Duration {
    let s = (streams as f64 / WAKE_UPS_PER_SECOND).clamp(MIN_REFILL.as_secs_f64(), MAX_REFILL.as_secs_f64());
    Duration::from_secs_f64(s)
}

/// Real time: the most segments one wake-up computes.
pub fn refill_segments(cfg: &StreamConfig) -> usize {
    let seg = cfg.segment_points as f64 * cfg.stepping.dt;
    (MAX_REFILL.as_secs_f64() / seg).ceil() as usize + 1
}

/// Output points kept for rollbacks: everything a stream can have sent ahead of the robot (the lookahead, one
/// refill and one segment), plus a margin.
pub fn history_len(cfg: &StreamConfig) -> usize {
    let dt = cfg.stepping.dt;
    let refill = if cfg.realtime { MAX_REFILL.as_secs_f64() } else { 0.0 };
    let ahead = cfg.lookahead.as_secs_f64() + refill + cfg.segment_points as f64 * dt;
    ((ahead / dt).ceil() as usize + 2).max(16)
}

#[cfg(test)]
mod tests {
    use super::*;
    use dmp::Stepping;

    #[test]
    fn refills_grow_with_the_streams_between_their_bounds() {
        assert_eq!(refill(0), MIN_REFILL);
        assert_eq!(refill(100), MIN_REFILL);
        assert_eq!(refill(450), Duration::from_millis(45));
        assert_eq!(refill(600), MAX_REFILL);
        assert_eq!(refill(1_000), MAX_REFILL);
        let cfg = StreamConfig {
            stepping: Stepping::rk4(1e-3),
            segment_points: 10,
            realtime: true,
            lookahead: Duration::from_millis(50),
            max_duration: 1.0,
            urgency: None,
        };
        assert_eq!(refill_segments(&cfg), 7, "room for the longest refill");
    }
}
