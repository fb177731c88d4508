//! One cell: its obstacles (versioned, read by every stream through a `watch` channel, so readers never block
//! the writer) and the latest state of every robot working in the cell (moving obstacles for the others).

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

use dmp_proto::keys::check_name;
use dmp_proto::v1;
use prost::Message;
use tokio::sync::watch;

use crate::config::scene::{StalePolicy, Staleness};
use crate::error::ServerError;
use crate::memory::{MemoryBudget, MemoryReservation};

/// An obstacle as the cell holds it.
#[derive(Debug, Clone)]
pub struct ReceivedObstacle {
    /// As received (normalised: the id set, the centre as of `received_unix_s`).
    pub proto: v1::Obstacle,
    /// The engine's obstacle: centre at `received_unix_s`, moving with its velocity.
    pub engine: dmp::Obstacle,
    /// When the update arrived, Unix seconds.
    pub received_unix_s: f64,
    /// When it expires, Unix seconds.
    pub expires_unix_s: Option<f64>,
    /// Its estimated memory ([`obstacle_bytes`]).
    pub bytes: usize,
    /// Not updated within the cell's `stale_after_s`: frozen where it was then (its velocity zeroed), flagged
    /// until the next update ([`crate::cells::staleness`]).
    pub stale: bool,
}

/// The estimated memory of an obstacle in a scene: the message and the engine's copy of it (each about its encoded
/// size: a 64-D rotation is 32 KiB in both), its id in the map, and a fixed part.
pub fn obstacle_bytes(o: &v1::Obstacle) -> usize {
    2 * o.encoded_len() + 2 * o.id.len() + 512
}

impl ReceivedObstacle {
    /// The proto with its centre moved to `now_unix_s`.
    pub fn proto_at(&self, now_unix_s: f64) -> v1::Obstacle {
        let mut p = self.proto.clone();
        let dt = now_unix_s - self.received_unix_s;
        for (c, v) in p.center.iter_mut().zip(&self.proto.velocity) {
            *c += v * dt;
        }
        p
    }
}

/// The obstacles at one version.
#[derive(Debug, Clone, Default)]
pub struct ObstacleSet {
    /// Grows by one with every change.
    pub version: u64,
    /// By id.
    pub obstacles: BTreeMap<String, ReceivedObstacle>,
    /// The obstacles' estimated memory, bytes.
    pub bytes: usize,
    /// When the last change was made (a put or a delete received, an expiry), Unix seconds; 0 before any.
    pub updated_unix_s: f64,
}

impl ObstacleSet {
    /// The ids of the stale obstacles, in order.
    pub fn stale_ids(&self) -> impl Iterator<Item = &str> {
        self.obstacles.values().filter(|o| o.stale).map(|o| o.proto.id.as_str())
    }
}

/// A stream counted in its cell's [`Cell::streams`] while it lives.
#[derive(Debug)]
pub struct CellStream {
    streams: Arc<AtomicUsize>,
}

impl Drop for CellStream {
    fn drop(&mut self) {
        self.streams.fetch_sub(1, Ordering::Relaxed);
    }
}

/// A robot seen by the cell (its last published state).
#[derive(Debug, Clone)]
pub struct SeenRobot {
    /// The state.
    pub state: v1::RobotState,
    /// Its footprint in the engine's form.
    pub footprint: Option<dmp::Shape>,
}

/// A cell: its obstacles and its robots. Cheap to clone.
#[derive(Debug, Clone)]
pub struct Cell {
    cell: Arc<str>,
    tx: Arc<watch::Sender<Arc<ObstacleSet>>>,
    /// Robot states change at the control rate: kept apart from the versioned obstacles so that they do not wake
    /// every stream. The lock is never held across an await.
    robots: Arc<Mutex<BTreeMap<String, Arc<SeenRobot>>>>,
    max_obstacles: usize,
    /// Most bytes of obstacles.
    max_bytes: usize,
    /// The obstacles' share of the server's memory budget. Locked only inside the watch's update.
    memory: Arc<Mutex<MemoryReservation>>,
    /// Streams executing in the cell now ([`Cell::stream_opened`]).
    streams: Arc<AtomicUsize>,
    /// Half-width of the workspace box every obstacle's centre must lie in, metres.
    workspace_m: f64,
    staleness: Staleness,
}

