//! The robots' state bus: every executing robot's state is recorded in the local scene and, with Zenoh, published on
//! `dmp/<cell>/robots/<robot-id>/state` (protobuf `dmp.v1.RobotState`), so that the robots of the cell, served by
//! this server or another, see each other as moving obstacles. With each robot's publisher goes its liveliness token
//! (`dmp/<cell>/robots/<robot-id>/alive`): when the robot retires, or this server's session goes, the other servers
//! forget the robot.

use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use dmp_proto::keys::{check_name, robot_alive_key, robot_state_key};
use dmp_proto::{codec, v1};
use tracing::{debug, warn};
use zenoh::Session;
use zenoh::bytes::Encoding;
use zenoh::liveliness::LivelinessToken;
use zenoh::pubsub::Publisher;
use zenoh::sample::Locality;

use crate::cells::Cells;
use crate::cells::cell::Cell;

/// Publishes executing robots' states: into their cell's scene always (every segment), and on Zenoh when the
/// server has a session (at most once per `period` per robot: other servers extrapolate with the velocity). Cheap to
/// clone; a Zenoh error is logged, never returned (a robot's motion never waits on the network).
#[derive(Debug, Clone)]
pub(crate) struct RobotBus {
    zenoh: Option<Arc<ZenohRobotBus>>,
    /// The server's cells, to record a robot also in the cells that list its cell as a neighbour.
    cells: Option<Cells>,
}

/// A robot's Zenoh publisher, whether any remote subscriber matches it, and the stamp of its last state sent.
#[derive(Debug)]
struct RobotPublisher {
    publisher: Publisher<'static>,
    /// Kept up to date by a matching listener: with nobody listening (a lone server), states are neither encoded
    /// nor put.
    matching: Arc<AtomicBool>,
    last_stamp: Mutex<f64>,
    /// The robot's liveliness token, undeclared when the publisher is dropped (the robot retired).
    _alive: Option<LivelinessToken>,
}

/// The Zenoh side: one publisher per robot, declared at its first state (a declared publisher keeps its routes,
/// unlike a `session.put` per state) and undeclared when it retires.
#[derive(Debug)]
struct ZenohRobotBus {
    session: Session,
    period_s: f64,
    /// By cell, then robot id. The lock is held only to look up or insert, never across an await.
    publishers: Mutex<HashMap<String, HashMap<String, Arc<RobotPublisher>>>>,
}

impl RobotBus {
    /// A bus publishing on `dmp/<cell>/robots/...` of `zenoh` (session, period between two states of a robot,
    /// seconds) when one is given.
    pub(crate) fn new(zenoh: Option<(Session, f64)>) -> Self {
        let zenoh = zenoh.map(|(session, period_s)| {
            Arc::new(ZenohRobotBus { session, period_s, publishers: Mutex::new(HashMap::new()) })
        });
        Self { zenoh, cells: None }
    }

    /// The same bus, recording each robot also in the cells of `cells` that avoid its cell's robots
    /// (`plant.neighbours`).
    pub(crate) fn mirroring(mut self, cells: Cells) -> Self {
        self.cells = Some(cells);
        self
    }

    /// The cells of this server, other than `cell`, whose robots avoid those of `cell`.
    fn avoiders(&self, cell: &str) -> Vec<Cell> {
        let Some(cells) = &self.cells else { return Vec::new() };
        cells.avoiders_of(cell).iter().filter_map(|a| cells.get(a).ok()).collect()
    }

    /// Records a robot's state in its cell's scene and publishes it on Zenoh (encoding `application/protobuf`)
    /// unless the robot's last state went out less than the period ago.
    pub(crate) async fn publish(&self, scene: &Cell, state: v1::RobotState, footprint: Option<dmp::Shape>) {
        for other in self.avoiders(scene.name()) {
            other.update_robot(state.clone(), footprint.clone());
        }
        let Some(z) = &self.zenoh else {
            scene.update_robot(state, footprint);
            return;
        };
        let out = z.publisher(scene.name(), &state.robot_id).await;
        let due = out.as_ref().is_some_and(|o| {
            if !o.matching.load(Ordering::Relaxed) {
                return false;
            }
            let mut last = o.last_stamp.lock().unwrap_or_else(|p| p.into_inner());
            let due = state.stamp_unix_s - *last >= z.period_s;
            if due {
                *last = state.stamp_unix_s;
            }
            due
        });
        let payload = due.then(|| codec::encode(&state));
        let robot_id = (payload.is_some()).then(|| state.robot_id.clone());
        scene.update_robot(state, footprint);
        if let (Some(out), Some(payload), Some(robot_id)) = (out, payload, robot_id)
            && let Err(e) = out.publisher.put(payload).await
        {
            warn!(robot = %robot_id, error = %e, "zenoh: robot state not published");
        }
    }

