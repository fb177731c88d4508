//! One cell: its obstacles (versioned, read by every stream through a `watch` channel, so readers never block
//! the writer) and the latest state of every robot working in the cell (moving obstacles for the others).

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};

use dmp_proto::v1;
use tokio::sync::watch;

use crate::error::ServerError;

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
    /// Half-width of the workspace box every obstacle's centre must lie in, metres.
    workspace_m: f64,
}

impl Cell {
    /// The empty scene of `cell`, holding at most `max_obstacles`, in the default workspace.
    pub fn new(cell: impl Into<Arc<str>>, max_obstacles: usize) -> Self {
        Self::new_in_workspace(cell, max_obstacles, crate::config::Limits::default().workspace_m)
    }

    /// [`Cell::new`] whose obstacles' centres must lie within `[-workspace_m, workspace_m]` on every axis.
    pub fn new_in_workspace(cell: impl Into<Arc<str>>, max_obstacles: usize, workspace_m: f64) -> Self {
        let (tx, _) = watch::channel(Arc::new(ObstacleSet::default()));
        Self { cell: cell.into(), tx: Arc::new(tx), robots: Arc::default(), max_obstacles, workspace_m }
    }

    /// The cell's name.
    pub fn name(&self) -> &str {
        &self.cell
    }

    /// How many robots the cell sees now.
    pub fn robot_count(&self) -> usize {
        self.robots.lock().unwrap_or_else(|p| p.into_inner()).len()
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
    pub fn put(&self, obstacle: v1::Obstacle, now_unix_s: f64) -> Result<u64, ServerError> {
        if obstacle.id.is_empty() {
            return Err(ServerError::invalid("obstacle.id", "must not be empty"));
        }
        let engine = crate::convert::obstacle_from_proto(&obstacle, self.workspace_m)
            .map_err(|e| e.within("obstacle"))?;
        let expires_unix_s = (obstacle.ttl_s > 0.0).then_some(now_unix_s + obstacle.ttl_s);
        let entry = ReceivedObstacle { proto: obstacle, engine, received_unix_s: now_unix_s, expires_unix_s };
        let mut result = Ok(0);
        self.tx.send_modify(|snap| {
            if !snap.obstacles.contains_key(&entry.proto.id) && snap.obstacles.len() >= self.max_obstacles {
                result = Err(ServerError::ResourceExhausted(format!(
                    "the scene already holds {} obstacles (the limit)",
                    self.max_obstacles
                )));
                return;
            }
            let s = Arc::make_mut(snap);
            s.obstacles.insert(entry.proto.id.clone(), entry);
            s.version += 1;
            result = Ok(s.version);
        });
        result
    }

    /// Removes an obstacle; returns the version and whether it existed. A delete of an unknown id changes nothing.
    pub fn delete(&self, id: &str) -> (u64, bool) {
        let mut out = (0, false);
        self.tx.send_if_modified(|snap| {
            if snap.obstacles.contains_key(id) {
                let s = Arc::make_mut(snap);
                s.obstacles.remove(id);
                s.version += 1;
                out = (s.version, true);
                true
            } else {
                out = (snap.version, false);
                false
            }
        });
        out
    }

    /// Removes the obstacles whose time to live has passed; returns how many.
    pub fn expire(&self, now_unix_s: f64) -> usize {
        let mut n = 0;
        self.tx.send_if_modified(|snap| {
            let expired: Vec<String> = snap
                .obstacles
                .iter()
                .filter(|(_, o)| o.expires_unix_s.is_some_and(|e| e <= now_unix_s))
                .map(|(id, _)| id.clone())
                .collect();
            if expired.is_empty() {
                return false;
            }
            let s = Arc::make_mut(snap);
            for id in &expired {
                s.obstacles.remove(id);
            }
            s.version += 1;
            n = expired.len();
            true
        });
        n
    }

    /// Records the latest state of a robot.
    pub fn update_robot(&self, state: v1::RobotState, footprint: Option<dmp::Shape>) {
        let mut robots = self.robots.lock().unwrap_or_else(|p| p.into_inner());
        match robots.get_mut(&state.robot_id) {
            Some(r) => *r = Arc::new(SeenRobot { state, footprint }),
            None => {
                robots.insert(state.robot_id.clone(), Arc::new(SeenRobot { state, footprint }));
            }
        }
    }

    /// Forgets a robot (its run ended).
    pub fn remove_robot(&self, robot_id: &str) {
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
    pub fn other_robots_into(
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
