//! What every service shares.

use std::sync::Arc;

use tokio_util::sync::CancellationToken;

use crate::access::{AccessControl, Caller};
use crate::exposure::Exposure;

use crate::cells::Cells;
use crate::clock::Clock;
use crate::compute::Compute;
use crate::config::Config;
use crate::error::ServerError;
use crate::executing::Executing;
use crate::memory::MemoryBudget;
use crate::robots::RobotBus;
use crate::state_admission::StateAdmission;
use crate::store::Store;
use crate::stream_permits::{Peer, StreamKind, StreamPermit, StreamPermits};

/// The server's shared state: configuration, store, scene, the robots' state bus, stream permits and the shutdown
/// signal.
#[derive(Debug)]
pub struct AppState {
    /// The Zenoh locators the embedded session listens on (empty without Zenoh), for GetInfo.
    pub zenoh_locators: Vec<String>,
    /// The effective configuration.
    pub config: Config,
    /// The primitives.
    pub store: Store,
    /// Every cell's obstacles and robot states.
    /// On a server of a plant: what puts the versions it stores for the other servers ([`crate::plant`]).
    pub replicator: Option<crate::plant::replication::Replicator>,
    pub cells: Cells,
    /// Publishes executing robots' states (over Zenoh when it is on).
    pub robots: RobotBus,
    /// One permit per open stream: executions and watches in pools of their own, bounded per connection and per
    /// client.
    pub streams: StreamPermits,
    /// The server's memory budget (`limits.max_server_bytes`): streams and scenes reserve from it.
    pub memory: MemoryBudget,
    /// Cancelled when the server shuts down: every stream ends.
    pub shutdown: CancellationToken,
    /// Traffic counters.
    pub counters: Counters,
    /// What only the streams measure, for the metrics ([`crate::metrics`]).
    pub histograms: crate::metrics::Histograms,
    /// Wall time and pacing instants.
    pub clock: Clock,
    /// The compute pools and their admission budgets.
    pub compute: Compute,
    /// The robots executing now, one stream each.
    pub executing: Executing,
    /// Which robot states from outside the server the cells take, and how many were dropped.
    pub state_admission: StateAdmission,
    /// The identities and what they may do (open without an access file).
    pub access: Arc<AccessControl>,
    /// What is exposed without protection (`--insecure`).
    pub exposure: Exposure,
    /// Where the streams hand their segments to ROS 2 (empty without `ros2.domain`).
    pub ros2_out: crate::ros2::outbox::Ros2Out,
}

/// What the server has done so far.
#[derive(Debug)]
pub struct Counters {
    /// When the server started.
    pub started: std::time::Instant,
    /// Segments sent (a group segment counts once per member).
    pub segments_sent: std::sync::atomic::AtomicU64,
}

impl Default for Counters {
    fn default() -> Self {
        Self { started: std::time::Instant::now(), segments_sent: Default::default() }
    }
}

impl AppState {
    /// Who sent `request` (the authentication layer put it there), as the access file in force now knows it. A
    /// request that did not pass the layer, as
    /// handlers called directly, is the open server's caller when there is no access file, and refused otherwise.
    pub fn caller<T>(&self, request: &tonic::Request<T>) -> Result<Caller, ServerError> {
        match request.extensions().get::<Caller>() {
            Some(c) => self.access.refresh(c),
            None if !self.access.enabled() => Ok(Caller::open()),
            None => Err(ServerError::Unauthenticated("the request was not authenticated".into())),
        }
    }

    /// Executions open now (what real-time pacing scales with).
    pub fn open_streams(&self) -> usize {
        self.streams.open_executions()
    }

    /// A permit for a stream of `kind` from `peer`, or ResourceExhausted naming the limit reached.
    pub fn stream_permit(&self, kind: StreamKind, peer: &Peer) -> Result<StreamPermit, ServerError> {
        if self.shutdown.is_cancelled() {
            return Err(ServerError::ShuttingDown);
        }
        self.streams.acquire(kind, peer)
    }
}

#[cfg(test)]
impl AppState {
    /// A server's state for unit tests: the default configuration, the store in `dir`, cell `c`, no Zenoh.
    pub(crate) fn for_tests(dir: &std::path::Path, clock: Clock) -> Self {
        let config = Config::default();
        let memory = MemoryBudget::new(config.limits.max_server_bytes);
        Self {
            zenoh_locators: Vec::new(),
            streams: StreamPermits::new(&config.limits),
            store: Store::open(dir).expect("a store in a fresh directory"),
            robots: RobotBus::new(None),
            cells: Cells::with_limits(
                "c",
                &crate::config::Limits { max_cells: 10, ..config.limits.clone() },
                memory.clone(),
                Default::default(),
            )
            .expect("cell c"),
            replicator: None,
            compute: Compute::start(&config.compute).expect("compute threads start"),
            memory,
            executing: Executing::default(),
            state_admission: StateAdmission::new(&config.limits),
            config,
            shutdown: CancellationToken::new(),
            counters: Default::default(),
            histograms: Default::default(),
            clock,
            access: Arc::new(AccessControl::open()),
            exposure: Exposure::default(),
            ros2_out: Default::default(),
        }
    }
}