impl Cell {
    /// The empty scene of `cell`, holding at most `max_obstacles`, with no memory bounds, in the default workspace.
    #[cfg(test)]
    pub(crate) fn new(cell: impl Into<Arc<str>>, max_obstacles: usize) -> Self {
        let workspace_m = crate::config::RequestLimits::default().workspace_m;
        Self::with_budget(cell, max_obstacles, usize::MAX, &MemoryBudget::new(usize::MAX), workspace_m)
    }

    /// The empty scene of `cell`, holding at most `max_obstacles` and `max_bytes` of them, which it reserves from
    /// `memory`, whose obstacles' centres must lie within `[-workspace_m, workspace_m]` on every axis.
    pub(crate) fn with_budget(
        cell: impl Into<Arc<str>>,
        max_obstacles: usize,
        max_bytes: usize,
        memory: &MemoryBudget,
        workspace_m: f64,
    ) -> Self {
        let (tx, _) = watch::channel(Arc::new(ObstacleSet::default()));
        Self {
            cell: cell.into(),
            tx: Arc::new(tx),
            robots: Arc::default(),
            max_obstacles,
            max_bytes,
            memory: Arc::new(Mutex::new(memory.empty())),
            streams: Arc::default(),
            workspace_m,
            staleness: Staleness::default(),
        }
    }

    /// The same cell with its obstacles going stale by `staleness` (default: never).
    pub(crate) fn with_staleness(mut self, staleness: Staleness) -> Self {
        self.staleness = staleness;
        self
    }

    /// The cell's staleness rule.
    pub(crate) fn staleness(&self) -> Staleness {
        self.staleness
    }

    /// Whether nothing holds or uses the cell but the map of cells: no obstacle, no robot, no stream and no
    /// subscriber (every stream and watch holds a clone or a receiver).
    pub(crate) fn is_unused(&self) -> bool {
        Arc::strong_count(&self.tx) == 1
            && self.tx.receiver_count() == 0
            && self.tx.borrow().obstacles.is_empty()
            && self.robot_count() == 0
    }

    /// Moves the scene's memory account by `delta` (checked against the cell's and the server's budgets).
    fn account(&self, old: usize, new: usize, id: &str) -> Result<(), ServerError> {
        let mut memory = self.memory.lock().unwrap_or_else(|p| p.into_inner());
        if new > old {
            memory.grow(&format!("obstacle `{id}`"), new - old)
        } else {
            memory.shrink(old - new);
            Ok(())
        }
    }

    /// The cell's name.
    pub(crate) fn name(&self) -> &str {
        &self.cell
    }

    /// Counts a stream executing in the cell until the returned guard is dropped.
    pub(crate) fn stream_opened(&self) -> CellStream {
        self.streams.fetch_add(1, Ordering::Relaxed);
        CellStream { streams: self.streams.clone() }
    }

    /// Streams executing in the cell now (Execute, Session, ExecuteGroup: one per stream, whatever its robots).
    pub(crate) fn streams(&self) -> usize {
        self.streams.load(Ordering::Relaxed)
    }

    /// How many robots the cell sees now.
    pub fn robot_count(&self) -> usize {
        self.robots.lock().unwrap_or_else(|p| p.into_inner()).len()
    }

