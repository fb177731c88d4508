//! What a served run needs of the server, and nothing more: the clock, the compute pools, the robots' state bus,
//! the ROS 2 outbox, the shutdown signal, and the counters and histograms it keeps. A stream is handed this, never
//! the services' shared state.

use std::sync::atomic::AtomicU64;
use std::time::Instant;

use tokio_util::sync::CancellationToken;

use super::compute::Compute;
use super::histograms::Histograms;
use super::outbox::Ros2Out;
use crate::cells::robot_bus::RobotBus;
use crate::clock::Clock;
use crate::connections::stream_permits::StreamPermits;

/// The server's parts a run uses.
#[derive(Debug)]
pub(crate) struct RunContext {
    /// Wall time and pacing instants.
    pub clock: Clock,
    /// The compute pools and their admission budgets.
    pub compute: Compute,
    /// Publishes executing robots' states (over Zenoh when it is on).
    pub robots: RobotBus,
    /// Where the streams hand their segments to ROS 2 (empty without `ros2.domain`).
    pub ros2_out: Ros2Out,
    /// Cancelled when the server shuts down: every stream ends.
    pub shutdown: CancellationToken,
    /// One permit per open stream (real-time pacing scales with the executions open).
    pub streams: StreamPermits,
    /// Traffic counters.
    pub counters: Counters,
    /// What only the streams measure, for the metrics.
    pub histograms: Histograms,
}

impl RunContext {
    /// Executions open now (what real-time pacing scales with).
    pub(crate) fn open_streams(&self) -> usize {
        self.streams.open_executions()
    }
}

/// What the server has done so far.
#[derive(Debug)]
pub(crate) struct Counters {
    /// When the server started.
    pub started: Instant,
    /// Segments sent (a group segment counts once per member).
    pub segments_sent: AtomicU64,
}

impl Default for Counters {
    fn default() -> Self {
        Self { started: Instant::now(), segments_sent: Default::default() }
    }
}

#[cfg(test)]
impl RunContext {
    /// A context for unit tests on `clock`: the default configuration, no Zenoh, no ROS 2.
    pub(crate) fn for_tests(clock: Clock) -> Self {
        let config = crate::config::Config::default();
        Self {
            clock,
            compute: Compute::start(&config.compute).expect("compute threads start"),
            robots: RobotBus::new(None),
            ros2_out: Ros2Out::default(),
            shutdown: CancellationToken::new(),
            streams: StreamPermits::new(&config.limits),
            counters: Counters::default(),
            histograms: Histograms::default(),
        }
    }
}
