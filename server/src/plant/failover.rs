//! Fail-over: when a server of the plant dies, one survivor serves each of its cells until it comes back.
//!
//! **Who takes a cell.** Every server knows each cell's home (the server whose announcement on
//! `dmp/@servers/<id>` lists it, remembered after that server is gone; a server that joins meanwhile learns it from
//! the others' `homes_away`) and the live servers (their liveliness tokens, [`Directory`]). A cell whose home is not live is served by the live server of highest rendezvous weight
//! (highest-random-weight hashing): the weight of (cell, server) is the first 8 bytes of SHA-256 of
//! `cell \0 server-id`, ties going to the smaller id. Every server computes it alike from the same live set, so
//! each cell is taken by one server once their directories agree (a few milliseconds after a token goes), and a
//! server coming or going moves only the cells it wins or held.
//!
//! **Taking.** The taker serves the cell as one of its own (requests for it, its obstacles and robot states on
//! `dmp/<cell>/...`, which the bridge already receives for every cell), queries `dmp/<cell>/obstacles/**` for its
//! scene (every queryable: the router's obstacle storage of `deploy/zenohd-obstacles.json5`, perception nodes
//! serving their latest obstacles), and then answers on `dmp/@cells/<cell>` (`dmp.v1.PlantServer`, the cell in
//! its `taken`), so that clients resolve the cell to it (and to the cell's own server while both answer). No passive copy of the scene is kept: without a
//! storage or a perception node that answers, the taken cell's scene starts empty and fills as perception
//! publishes again (a tracker's next put). Run the router with the obstacle storage for a plant that fails over.
//!
//! **Giving back.** When the home's token comes back (or another live server now wins the cell), the taker stops
//! answering on `dmp/@cells/<cell>`, forgets the cell's scene, and ends its streams with UNAVAILABLE naming the
//! server the cell went to: the client resumes there (`dmp_client::resume`).

use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Duration;

use dmp_proto::keys::{cell_server_key, obstacles_of};
use dmp_proto::{codec, v1};
use tokio::task::JoinHandle;
use tokio_util::sync::CancellationToken;
use tracing::{debug, info, warn};
use zenoh::bytes::Encoding;
use zenoh::query::{ConsolidationMode, QueryTarget, Queryable};
use zenoh::sample::Sample;
use zenoh::{Session, Wait};

use crate::cells::Cells;
use crate::cells::directory::Directory;
use crate::cells::rendezvous::rendezvous;
use crate::cells::taken::TakenCells;

/// What applies an obstacle sample (the bridge's, [`crate::zenoh_bridge::ZenohBridge::obstacle_sink`]).
pub(crate) type ObstacleSink = Arc<dyn Fn(&Sample) + Send + Sync>;

/// How long the query for a taken cell's scene waits for replies.
const SCENE_QUERY_TIMEOUT: Duration = Duration::from_secs(5);

/// The fail-over task of one server.
#[derive(Debug)]
pub(crate) struct Failover {
    task: JoinHandle<()>,
}

impl Failover {
    /// Watches `directory` and takes or gives back cells for `me` (this server's announcement).
    pub(super) fn start(
        session: &Session,
        me: v1::PlantServer,
        directory: Directory,
        cells: Cells,
        scene: ObstacleSink,
        shutdown: CancellationToken,
    ) -> Self {
        let mut changes = directory.changes();
        let mut state = State {
            session: session.clone(),
            me,
            directory,
            taken: cells.taken().clone(),
            cells,
            scene,
            homes: BTreeMap::new(),
            announced: BTreeMap::new(),
        };
        let task = tokio::spawn(async move {
            loop {
                state.apply().await;
                tokio::select! {
                    _ = shutdown.cancelled() => break,
                    changed = changes.changed() => if changed.is_err() { break },
                }
            }
            state.release_all().await;
        });
        Self { task }
    }

    /// Stops: the taken cells' announcements go (their streams end with the server's).
    pub(super) async fn close(self) {
        self.task.abort();
        let _ = self.task.await;
    }
}

