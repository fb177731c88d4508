//! What a stream costs in memory, estimated before it is admitted: the segments it may hold at once (those in its
//! channel, the one being computed and the one being encoded), its history for rollbacks and a fixed share for its
//! run and task. A stream is refused when one segment exceeds `limits.max_segment_bytes`, when the whole exceeds
//! `limits.max_stream_bytes`, or when the server's budget (`limits.max_server_bytes`) cannot hold it; otherwise
//! its reservation lives in its producer task and is released when the task ends (the run's end, a cancel, the
//! client leaving, whether or not it read anything).

use super::pacing::StreamConfig;
use super::pacing::history_len;
use crate::config::RequestLimits;
use crate::error::ServerError;
use crate::memory::{MemoryBudget, MemoryReservation, check_within};

/// Bytes of one point of one dimension in a segment: position, velocity, acceleration.
const SEGMENT_BYTES_PER_VALUE: usize = 3 * 8;

/// A segment's fixed part (its header fields, the proto's and the channel's overhead).
const SEGMENT_OVERHEAD: usize = 512;

/// Bytes of one point of one dimension in the history: position, velocity, and a phase per point.
const HISTORY_BYTES_PER_VALUE: usize = 2 * 8;

/// Segments held besides the channel's: the one being computed and the one being encoded for the connection.
const SEGMENTS_IN_FLIGHT: usize = 2;

/// A stream's run (the engine's state, the primitive, its task and channel), apart from segments and history.
const RUN_OVERHEAD: usize = 64 * 1024;

/// A stream's estimated memory.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StreamBytes {
    /// One segment.
    pub segment: usize,
    /// The whole stream.
    pub total: usize,
}

impl StreamBytes {
    /// The estimate of a stream of `dim` dimensions paced by `cfg`, whose channel holds `buffered` segments.
    pub fn estimate(cfg: &StreamConfig, dim: usize, buffered: usize) -> Self {
        let segment =
            cfg.segment_points.saturating_mul(dim).saturating_mul(SEGMENT_BYTES_PER_VALUE) + SEGMENT_OVERHEAD;
        // The history keeps whole records: up to one segment more than asked, and a spare one recycled.
        let history_points = history_len(cfg).saturating_add(2 * cfg.segment_points);
        let history =
            history_points.saturating_mul(dim).saturating_mul(HISTORY_BYTES_PER_VALUE) + 8 * history_points;
        let total = segment
            .saturating_mul(buffered + SEGMENTS_IN_FLIGHT)
            .saturating_add(history)
            .saturating_add(RUN_OVERHEAD);
        Self { segment, total }
    }

    /// Checks the estimate against the limits and reserves it from `budget`: the stream's reservation, or
    /// ResourceExhausted naming the limit, the stream's bytes and the limit's value.
    pub fn admit(
        self,
        limits: &RequestLimits,
        budget: &MemoryBudget,
    ) -> Result<MemoryReservation, ServerError> {
        check_within(
            "one segment of this stream",
            self.segment,
            "max_segment_bytes",
            limits.max_segment_bytes,
        )?;
        check_within("this stream", self.total, "max_stream_bytes", limits.max_stream_bytes)?;
        budget.reserve("this stream", self.total)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use dmp::Stepping;
    use std::time::Duration;

    fn cfg(segment_points: usize) -> StreamConfig {
        StreamConfig {
            stepping: Stepping::rk4(1e-3),
            segment_points,
            realtime: false,
            lookahead: Duration::from_millis(50),
            max_duration: 1.0,
            urgency: None,
        }
    }

    #[test]
    fn long_wide_segments_are_refused_and_small_streams_admitted() {
        let limits = RequestLimits::default();
        let budget = MemoryBudget::new(limits.max_server_bytes);
        // The default stream of a 7-D arm: well within every limit.
        let small = StreamBytes::estimate(&cfg(10), 7, 4);
        let r = small.admit(&limits, &budget).unwrap();
        assert_eq!(budget.used(), small.total);
        drop(r);
        assert_eq!(budget.used(), 0);
        // 10 s segments of a 64-D primitive: one segment alone is over 15 MB.
        let big = StreamBytes::estimate(&cfg(10_000), 64, 4);
        assert!(big.segment > 15_000_000);
        let msg = big.admit(&limits, &budget).unwrap_err().to_string();
        assert!(
            msg.contains("max_segment_bytes = 4194304") && msg.contains(&big.segment.to_string()),
            "{msg}"
        );
        assert_eq!(budget.used(), 0);
        // Segments within their limit, but too many of them.
        let many = StreamBytes::estimate(&cfg(2_000), 64, 100);
        let msg = many.admit(&limits, &budget).unwrap_err().to_string();
        assert!(msg.contains("max_stream_bytes"), "{msg}");
    }
}