    /// Forgets a robot whose run ended, locally and on Zenoh (a delete on its key).
    pub(crate) async fn retire(&self, scene: &Cell, robot_id: &str) {
        scene.remove_robot(robot_id);
        for other in self.avoiders(scene.name()) {
            other.remove_robot(robot_id);
        }
        let Some(z) = &self.zenoh else { return };
        let out = {
            let mut map = z.publishers.lock().unwrap_or_else(|p| p.into_inner());
            let out = map.get_mut(scene.name()).and_then(|m| m.remove(robot_id));
            if map.get(scene.name()).is_some_and(|m| m.is_empty()) {
                map.remove(scene.name());
            }
            out
        };
        let result = match out {
            Some(o) => o.publisher.delete().await,
            None if check_name("robot_id", robot_id).is_ok() => {
                z.session.delete(robot_state_key(scene.name(), robot_id)).await
            }
            None => return,
        };
        match result {
            Ok(()) => debug!(robot = %robot_id, "zenoh: robot retired"),
            Err(e) => warn!(robot = %robot_id, error = %e, "zenoh: robot retirement not published"),
        }
    }

    /// How many robots currently have a Zenoh publisher.
    #[cfg(test)]
    pub(crate) fn publishers(&self) -> usize {
        self.zenoh.as_ref().map_or(0, |z| {
            z.publishers.lock().unwrap_or_else(|p| p.into_inner()).values().map(HashMap::len).sum()
        })
    }
}

