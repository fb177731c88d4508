//! `dmp.v1.SceneService`: put, delete, list and watch obstacles over gRPC, for clients without Zenoh. A gRPC put
//! changes this server's scene only (it is not republished on Zenoh).

use std::sync::Arc;

use dmp_proto::keys::check_name;
use dmp_proto::v1;
use dmp_proto::v1::scene_service_server::SceneService;
use tokio::sync::mpsc;
use tokio_stream::wrappers::ReceiverStream;
use tokio_util::sync::CancellationToken;
use tonic::{Request, Response, Status};
use tracing::debug;

use crate::access::{Action, Grant};
use crate::audit;
use crate::cells::cell::{Cell, ObstacleSet};
use crate::cells::taken::GivenBack;
use crate::clock::Clock;
use crate::connections::stream_permits::{Peer, StreamKind};
use crate::error::ServerError;
use crate::grpc::shared::ServiceState;

/// The scene service.
#[derive(Debug, Clone)]
pub(crate) struct SceneServiceImpl {
    /// What the services share.
    pub state: Arc<ServiceState>,
}

impl SceneServiceImpl {
    /// The service on the shared state.
    pub(crate) fn new(state: Arc<ServiceState>) -> Self {
        Self { state }
    }
}

/// The message of a snapshot: obstacles sorted by id, centres moved to `now_unix_s`.
pub(crate) fn snapshot_to_proto(snapshot: &ObstacleSet, now_unix_s: f64) -> v1::SceneSnapshot {
    v1::SceneSnapshot {
        scene_version: snapshot.version,
        obstacles: snapshot.obstacles.values().map(|o| o.proto_at(now_unix_s)).collect(),
    }
}

/// Streams the current snapshot, then the snapshot after every change, into a channel of `buffer` events.
///
/// One task per watch holds `permit` until it ends, or until its `grant` is revoked by a reload of the access file
/// (a last PERMISSION_DENIED), or until the cell, served for a dead server, goes back (`given_back`: a last
/// UNAVAILABLE naming where it went): when the client leaves (a send fails, or the channel closes
/// while no change comes) or on `shutdown` (a last `Unavailable` status, if there is room). The bound is the
/// backpressure: a slow reader is sent the latest snapshot when it catches up (versions in between are skipped; each
/// event is a whole snapshot, so nothing is lost), never a growing queue.
pub(crate) fn watch_stream(
    scene: &Cell,
    clock: Clock,
    buffer: usize,
    shutdown: CancellationToken,
    permit: impl Send + 'static,
    mut grant: Option<Grant>,
    given_back: Option<GivenBack>,
) -> ReceiverStream<Result<v1::SceneEvent, Status>> {
    let (tx, rx) = mpsc::channel(buffer.max(1));
    let mut changes = scene.subscribe();
    let cell = scene.name().to_owned();
    tokio::spawn(async move {
        let _permit = permit;
        let moved = crate::cells::taken::moved(given_back, &cell);
        tokio::pin!(moved);
        let revoked = async {
            match grant.as_mut() {
                Some(g) => g.revoked().await,
                None => std::future::pending().await,
            }
        };
        tokio::pin!(revoked);
        loop {
            let snapshot = changes.borrow_and_update().clone();
            let event = v1::SceneEvent { snapshot: Some(snapshot_to_proto(&snapshot, clock.now_unix_s())) };
            tokio::select! {
                biased;
                _ = shutdown.cancelled() => break,
                sent = tx.send(Ok(event)) => if sent.is_err() { return },
            }
            tokio::select! {
                biased;
                _ = shutdown.cancelled() => break,
                _ = tx.closed() => return,
                denied = &mut revoked => {
                    debug!(error = %denied, "scene watch revoked");
                    let _ = tx.try_send(Err(denied.into()));
                    return;
                }
                moved = &mut moved => {
                    debug!(error = %moved, "scene watch of a cell that went back");
                    // A reader whose buffer is full is waited for a little, not forever.
                    let _ = tokio::time::timeout(std::time::Duration::from_secs(1), tx.send(Err(moved.into()))).await;
                    return;
                }
                changed = changes.changed() => if changed.is_err() { break },
            }
        }
        let _ = tx.try_send(Err(ServerError::ShuttingDown.into()));
        debug!("scene watch ended");
    });
    ReceiverStream::new(rx)
}