/// Asks `dmp/<cell>/obstacles/**` for a taken cell's scene, from whoever keeps it (the router's storage, perception
/// nodes), and applies every reply: all are in when it returns (the query ends when every queryable has answered,
/// or after [`SCENE_QUERY_TIMEOUT`]), so that the cell is announced only then and no client starts a run in it on
/// an empty scene.
async fn ask_scene(session: &Session, sink: &ObstacleSink, cell: &str) {
    let asked = session
        .get(format!("{}/**", obstacles_of(cell)))
        .target(QueryTarget::All)
        .consolidation(ConsolidationMode::None)
        .timeout(SCENE_QUERY_TIMEOUT)
        .await;
    match asked {
        Ok(replies) => {
            let mut obstacles = 0usize;
            while let Ok(reply) = replies.recv_async().await {
                if let Ok(sample) = reply.result() {
                    sink(sample);
                    obstacles += 1;
                }
            }
            debug!(cell, obstacles, "plant: fail-over: the taken cell's scene is in");
        }
        Err(e) => warn!(cell, error = %e, "plant: fail-over: cannot ask for the taken cell's scene"),
    }
}

struct State {
    session: Session,
    me: v1::PlantServer,
    directory: Directory,
    cells: Cells,
    taken: TakenCells,
    scene: ObstacleSink,
    /// Each cell's home server, as last announced (the directory's, at the last change).
    homes: BTreeMap<String, String>,
    /// The queryables announcing the taken cells.
    announced: BTreeMap<String, Queryable<()>>,
}

impl State {
    /// Brings the taken cells in line with the directory.
    async fn apply(&mut self) {
        let servers = self.directory.servers();
        self.homes = self.directory.homes();
        let mut live: Vec<&str> = servers.iter().map(|s| s.server_id.as_str()).collect();
        if !live.contains(&self.me.server_id.as_str()) {
            live.push(&self.me.server_id);
        }
        let mut moves = Vec::new();
        for (cell, home) in &self.homes {
            if *home == self.me.server_id || self.me.cells.contains(cell) {
                continue;
            }
            let holder = if live.contains(&home.as_str()) {
                home.as_str()
            } else {
                rendezvous(cell, live.iter().copied()).unwrap_or(home)
            };
            let mine = holder == self.me.server_id;
            if mine != self.taken.contains(cell) {
                // None: take it; Some: it went to that server.
                moves.push((cell.clone(), (!mine).then(|| holder.to_owned())));
            }
        }
        let mut taking = tokio::task::JoinSet::new();
        for (cell, to) in moves {
            match to {
                Some(to) => self.give_back(&cell, &to).await,
                None if self.taken.take(&cell) => {
                    let home = self.homes.get(&cell).cloned().unwrap_or_default();
                    info!(cell, home = %home, "plant: fail-over: taking the cell of a server gone");
                    // The scenes of all the cells taken at once: a dead server's many cells wait for the slowest
                    // query, not for their sum.
                    let (session, sink) = (self.session.clone(), self.scene.clone());
                    taking.spawn(async move {
                        ask_scene(&session, &sink, &cell).await;
                        cell
                    });
                }
                None => {}
            }
        }
        while let Some(taken) = taking.join_next().await {
            match taken {
                Ok(cell) => self.announce(&cell).await,
                Err(e) => warn!(error = %e, "plant: fail-over: a scene query failed"),
            }
        }
    }

    /// Answers for a cell taken on `dmp/@cells/<cell>`: clients find it here.
    async fn announce(&mut self, cell: &str) {
        let mut answer = self.me.clone();
        answer.taken = vec![cell.to_owned()];
        let payload = codec::encode(&answer);
        let key = cell_server_key(cell);
        let reply_key = key.clone();
        let declared = self
            .session
            .declare_queryable(&key)
            .callback(move |query| {
                let sent =
                    query.reply(&reply_key, payload.clone()).encoding(Encoding::APPLICATION_PROTOBUF).wait();
                if let Err(e) = sent {
                    debug!(key = %reply_key, error = %e, "plant: taken cell's answer not sent");
                }
            })
            .await;
        match declared {
            Ok(q) => {
                self.announced.insert(cell.to_owned(), q);
            }
            Err(e) => warn!(cell, error = %e, "plant: fail-over: cannot announce the taken cell"),
        }
    }

    async fn give_back(&mut self, cell: &str, to: &str) {
        // Unannounced first, so that a client whose stream ends resolves the cell to its new server.
        if let Some(q) = self.announced.remove(cell)
            && let Err(e) = q.undeclare().await
        {
            debug!(cell, error = %e, "plant: taken cell's queryable undeclare failed");
        }
        let named = match self.directory.get(to) {
            Some(s) => format!("`{to}` at {}", s.grpc_address),
            None => format!("`{to}`"),
        };
        if self.taken.give_back(cell, &named) {
            self.cells.forget(cell);
            info!(cell, to = %to, "plant: fail-over: the cell went back");
        }
    }

    async fn release_all(&mut self) {
        for (_, q) in std::mem::take(&mut self.announced) {
            let _ = q.undeclare().await;
        }
    }
}
