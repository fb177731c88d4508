//! What only the streams can measure, for the Prometheus endpoint ([`crate::metrics`]): how late each real-time
//! segment was handed to its gRPC stream, and how long an obstacle update took to reach a segment. Observed on the
//! streams' async tasks, never on the compute threads.

use prometheus_client::metrics::histogram::Histogram;

/// The histograms that only the streams can measure (every other metric is read from counters kept elsewhere).
#[derive(Debug)]
pub(crate) struct Histograms {
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
    pub(crate) fn handed_over(
        &self,
        now_unix_s: f64,
        first_point_unix_s: Option<f64>,
        update_unix_s: Option<f64>,
    ) {
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