#[tonic::async_trait]
impl SceneService for SceneServiceImpl {
    async fn put_obstacle(
        &self,
        request: Request<v1::PutObstacleRequest>,
    ) -> Result<Response<v1::SceneChange>, Status> {
        let caller = self.state.caller(&request)?;
        let request = request.into_inner();
        let name = self.state.cells.resolve(&request.cell)?;
        caller.check(&Action::ChangeScene { cell: name })?;
        let cell = self.state.cells.get(name)?;
        let obstacle = request.obstacle.ok_or_else(|| ServerError::invalid("obstacle", "is required"))?;
        let id = obstacle.id.clone();
        let version = cell.put(obstacle, self.state.runs.clock.now_unix_s())?;
        debug!(obstacle = %id, version, "obstacle put over gRPC");
        audit!(caller, "put obstacle", cell = name, obstacle = %id, version);
        Ok(Response::new(v1::SceneChange { scene_version: version, changed: true }))
    }

    async fn delete_obstacle(
        &self,
        request: Request<v1::DeleteObstacleRequest>,
    ) -> Result<Response<v1::SceneChange>, Status> {
        let caller = self.state.caller(&request)?;
        let v1::DeleteObstacleRequest { id, cell: name } = request.into_inner();
        check_name("id", &id).map_err(ServerError::from)?;
        let name = self.state.cells.resolve(&name)?;
        caller.check(&Action::ChangeScene { cell: name })?;
        // A delete never creates a cell: in one that does not exist there is nothing to delete.
        let Some(cell) = self.state.cells.find(name)? else {
            return Ok(Response::new(v1::SceneChange { scene_version: 0, changed: false }));
        };
        let (version, changed) = cell.delete(&id, self.state.runs.clock.now_unix_s());
        debug!(obstacle = %id, version, changed, "obstacle deleted over gRPC");
        audit!(caller, "delete obstacle", cell = name, obstacle = %id, version, changed);
        Ok(Response::new(v1::SceneChange { scene_version: version, changed }))
    }

    async fn list_obstacles(
        &self,
        request: Request<v1::ListObstaclesRequest>,
    ) -> Result<Response<v1::SceneSnapshot>, Status> {
        let caller = self.state.caller(&request)?;
        let request = request.into_inner();
        let name = self.state.cells.resolve(&request.cell)?;
        caller.check(&Action::ReadScene { cell: name })?;
        // A read never creates a cell: one that does not exist is empty.
        let Some(cell) = self.state.cells.find(name)? else {
            return Ok(Response::new(v1::SceneSnapshot::default()));
        };
        Ok(Response::new(snapshot_to_proto(&cell.snapshot(), self.state.runs.clock.now_unix_s())))
    }

    type WatchSceneStream = ReceiverStream<Result<v1::SceneEvent, Status>>;

