//! What every service shares.

use std::sync::Arc;

use tokio::sync::Semaphore;
use tokio_util::sync::CancellationToken;

use crate::cells::Cells;
use crate::clock::Clock;
use crate::config::Config;
use crate::error::ServerError;
use crate::executing::Executing;
use crate::robots::RobotBus;
use crate::state_admission::StateAdmission;
use crate::store::Store;

/// The server's shared state: configuration, store, scene, the robots' state bus, stream permits and the shutdown
/// signal.
#[derive(Debug)]
pub struct AppState {
    /// The effective configuration.
    pub config: Config,
    /// The primitives.
    pub store: Store,
    /// Every cell's obstacles and robot states.
    pub cells: Cells,
    /// Publishes executing robots' states (over Zenoh when it is on).
    pub robots: RobotBus,
    /// One permit per open stream, `limits.max_streams` in all.
    pub streams: Arc<Semaphore>,
    /// Cancelled when the server shuts down: every stream ends.
    pub shutdown: CancellationToken,
    /// Traffic counters.
    pub counters: Counters,
    /// Wall time and pacing instants.
    pub clock: Clock,
    /// The robots executing now, one stream each.
    pub executing: Executing,
    /// Which robot states from outside the server the cells take, and how many were dropped.
    pub state_admission: StateAdmission,
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
    /// Streams open now.
    pub fn open_streams(&self) -> usize {
        self.config.limits.max_streams.saturating_sub(self.streams.available_permits())
    }

    /// A stream permit, or ResourceExhausted when every one is taken.
    pub fn stream_permit(&self) -> Result<tokio::sync::OwnedSemaphorePermit, ServerError> {
        if self.shutdown.is_cancelled() {
            return Err(ServerError::ShuttingDown);
        }
        self.streams.clone().try_acquire_owned().map_err(|_| {
            ServerError::ResourceExhausted(format!(
                "{} streams are open (the limit); retry later",
                self.config.limits.max_streams
            ))
        })
    }
}

#[cfg(test)]
impl AppState {
    /// A server's state for unit tests: the default configuration, the store in `dir`, cell `c`, no Zenoh.
    pub(crate) fn for_tests(dir: &std::path::Path, clock: Clock) -> Self {
        let config = Config::default();
        Self {
            streams: Arc::new(Semaphore::new(config.limits.max_streams)),
            store: Store::open(dir).expect("a store in a fresh directory"),
            robots: RobotBus::new(None),
            cells: Cells::new("c", 10, config.limits.max_obstacles).expect("cell c"),
            executing: Executing::default(),
            state_admission: StateAdmission::new(&config.limits),
            config,
            shutdown: CancellationToken::new(),
            counters: Default::default(),
            clock,
        }
    }
}
