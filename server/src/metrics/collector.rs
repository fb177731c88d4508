//! The metrics read at each scrape from the server's own counters and from `GetStats`.

use std::fmt;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use prometheus_client::collector::Collector;
use prometheus_client::encoding::{DescriptorEncoder, EncodeLabelSet, EncodeMetric};
use prometheus_client::metrics::MetricType;
use prometheus_client::metrics::counter::ConstCounter;
use prometheus_client::metrics::gauge::ConstGauge;

use crate::grpc::server::ServerServiceImpl;
use crate::grpc::shared::ServiceState;

/// Renders the server's metrics at each scrape.
#[derive(Debug)]
pub(crate) struct ServerCollector {
    state: Arc<ServiceState>,
    /// The Zenoh bridge's count of refused payloads (none without Zenoh).
    malformed: Option<Arc<AtomicU64>>,
}

impl ServerCollector {
    /// The metrics of `state`, and of the Zenoh bridge's `malformed` counter.
    pub(crate) fn new(state: Arc<ServiceState>, malformed: Option<Arc<AtomicU64>>) -> Self {
        Self { state, malformed }
    }
}

/// One metric family being written.
struct Family<'a, 'b> {
    encoder: &'b mut DescriptorEncoder<'a>,
}

impl Family<'_, '_> {
    fn gauge(&mut self, name: &str, help: &str, value: f64) -> fmt::Result {
        ConstGauge::new(value).encode(self.encoder.encode_descriptor(name, help, None, MetricType::Gauge)?)
    }

    /// `name` without `_total`: the encoding adds it.
    fn counter(&mut self, name: &str, help: &str, value: u64) -> fmt::Result {
        ConstCounter::new(value).encode(self.encoder.encode_descriptor(
            name,
            help,
            None,
            MetricType::Counter,
        )?)
    }

    fn gauges<L: EncodeLabelSet>(
        &mut self,
        name: &str,
        help: &str,
        values: impl IntoIterator<Item = (L, f64)>,
    ) -> fmt::Result {
        let mut family = self.encoder.encode_descriptor(name, help, None, MetricType::Gauge)?;
        for (labels, value) in values {
            ConstGauge::new(value).encode(family.encode_family(&labels)?)?;
        }
        Ok(())
    }

    fn counters<L: EncodeLabelSet>(
        &mut self,
        name: &str,
        help: &str,
        values: impl IntoIterator<Item = (L, u64)>,
    ) -> fmt::Result {
        let mut family = self.encoder.encode_descriptor(name, help, None, MetricType::Counter)?;
        for (labels, value) in values {
            ConstCounter::new(value).encode(family.encode_family(&labels)?)?;
        }
        Ok(())
    }

    fn histogram(
        &mut self,
        name: &str,
        help: &str,
        h: &prometheus_client::metrics::histogram::Histogram,
    ) -> fmt::Result {
        h.encode(self.encoder.encode_descriptor(name, help, None, MetricType::Histogram)?)
    }
}