    async fn watch_scene(
        &self,
        request: Request<v1::WatchSceneRequest>,
    ) -> Result<Response<Self::WatchSceneStream>, Status> {
        let s = &self.state;
        let caller = s.caller(&request)?;
        let cell = s.cells.resolve(&request.get_ref().cell)?.to_owned();
        caller.check(&Action::ReadScene { cell: &cell })?;
        let permit = s.stream_permit(StreamKind::Watch, &Peer::of(&request))?;
        let scene = s.cells.get(&cell)?;
        let given_back = s.cells.stream_guard(&cell)?;
        let grant =
            s.access.grant(caller, move |c, a| c.check_again(a, &Action::ReadScene { cell: &cell }))?;
        Ok(Response::new(watch_stream(
            &scene,
            s.runs.clock,
            s.config.limits.stream_buffer,
            s.runs.shutdown.clone(),
            permit,
            Some(grant),
            given_back,
        )))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::clock::system_unix_s;
    use std::future::IntoFuture;
    use std::time::Duration;
    use tokio::sync::Semaphore;
    use tokio_stream::StreamExt;

    async fn within<F: IntoFuture>(what: &str, f: F) -> F::Output {
        tokio::time::timeout(Duration::from_secs(10), f).await.unwrap_or_else(|_| panic!("timed out: {what}"))
    }

    fn moving(id: &str) -> v1::Obstacle {
        v1::Obstacle {
            id: id.into(),
            shape: Some(v1::obstacle::Shape::Superquadric(v1::Superquadric {
                semi_axes: vec![0.1, 0.2],
                exponents: vec![],
            })),
            center: vec![0.0, 0.0],
            velocity: vec![1.0, 0.0],
            ..Default::default()
        }
    }

    /// A watch of `scene` on the system clock, holding one of `permits`, ending on `shutdown` or, when given,
    /// when the cell goes back.
    fn watch(
        scene: &Cell,
        buffer: usize,
        shutdown: &CancellationToken,
        permits: &Arc<Semaphore>,
        given_back: Option<GivenBack>,
    ) -> ReceiverStream<Result<v1::SceneEvent, Status>> {
        let permit = permits.clone().try_acquire_owned().unwrap();
        watch_stream(scene, Clock::system(), buffer, shutdown.clone(), permit, None, given_back)
    }

    fn ids(e: &v1::SceneEvent) -> Vec<&str> {
        e.snapshot.as_ref().unwrap().obstacles.iter().map(|o| o.id.as_str()).collect()
    }

    #[test]
    fn snapshots_move_centres_to_now() {
        let scene = Cell::new("c", 10);
        scene.put(moving("b"), 100.0).unwrap();
        scene.put(moving("a"), 100.0).unwrap();
        let p = snapshot_to_proto(&scene.snapshot(), 102.5);
        assert_eq!(p.scene_version, 2);
        assert_eq!(p.obstacles.iter().map(|o| o.id.as_str()).collect::<Vec<_>>(), ["a", "b"]);
        assert_eq!(p.obstacles[0].center, vec![2.5, 0.0]);
    }

    #[tokio::test(flavor = "multi_thread")]
    async fn a_watch_sends_the_snapshot_then_changes_and_frees_its_permit() {
        let scene = Cell::new("c", 10);
        scene.put(moving("a"), system_unix_s()).unwrap();
        let permits = Arc::new(Semaphore::new(1));
        let shutdown = CancellationToken::new();
        let mut stream = watch(&scene, 2, &shutdown, &permits, None);
        let first = within("first", stream.next()).await.unwrap().unwrap();
        assert_eq!(ids(&first), ["a"]);
        scene.put(moving("b"), system_unix_s()).unwrap();
        let second = within("second", stream.next()).await.unwrap().unwrap();
        assert_eq!(ids(&second), ["a", "b"]);
        assert_eq!(second.snapshot.unwrap().scene_version, 2);
        scene.delete("a", system_unix_s());
        assert_eq!(ids(&within("third", stream.next()).await.unwrap().unwrap()), ["b"]);
        assert_eq!(permits.available_permits(), 0);

        // The client leaves while nothing changes: the task ends and the permit is back.
        drop(stream);
        let _freed = within("permit", permits.clone().acquire_owned()).await.unwrap();
    }

    #[tokio::test(flavor = "multi_thread")]
    async fn a_watch_of_a_taken_cell_ends_when_it_goes_back_naming_where() {
        let scene = Cell::new("c", 10);
        let taken = crate::cells::taken::TakenCells::default();
        assert!(taken.take("c"));
        let permits = Arc::new(Semaphore::new(1));
        let mut stream = watch(&scene, 2, &CancellationToken::new(), &permits, taken.until_given_back("c"));
        assert!(ids(&within("first", stream.next()).await.unwrap().unwrap()).is_empty());
        assert!(taken.give_back("c", "`s1` at http://h:1"));
        let last = within("the end", stream.next()).await.unwrap().unwrap_err();
        assert_eq!(last.code(), tonic::Code::Unavailable);
        assert!(last.message().contains("cell `c` moved to server `s1` at http://h:1"), "{}", last.message());
        assert!(within("closed", stream.next()).await.is_none());
        let _freed = within("permit", permits.clone().acquire_owned()).await.unwrap();
    }

    #[tokio::test(flavor = "multi_thread")]
    async fn a_watch_ends_on_shutdown() {
        let scene = Cell::new("c", 10);
        let permits = Arc::new(Semaphore::new(1));
        let shutdown = CancellationToken::new();
        let mut stream = watch(&scene, 1, &shutdown, &permits, None);
        assert!(ids(&within("first", stream.next()).await.unwrap().unwrap()).is_empty());
        shutdown.cancel();
        let last = within("last", stream.next()).await.unwrap().unwrap_err();
        assert_eq!(last.code(), tonic::Code::Unavailable);
        assert!(within("end", stream.next()).await.is_none());
        let _freed = within("permit", permits.acquire()).await.unwrap();
    }

    #[tokio::test(flavor = "multi_thread")]
    async fn a_slow_reader_gets_the_latest_snapshot() {
        let scene = Cell::new("c", 100);
        let permits = Arc::new(Semaphore::new(1));
        let mut stream = watch(&scene, 1, &CancellationToken::new(), &permits, None);
        for i in 0..50 {
            scene.put(moving(&format!("o{i:02}")), system_unix_s()).unwrap();
        }
        // Whatever was buffered, the events only grow and the last one holds all 50 obstacles.
        let mut last = 0;
        while last < 50 {
            let e = within("event", stream.next()).await.unwrap().unwrap();
            let version = e.snapshot.unwrap().scene_version;
            assert!(version >= last);
            last = version;
        }
        assert_eq!(last, 50);
    }
}
