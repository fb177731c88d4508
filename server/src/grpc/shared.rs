//! What the gRPC services share. A run is handed only its [`RunContext`], never this.

use std::sync::Arc;

use crate::access::exposure::Exposure;
use crate::access::{AccessControl, Caller};
use crate::cells::Cells;
use crate::cells::state_admission::StateAdmission;
use crate::config::Config;
use crate::connections::stream_permits::{Peer, StreamKind, StreamPermit};
use crate::error::ServerError;
use crate::memory::MemoryBudget;
use crate::plant::replication::Replicator;
use crate::runs::context::RunContext;
use crate::runs::executing::Executing;
use crate::store::Store;

/// What the gRPC services share: the configuration, the store, the cells, the runs' context, the budgets and who
/// may do what.
#[derive(Debug)]
pub(crate) struct ServiceState {
    /// The Zenoh locators the embedded session listens on (empty without Zenoh), for GetInfo.
    pub zenoh_locators: Vec<String>,
    /// The effective configuration.
    pub config: Config,
    /// The primitives.
    pub store: Store,
    /// On a server of a plant: what puts the versions it stores for the other servers ([`crate::plant`]).
    pub replicator: Option<Replicator>,
    /// Every cell's obstacles and robot states.
    pub cells: Cells,
    /// What the streams use: clock, compute pools, robot bus, ROS 2 outbox, shutdown, permits, counters.
    pub runs: Arc<RunContext>,
    /// The server's memory budget (`limits.max_server_bytes`): streams and scenes reserve from it.
    pub memory: MemoryBudget,
    /// The robots executing now, one stream each.
    pub executing: Executing,
    /// Which robot states from outside the server the cells take, and how many were dropped.
    pub state_admission: StateAdmission,
    /// The identities and what they may do (open without an access file).
    pub access: Arc<AccessControl>,
    /// What is exposed without protection (`--insecure`).
    pub exposure: Exposure,
}

impl ServiceState {
    /// Who sent `request` (the authentication layer put it there), as the access file in force now knows it. A
    /// request that did not pass the layer, as
    /// handlers called directly, is the open server's caller when there is no access file, and refused otherwise.
    pub(crate) fn caller<T>(&self, request: &tonic::Request<T>) -> Result<Caller, ServerError> {
        match request.extensions().get::<Caller>() {
            Some(c) => self.access.refresh(c),
            None if !self.access.enabled() => Ok(Caller::open()),
            None => Err(ServerError::Unauthenticated("the request was not authenticated".into())),
        }
    }

    /// A permit for a stream of `kind` from `peer`, or ResourceExhausted naming the limit reached.
    pub(crate) fn stream_permit(&self, kind: StreamKind, peer: &Peer) -> Result<StreamPermit, ServerError> {
        if self.runs.shutdown.is_cancelled() {
            return Err(ServerError::ShuttingDown);
        }
        self.runs.streams.acquire(kind, peer)
    }
}

#[cfg(test)]
impl ServiceState {
    /// The services' state for unit tests: the default configuration, the store in `dir`, cell `c`, no Zenoh.
    pub(crate) fn for_tests(dir: &std::path::Path, clock: crate::clock::Clock) -> Self {
        let config = Config::default();
        let memory = MemoryBudget::new(config.limits.max_server_bytes);
        Self {
            zenoh_locators: Vec::new(),
            store: Store::open(dir).expect("a store in a fresh directory"),
            cells: Cells::with_limits(
                "c",
                &crate::config::RequestLimits { max_cells: 10, ..config.limits.clone() },
                memory.clone(),
                Default::default(),
            )
            .expect("cell c"),
            runs: Arc::new(RunContext::for_tests(clock)),
            replicator: None,
            memory,
            executing: Executing::default(),
            state_admission: StateAdmission::new(&config.limits),
            config,
            access: Arc::new(AccessControl::open()),
            exposure: Exposure::default(),
        }
    }
}
