//! Several servers on one Zenoh network (a plant): each serves its own cells, and they find each other and share
//! the primitives through Zenoh alone (routers, liveliness, queryables), without a protocol of their own.
//!
//! | concept | key | file |
//! | --- | --- | --- |
//! | a server is alive: its liveliness token, and a queryable answering `dmp.v1.PlantServer` (id, gRPC address, cells) | `dmp/@servers/<server-id>` | [`discovery`] |
//! | which server serves a cell: a queryable per cell served, answering `dmp.v1.PlantServer` | `dmp/@cells/<cell>` | [`discovery`] |
//! | the live servers this one knows, to name the server of a cell it does not serve | `dmp/@servers/*` (liveliness, with history) | [`crate::cells::directory`] |
//! | replicated primitives: every version stored is put, the others store it; a queryable over the store answers a server that (re)starts | `dmp/@primitives/<robot>/<name>/<version>` | [`replication`] |
//! | fail-over: a dead server's cells served by one survivor each (rendezvous hashing over the live set), given back when it returns | `dmp/@cells/<cell>` (the taker's), `dmp/<cell>/obstacles/**` (queried) | [`failover`], [`crate::cells::taken`] |
//! | replicated deletes: a tombstone, a Zenoh delete of every version up to `N`, answered by the same queryable | `dmp/@primitives/<robot>/<name>/<N>` (delete) | [`replication`], `store/tombstones.rs` |
//!
//! The order of versions: a version stored on a server of a plant is numbered with that server's HLC time (NTP64,
//! `Session::new_timestamp`), or the last version plus one if that is later, and keeps its number on every server.
//! So every server orders the versions of a primitive alike, the latest being the largest number; two servers that
//! learn the same (robot, name) at once both keep their versions (their clocks differ, and each HLC never gives one
//! time twice), and the later stamp is the latest everywhere. Two records of one number from two servers (the same
//! HLC time on both, which their HLCs make all but impossible) keep the record of the smaller server id everywhere.
//!
//! Deletes follow the same order. A delete on a server stamps a tombstone `N`, the later of its HLC time and the
//! last version it knows, and deletes every version numbered `N` or less on every server, whenever the version or
//! the tombstone arrives (a server that was down gets the tombstones in its catch-up, as it gets the versions). A
//! version stamped after the delete is kept everywhere; a server that applied the tombstone numbers its next
//! version above `N`, so a re-learn after a delete is the latest everywhere even with clocks apart. Of two
//! tombstones of one name the larger holds. A version or tombstone stamped more than the HLC's bound ahead of the
//! receiver's clock is refused, and a delete purges one held from before (`store/tombstones.rs`). One tombstone
//! per (robot, name) is kept, for [`crate::store::TOMBSTONE_RETENTION`] (7 days): a server down longer should
//! start on an empty store.
//!
//! Robot records (`RobotService`) are not replicated: each server keeps its own.

pub(crate) mod discovery;
pub(crate) mod failover;
pub(crate) mod replication;

use std::sync::Arc;

use dmp_proto::v1;
use tokio_util::sync::CancellationToken;
use tracing::info;
use zenoh::Session;

use crate::cells::Cells;
use crate::config::{Config, RequestLimits};
use crate::error::ServerError;
use crate::store::{Store, VersionClock};

use self::discovery::Discovery;
use self::failover::{Failover, ObstacleSink};
use self::replication::Replication;
use crate::cells::directory::Directory;

/// This server's part in the plant: its announcement and the replication of its store. Closed with
/// [`Plant::close`] before the session.
#[derive(Debug)]
pub(crate) struct Plant {
    server: v1::PlantServer,
    discovery: Discovery,
    replication: Replication,
    failover: Failover,
}

/// The version clock of a plant's store: the session's HLC time, NTP64.
pub(crate) fn version_clock(session: &Session) -> VersionClock {
    let session = session.clone();
    Arc::new(move || session.new_timestamp().get_time().as_u64())
}

impl Plant {
    /// Joins the plant when `config` names this server (`plant.server_id`), announcing it at `advertised` (its gRPC
    /// address) with the cells it serves: returns `store` stamped with the plant's version clock, and the plant.
    /// Without a server id the store is returned as it is, and there is no plant. A taken cell's scene is applied
    /// through `sink` (the Zenoh bridge's).
    pub(crate) async fn join(
        config: &Config,
        zenoh: (Option<&Session>, Option<ObstacleSink>),
        advertised: String,
        (directory, cells): (Directory, &Cells),
        store: Store,
        shutdown: &CancellationToken,
    ) -> Result<(Store, Option<Self>), ServerError> {
        let Some(id) = &config.plant.server_id else { return Ok((store, None)) };
        let (Some(session), Some(sink)) = zenoh else {
            return Err(ServerError::FailedPrecondition(
                "plant.server_id needs Zenoh (not --no-zenoh)".into(),
            ));
        };
        let store = store.stamped(id, version_clock(session));
        let server = v1::PlantServer {
            server_id: id.clone(),
            grpc_address: advertised,
            cells: announced_cells(cells),
            ..Default::default()
        };
        let plant = Self::start(
            session,
            server,
            (directory, cells.clone(), sink),
            store.clone(),
            config.limits.clone(),
            shutdown.clone(),
        )
        .await?;
        Ok((store, Some(plant)))
    }

    /// Announces `server` (its token and queryables), fills `directory` with the plant's live servers, and
    /// replicates `store` (stamped by [`version_clock`]) with the other servers, catching up with them now and
    /// whenever one (re)appears. Incoming primitives are checked against `limits`. Takes the cells of dead servers
    /// into `cells` as [`failover`] says, their scenes applied through `scene`.
    pub(crate) async fn start(
        session: &Session,
        server: v1::PlantServer,
        (directory, cells, scene): (Directory, Cells, ObstacleSink),
        store: Store,
        limits: RequestLimits,
        shutdown: CancellationToken,
    ) -> Result<Self, ServerError> {
        let discovery = Discovery::start(session, &server, directory.clone(), shutdown.clone()).await?;
        let replication = Replication::start(session, store, limits, shutdown.clone()).await?;
        let failover = Failover::start(session, server.clone(), directory, cells, scene, shutdown);
        info!(server = %server.server_id, grpc = %server.grpc_address, cells = ?server.cells, "plant: joined");
        Ok(Self { server, discovery, replication, failover })
    }

    /// What puts the versions this server stores (the primitive service holds it).
    pub(crate) fn replicator(&self) -> self::replication::Replicator {
        self.replication.replicator()
    }

    /// Leaves the plant: the token and queryables go (the others forget this server), the tasks stop.
    pub(crate) async fn close(self) {
        let (stored, refused) = self.replication.counts();
        info!(server = %self.server.server_id, stored, refused, "plant: leaving; replicated versions received");
        self.failover.close().await;
        self.replication.close().await;
        self.discovery.close().await;
    }
}

/// The cells a server of the plant announces: those it serves, or its default cell when it serves any.
pub(crate) fn announced_cells(cells: &Cells) -> Vec<String> {
    cells.served().unwrap_or_else(|| vec![cells.default_cell().to_owned()])
}