    /// How many robots the cell sees now besides `members` (a run's own robots).
    pub(crate) fn robot_count_besides<'a>(&self, members: impl IntoIterator<Item = &'a str>) -> usize {
        let robots = self.robots.lock().unwrap_or_else(|p| p.into_inner());
        let own = members.into_iter().filter(|id| robots.contains_key(*id)).count();
        robots.len().saturating_sub(own)
    }

    /// The current snapshot.
    pub fn snapshot(&self) -> Arc<ObstacleSet> {
        self.tx.borrow().clone()
    }

    /// A receiver that sees every new snapshot.
    pub fn subscribe(&self) -> watch::Receiver<Arc<ObstacleSet>> {
        self.tx.subscribe()
    }

    /// Adds or replaces an obstacle received at `now_unix_s`; returns the new version.
    pub(crate) fn put(&self, obstacle: v1::Obstacle, now_unix_s: f64) -> Result<u64, ServerError> {
        check_name("obstacle.id", &obstacle.id)?;
        let engine = crate::wire::obstacle_from_proto(&obstacle, self.workspace_m)
            .map_err(|e| e.within("obstacle"))?;
        let expires_unix_s = (obstacle.ttl_s > 0.0).then_some(now_unix_s + obstacle.ttl_s);
        let bytes = obstacle_bytes(&obstacle);
        let entry = ReceivedObstacle {
            proto: obstacle,
            engine,
            received_unix_s: now_unix_s,
            expires_unix_s,
            bytes,
            stale: false,
        };
        let mut result = Ok(0);
        self.tx.send_if_modified(|snap| {
            let old = snap.obstacles.get(&entry.proto.id).map(|o| o.bytes);
            if old.is_none() && snap.obstacles.len() >= self.max_obstacles {
                result = Err(ServerError::ResourceExhausted(format!(
                    "the scene of cell `{}` already holds {} obstacles (limits.max_obstacles)",
                    self.cell, self.max_obstacles
                )));
                return false;
            }
            let old = old.unwrap_or(0);
            let total = snap.bytes - old + entry.bytes;
            if total > self.max_bytes {
                result = Err(ServerError::ResourceExhausted(format!(
                    "obstacle `{}` needs about {} bytes, and the scene of cell `{}` would hold {total}, more than \
                     limits.max_scene_bytes = {}",
                    entry.proto.id, entry.bytes, self.cell, self.max_bytes
                )));
                return false;
            }
            if let Err(e) = self.account(old, entry.bytes, &entry.proto.id) {
                result = Err(e);
                return false;
            }
            let s = Arc::make_mut(snap);
            s.bytes = total;
            s.obstacles.insert(entry.proto.id.clone(), entry);
            s.version += 1;
            s.updated_unix_s = now_unix_s;
            result = Ok(s.version);
            true
        });
        result
    }

    /// Removes an obstacle, on a delete received at `now_unix_s`; returns the version and whether it existed. A
    /// delete of an unknown id changes nothing.
    pub(crate) fn delete(&self, id: &str, now_unix_s: f64) -> (u64, bool) {
        let mut out = (0, false);
        self.tx.send_if_modified(|snap| {
            if let Some(bytes) = snap.obstacles.get(id).map(|o| o.bytes) {
                let s = Arc::make_mut(snap);
                s.obstacles.remove(id);
                s.bytes -= bytes;
                let _ = self.account(bytes, 0, id);
                s.version += 1;
                s.updated_unix_s = now_unix_s;
                out = (s.version, true);
                true
            } else {
                out = (snap.version, false);
                false
            }
        });
        out
    }

    /// Removes the obstacles whose time to live has passed, and handles those not updated within the cell's
    /// `stale_after_s` by its policy (dropped, or frozen and flagged); returns how many changed.
    pub(crate) fn expire(&self, now_unix_s: f64) -> usize {
        let stale_after = (!self.staleness.is_off()).then_some(self.staleness.after_s);
        let drop_stale = self.staleness.policy == StalePolicy::Drop;
        let mut n = 0;
        self.tx.send_if_modified(|snap| {
            let mut expired = Vec::new();
            let mut stale = Vec::new();
            for (id, o) in &snap.obstacles {
                if o.expires_unix_s.is_some_and(|e| e <= now_unix_s) {
                    expired.push(id.clone());
                } else if !o.stale && stale_after.is_some_and(|after| now_unix_s - o.received_unix_s > after)
                {
                    if drop_stale { expired.push(id.clone()) } else { stale.push(id.clone()) }
                }
            }
            if expired.is_empty() && stale.is_empty() {
                return false;
            }
            let s = Arc::make_mut(snap);
            for id in &expired {
                if let Some(o) = s.obstacles.remove(id) {
                    s.bytes -= o.bytes;
                    let _ = self.account(o.bytes, 0, id);
                }
            }
            for id in &stale {
                if let Some(o) = s.obstacles.get_mut(id) {
                    freeze(o, now_unix_s);
                }
            }
            s.version += 1;
            s.updated_unix_s = now_unix_s;
            n = expired.len() + stale.len();
            true
        });
        n
    }

    /// Records the latest state of a robot.
    pub(crate) fn update_robot(&self, state: v1::RobotState, footprint: Option<dmp::Shape>) {
        let mut robots = self.robots.lock().unwrap_or_else(|p| p.into_inner());
        match robots.get_mut(&state.robot_id) {
            Some(r) => *r = Arc::new(SeenRobot { state, footprint }),
            None => {
                robots.insert(state.robot_id.clone(), Arc::new(SeenRobot { state, footprint }));
            }
        }
    }

    /// Forgets a robot (its run ended).
    pub(crate) fn remove_robot(&self, robot_id: &str) {
        let mut robots = self.robots.lock().unwrap_or_else(|p| p.into_inner());
        robots.remove(robot_id);
    }

    /// The other robots of the cell, except `robot_id`, whose state is not older than `max_age_s`.
    pub fn other_robots(&self, robot_id: &str, now_unix_s: f64, max_age_s: f64) -> Vec<Arc<SeenRobot>> {
        let mut out = Vec::new();
        self.other_robots_into(robot_id, now_unix_s, max_age_s, &mut out);
        out
    }

    /// [`Cell::other_robots`] into `out` (cleared first), reusing its allocations.
    pub(crate) fn other_robots_into(
        &self,
        robot_id: &str,
        now_unix_s: f64,
        max_age_s: f64,
        out: &mut Vec<Arc<SeenRobot>>,
    ) {
        out.clear();
        let robots = self.robots.lock().unwrap_or_else(|p| p.into_inner());
        out.extend(
            robots
                .values()
                .filter(|r| r.state.robot_id != robot_id && now_unix_s - r.state.stamp_unix_s <= max_age_s)
                .cloned(),
        );
    }
}