impl ZenohRobotBus {
    /// The robot's publisher, declared at first use; None (logged) for an id that cannot be a key chunk.
    async fn publisher(&self, cell: &str, robot_id: &str) -> Option<Arc<RobotPublisher>> {
        let found = {
            let map = self.publishers.lock().unwrap_or_else(|p| p.into_inner());
            map.get(cell).and_then(|m| m.get(robot_id)).cloned()
        };
        if found.is_some() {
            return found;
        }
        if let Err(e) = check_name("robot_id", robot_id) {
            warn!(robot = %robot_id, reason = %e, "zenoh: robot state not published");
            return None;
        }
        let declared = self
            .session
            .declare_publisher(robot_state_key(cell, robot_id))
            .encoding(Encoding::APPLICATION_PROTOBUF)
            // This server's own subscriber takes remote states only: its robots are already in the scene.
            .allowed_destination(Locality::Remote)
            .await;
        match declared {
            Ok(publisher) => {
                // Called at once if a subscriber matches already, then at every change.
                let matching = Arc::new(AtomicBool::new(false));
                let flag = matching.clone();
                let listener = publisher
                    .matching_listener()
                    .callback(move |m| flag.store(m.matching(), Ordering::Relaxed))
                    .background()
                    .await;
                if let Err(e) = listener {
                    warn!(robot = %robot_id, error = %e, "zenoh: no matching listener, every state is published");
                    matching.store(true, Ordering::Relaxed);
                }
                // One stream per robot (`crate::runs::executing`) publishes its states, so a robot's publisher and token
                // are declared once.
                let alive =
                    match self.session.liveliness().declare_token(robot_alive_key(cell, robot_id)).await {
                        Ok(token) => Some(token),
                        Err(e) => {
                            warn!(robot = %robot_id, error = %e, "zenoh: no liveliness token for the robot");
                            None
                        }
                    };
                let out = Arc::new(RobotPublisher {
                    publisher,
                    matching,
                    last_stamp: Mutex::new(f64::NEG_INFINITY),
                    _alive: alive,
                });
                let mut map = self.publishers.lock().unwrap_or_else(|p| p.into_inner());
                // A concurrent first publish may have won: keep its publisher, drop (undeclare) this one.
                let cell_map = map.entry(cell.to_owned()).or_default();
                Some(cell_map.entry(robot_id.to_owned()).or_insert(out).clone())
            }
            Err(e) => {
                warn!(robot = %robot_id, error = %e, "zenoh: cannot declare the robot's publisher");
                None
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::ZenohConfig;
    use crate::zenoh_bridge::{ZenohBridge, open_session};
    use dmp_proto::keys::obstacle_key;
    use dmp_proto::zenoh_session::locators;
    use std::future::IntoFuture;
    use std::time::Duration;
    use tokio_util::sync::CancellationToken;

    async fn within<F: IntoFuture>(what: &str, f: F) -> F::Output {
        tokio::time::timeout(Duration::from_secs(10), f).await.unwrap_or_else(|_| panic!("timed out: {what}"))
    }

    fn state(id: &str, x: f64) -> v1::RobotState {
        v1::RobotState {
            robot_id: id.into(),
            stamp_unix_s: crate::clock::system_unix_s(),
            position: vec![x, 0.0, 0.0],
            velocity: vec![0.0; 3],
            footprint: Some(v1::Superquadric { semi_axes: vec![0.2; 3], exponents: vec![] }),
            ..Default::default()
        }
    }

    #[tokio::test(flavor = "multi_thread")]
    async fn without_zenoh_states_stay_local() {
        let scene = Cell::new("c", 10);
        let bus = RobotBus::new(None);
        bus.publish(&scene, state("r1", 1.0), None).await;
        assert_eq!(scene.other_robots("r2", crate::clock::system_unix_s(), 60.0).len(), 1);
        bus.retire(&scene, "r1").await;
        assert!(scene.other_robots("r2", crate::clock::system_unix_s(), 60.0).is_empty());
    }

    /// Two servers of one cell: the robots of one are seen by the other through Zenoh.
    #[tokio::test(flavor = "multi_thread")]
    async fn zenoh_robot_states_reach_another_server() {
        let cfg = |connect| ZenohConfig {
            disabled: false,
            mode: "peer".into(),
            listen: vec!["tcp/127.0.0.1:0".into()],
            connect,
            multicast_scouting: false,
            config_file: None,
        };
        // b (with the bridge) listens; a (with the bus) connects to it and so knows b's subscribers on opening.
        let b = within("open b", open_session(&cfg(vec![]))).await.unwrap();
        let cells_b = Cells::new("c", 10, 10).unwrap();
        let scene_b = cells_b.get("c").unwrap();
        let shutdown = CancellationToken::new();
        let bridge = within(
            "bridge b",
            ZenohBridge::start(
                b.clone(),
                cells_b,
                crate::clock::Clock::system(),
                crate::cells::state_admission::StateAdmission::new(&Default::default()),
                shutdown.clone(),
            ),
        )
        .await
        .unwrap();
        let a = within("open a", open_session(&cfg(locators(&b).await))).await.unwrap();
        let scene_a = Cell::new("c", 10);
        let bus = RobotBus::new(Some((a.clone(), 0.0)));

        // Belt and braces: a knows b's robot subscriber (declared after the obstacle one) before publishing.
        let probe = within("probe", a.declare_publisher(robot_state_key("c", "probe"))).await.unwrap();
        let listener = within("listener", probe.matching_listener()).await.unwrap();
        if !within("status", probe.matching_status()).await.unwrap().matching() {
            while !within("matching", listener.recv_async()).await.unwrap().matching() {}
        }
        drop(listener);
        drop(probe);
        let mut rx = scene_b.subscribe();
        bus.publish(&scene_a, state("r1", 1.0), None).await;
        bus.publish(&scene_a, state("r1", 2.0), None).await;
        assert_eq!(bus.publishers(), 1);
        // A sentinel obstacle sent after the states on the same session: when it arrives, so have they.
        let sentinel = obstacle_key("c", "sentinel");
        within("sentinel", a.put(&sentinel, r#"{"center": [0], "semi_axes": [1]}"#)).await.unwrap();
        within("scene b", rx.changed()).await.unwrap();
        let seen = scene_b.other_robots("r2", crate::clock::system_unix_s(), 60.0);
        assert_eq!(seen.len(), 1);
        assert_eq!(seen[0].state.position, vec![2.0, 0.0, 0.0]);
        assert!(seen[0].footprint.is_some());
        assert_eq!(
            scene_a.other_robots("r2", crate::clock::system_unix_s(), 60.0).len(),
            1,
            "recorded locally"
        );

        bus.retire(&scene_a, "r1").await;
        assert_eq!(bus.publishers(), 0);
        assert!(scene_a.other_robots("r2", crate::clock::system_unix_s(), 60.0).is_empty());
        within("sentinel delete", a.delete(&sentinel)).await.unwrap();
        within("scene b", rx.changed()).await.unwrap();
        assert!(scene_b.other_robots("r2", crate::clock::system_unix_s(), 60.0).is_empty());
        assert_eq!(bridge.malformed_payloads(), 0);

        shutdown.cancel();
        within("close bridge", bridge.close()).await;
        within("session a", a.close()).await.unwrap();
        within("session b", b.close()).await.unwrap();
    }
}