impl Collector for ServerCollector {
    fn encode(&self, mut encoder: DescriptorEncoder<'_>) -> fmt::Result {
        let s = &self.state;
        let stats = ServerServiceImpl::new(s.clone()).stats();
        let cells = s.cells.all();
        let mut f = Family { encoder: &mut encoder };
        let per_cell = |value: &dyn Fn(&crate::cells::cell::Cell) -> usize| {
            cells.iter().map(|c| ([("cell", c.name().to_owned())], value(c) as f64)).collect::<Vec<_>>()
        };
        f.gauges(
            "dmp_streams",
            "Streams executing in the cell now (Execute, Session, ExecuteGroup: one per stream).",
            per_cell(&|c| c.streams()),
        )?;
        f.gauges(
            "dmp_robots",
            "Robots the cell sees now: its streams' robots and other servers' over Zenoh.",
            per_cell(&|c| c.robot_count()),
        )?;
        f.gauges(
            "dmp_obstacles",
            "Obstacles in the cell's scene now.",
            per_cell(&|c| c.snapshot().obstacles.len()),
        )?;
        f.gauge(
            "dmp_open_streams",
            "Streams open now: executions and scene watches.",
            f64::from(stats.open_streams),
        )?;
        f.counter(
            "dmp_segments_sent",
            "Segments handed to their gRPC streams (a group segment counts once per member).",
            stats.segments_sent,
        )?;
        f.histogram(
            "dmp_segment_lateness_seconds",
            "Real-time streams: how late the first point of a segment was when the server handed the segment to its \
             gRPC stream, seconds (0 when it was handed over before it was due). Not the lateness at the robot.",
            &s.runs.histograms.segment_lateness,
        )?;
        f.histogram(
            "dmp_obstacle_update_to_segment_seconds",
            "Real-time streams: from an obstacle update received by the server (a Zenoh or gRPC put or delete, an \
             expiry) to the first segment of each stream of the cell computed with it, handed to its gRPC stream, \
             seconds. The publisher's put time is not known to the server.",
            &s.runs.histograms.obstacle_update_to_segment,
        )?;
        let refusals = s.runs.compute.admission.refusals().into_iter().chain(s.runs.streams.refusals());
        let refusals = refusals.chain([("limits.max_server_bytes", s.memory.refusals())]);
        f.counters(
            "dmp_admissions_refused",
            "Requests and streams refused for want of resources (RESOURCE_EXHAUSTED), by the setting that refused \
             them.",
            refusals.map(|(reason, n)| ([("reason", reason)], n)),
        )?;
        f.counter(
            "dmp_zenoh_malformed_payloads",
            "Zenoh payloads refused: malformed, invalid, or over a limit.",
            self.malformed.as_ref().map_or(0, |m| m.load(Ordering::Relaxed)),
        )?;
        f.counter(
            "dmp_robot_states_dropped",
            "Robot states dropped (Zenoh and Session): a stamp too far from the server's clock, a position out of the \
             workspace, a speed over the limit.",
            stats.robot_states_dropped,
        )?;
        f.counters(
            "dmp_store_operations",
            "Operations on the store of primitives, by kind (put: a learn or a put; list: one page).",
            s.store.operations().map(|(kind, n)| ([("kind", kind)], n)),
        )?;
        f.gauge(
            "dmp_memory_reserved_bytes",
            "Memory reserved now by streams and scenes, bytes.",
            s.memory.used() as f64,
        )?;
        f.gauge(
            "dmp_memory_budget_bytes",
            "The memory budget of streams and scenes (limits.max_server_bytes), bytes.",
            s.memory.limit() as f64,
        )?;
        f.gauges(
            "dmp_compute_work_reserved",
            "Work units reserved now: per second by real-time streams, in all by queued or running plans and learns.",
            [([("pool", "realtime")], stats.realtime_work_reserved), ([("pool", "batch")], stats.batch_work_reserved)],
        )?;
        f.gauges(
            "dmp_compute_work_budget",
            "The work budgets: per second for real-time streams, at once for plans and learns.",
            [
                ([("pool", "realtime")], stats.realtime_work_budget),
                ([("pool", "batch")], stats.batch_work_budget),
            ],
        )?;
        f.gauges(
            "dmp_compute_jobs_running",
            "Computations running now, by pool.",
            [
                ([("pool", "realtime")], f64::from(stats.realtime_jobs_running)),
                ([("pool", "batch")], f64::from(stats.batch_jobs_running)),
            ],
        )?;
        f.counter(
            "dmp_compute_jobs_abandoned",
            "Computations skipped because their client had gone.",
            stats.jobs_abandoned,
        )?;
        f.counter("dmp_compute_jobs_failed", "Computations that failed unexpectedly.", stats.jobs_failed)?;
        ConstCounter::new(stats.cpu_seconds).encode(f.encoder.encode_descriptor(
            "dmp_process_cpu_seconds",
            "CPU time of the process (user and system, every thread), seconds.",
            None,
            MetricType::Counter,
        )?)?;
        f.gauge(
            "dmp_process_resident_memory_bytes",
            "Resident memory of the process, bytes.",
            stats.rss_bytes as f64,
        )?;
        f.gauge("dmp_uptime_seconds", "Seconds since the server started.", stats.uptime_s)
    }
}