/// Flags `o` stale and stops it where it is at `now_unix_s`: with no fresh data its velocity is a guess that would
/// carry it away forever.
fn freeze(o: &mut ReceivedObstacle, now_unix_s: f64) {
    let mut proto = o.proto_at(now_unix_s);
    proto.velocity.iter_mut().for_each(|v| *v = 0.0);
    // The same shape at a valid centre: it converted before, so it converts again.
    if let Ok(engine) = dmp_proto::obstacle::obstacle_to_engine(&proto) {
        o.engine = engine;
        o.proto = proto;
        o.received_unix_s = now_unix_s;
    }
    o.stale = true;
}

#[cfg(test)]
mod tests {
    use super::*;

    fn moving(id: &str, ttl_s: f64) -> v1::Obstacle {
        v1::Obstacle {
            id: id.into(),
            shape: Some(v1::obstacle::Shape::Superquadric(v1::Superquadric {
                semi_axes: vec![0.1, 0.1],
                exponents: vec![1.0, 1.0],
            })),
            center: vec![0.0, 0.0],
            velocity: vec![1.0, 0.0],
            ttl_s,
            ..Default::default()
        }
    }

    #[test]
    fn stale_obstacles_are_frozen_and_flagged_or_dropped_and_an_update_refreshes_them() {
        let keep = Cell::new("c", 10).with_staleness(Staleness { after_s: 1.0, policy: StalePolicy::Keep });
        keep.put(moving("a", 0.0), 100.0).unwrap();
        keep.put(moving("b", 0.0), 100.8).unwrap();
        assert_eq!(keep.expire(101.0), 0, "not stale yet");
        assert_eq!(keep.expire(101.5), 1);
        let snap = keep.snapshot();
        assert_eq!(snap.stale_ids().collect::<Vec<_>>(), ["a"]);
        // Frozen where it was when it went stale: it drifts no more.
        let a = &snap.obstacles["a"];
        assert_eq!(a.proto_at(1000.0).center, vec![1.5, 0.0]);
        assert_eq!(keep.expire(101.6), 0, "flagged once");
        keep.put(moving("a", 0.0), 102.0).unwrap();
        assert_eq!(keep.snapshot().stale_ids().count(), 0, "an update makes it fresh");

        let drop = Cell::new("c", 10).with_staleness(Staleness { after_s: 1.0, policy: StalePolicy::Drop });
        drop.put(moving("a", 0.0), 100.0).unwrap();
        drop.put(moving("t", 0.5), 100.0).unwrap();
        assert_eq!(drop.expire(101.5), 2, "the ttl and the stale one");
        assert!(drop.snapshot().obstacles.is_empty());

        let off = Cell::new("c", 10);
        off.put(moving("a", 0.0), 100.0).unwrap();
        assert_eq!(off.expire(1.0e6), 0, "off: it lives until deleted");
    }
}
