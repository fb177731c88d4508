//! The cells for RViz: each cell's obstacles (true shape and isopotential) and its robots' planned paths
//! ([`super::marker_shapes`]), as a `visualization_msgs/msg/MarkerArray` on `/dmp/<cell>/markers` (the cell's name
//! as a topic token), in the cell's frame, whenever the scene or a path changes.
//!
//! Each marker keeps its id in its namespace while its obstacle or robot is there. A message carries what changed:
//! an ADD for each new or changed marker, a DELETE for each whose obstacle or robot went. The first message of a
//! cell starts with a DELETEALL (markers of an earlier run of the server), and every [`FULL_REFRESH_S`] the whole
//! set goes again, so that a tool that subscribes late draws everything. Each sample carries rmw_zenoh's attachment,
//! and the publisher its liveliness token ([`super::graph`]).

use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;
use std::time::Duration;

use dmp_proto::v1;
use dmp_ros2::keys::MARKER_ARRAY;
use dmp_ros2::msgs::builtin_interfaces::Time;
use dmp_ros2::msgs::std_msgs::Header;
use dmp_ros2::msgs::visualization_msgs::{Marker, MarkerArray};
use tokio::task::JoinHandle;
use tokio_util::sync::CancellationToken;
use tracing::{debug, warn};

use super::graph::{Graph, RosPublisher};
use super::marker_shapes::{isopotential, path, true_shape};
use super::paths::Paths;
use super::trajectory::topic_token;
use crate::cells::Cells;
use crate::cells::cell::ObstacleSet;
use crate::clock::Clock;

/// How often the cells' versions are looked at.
pub(crate) const PERIOD: Duration = Duration::from_millis(100);

/// How often every marker goes again, changed or not (seconds).
pub(crate) const FULL_REFRESH_S: f64 = 5.0;

/// The topic of a cell's markers.
pub(crate) fn markers_topic(cell: &str) -> String {
    format!("/dmp/{}/markers", topic_token(cell))
}

/// A marker's identity: its namespace and its obstacle's or robot's id.
type Key = (String, String);

/// The markers a tool shows, as the messages so far left them; what a new set of wanted markers changes.
#[derive(Debug, Default)]
pub struct Shown {
    shown: BTreeMap<Key, Marker>,
    next_id: i32,
    started: bool,
}

impl Shown {
    /// What to send so that the tool shows `wanted` (headerless markers, keyed by namespace and text): a
    /// DELETEALL first the first time, an ADD per new or changed marker (every marker when `full`), a DELETE per
    /// marker no longer wanted. Ids stay while a key stays.
    pub fn update(&mut self, wanted: Vec<Marker>, full: bool) -> Vec<Marker> {
        let mut out = Vec::new();
        if !self.started {
            self.started = true;
            out.push(Marker { action: Marker::DELETEALL, ..Default::default() });
        }
        let wanted: BTreeMap<Key, Marker> =
            wanted.into_iter().map(|m| ((m.ns.clone(), m.text.clone()), m)).collect();
        let gone: Vec<Key> = self.shown.keys().filter(|k| !wanted.contains_key(*k)).cloned().collect();
        for key in gone {
            if let Some(old) = self.shown.remove(&key) {
                out.push(Marker { ns: old.ns, id: old.id, action: Marker::DELETE, ..Default::default() });
            }
        }
        for (key, mut m) in wanted {
            m.id = match self.shown.get(&key) {
                Some(old) => old.id,
                None => {
                    self.next_id = self.next_id.wrapping_add(1);
                    self.next_id
                }
            };
            if full || self.shown.get(&key) != Some(&m) {
                out.push(m.clone());
                self.shown.insert(key, m);
            }
        }
        out
    }
}

/// The message of `markers` (from [`Shown::update`]): each with the header of `frame` at `now_unix_s`.
pub fn marker_array(frame: &str, now_unix_s: f64, mut markers: Vec<Marker>) -> MarkerArray {
    let header = Header { stamp: Time::from_unix_s(now_unix_s), frame_id: frame.to_owned() };
    for m in &mut markers {
        m.header = header.clone();
    }
    MarkerArray { markers }
}

/// One cell's publisher and what it showed.
struct CellMarkers {
    publisher: RosPublisher,
    scene_version: Option<u64>,
    paths_version: Option<u64>,
    paths: Vec<Marker>,
    /// Each obstacle's markers, with the obstacle they were drawn from (not drawn again while it is the same).
    drawn: HashMap<String, (v1::Obstacle, Vec<Marker>)>,
    shown: Shown,
    last_full_unix_s: f64,
}

impl CellMarkers {
    /// The markers of `scene`, drawing again only the obstacles that changed.
    fn obstacles(&mut self, scene: &ObstacleSet) -> Vec<Marker> {
        self.drawn.retain(|id, _| scene.obstacles.contains_key(id));
        let mut out = Vec::new();
        for (id, o) in &scene.obstacles {
            let fresh = self.drawn.get(id).is_some_and(|(proto, _)| *proto == o.proto);
            if !fresh {
                let markers = true_shape(&o.proto).into_iter().chain(isopotential(&o.engine)).collect();
                self.drawn.insert(id.clone(), (o.proto.clone(), markers));
            }
            out.extend(self.drawn[id].1.iter().cloned());
        }
        out
    }
}

/// Spawns the task that publishes the cells' markers until `stop`.
pub(crate) fn spawn(
    graph: Arc<Graph>,
    frame: String,
    cells: Cells,
    paths: Paths,
    clock: Clock,
    stop: CancellationToken,
) -> JoinHandle<()> {
    tokio::spawn(async move {
        let mut publishers: HashMap<String, CellMarkers> = HashMap::new();
        let mut tick = tokio::time::interval(PERIOD);
        tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
        loop {
            tokio::select! {
                _ = stop.cancelled() => break,
                _ = tick.tick() => {}
            }
            for cell in cells.all() {
                let name = cell.name().to_owned();
                if !publishers.contains_key(&name) {
                    match graph.publisher(&markers_topic(&name), &MARKER_ARRAY).await {
                        Ok(publisher) => {
                            let c = CellMarkers {
                                publisher,
                                scene_version: None,
                                paths_version: None,
                                paths: Vec::new(),
                                drawn: HashMap::new(),
                                shown: Shown::default(),
                                last_full_unix_s: f64::NEG_INFINITY,
                            };
                            publishers.insert(name.clone(), c);
                        }
                        Err(e) => {
                            warn!(cell = %name, error = %e, "ros2: cannot declare the markers' publisher");
                            continue;
                        }
                    }
                }
                let Some(p) = publishers.get_mut(&name) else { continue };
                let now = clock.now_unix_s();
                let snap = cell.snapshot();
                let full = now - p.last_full_unix_s >= FULL_REFRESH_S;
                let new_paths = paths.changed(&name, p.paths_version);
                if !full && p.scene_version == Some(snap.version) && new_paths.is_none() {
                    continue;
                }
                if let Some(c) = new_paths {
                    p.paths = c.robots.iter().filter_map(|(robot, path_)| path(robot, path_)).collect();
                    p.paths_version = Some(c.version);
                }
                let mut wanted = p.obstacles(&snap);
                wanted.extend(p.paths.iter().cloned());
                let markers = p.shown.update(wanted, full);
                if markers.is_empty() {
                    p.scene_version = Some(snap.version);
                    continue;
                }
                let msg = marker_array(&frame, now, markers);
                if let Err(e) = p.publisher.put(&msg, now).await {
                    warn!(cell = %name, error = %e, "ros2: markers not published");
                    continue;
                }
                p.scene_version = Some(snap.version);
                if full {
                    p.last_full_unix_s = now;
                }
                debug!(cell = %name, version = snap.version, markers = msg.markers.len(), "ros2 markers published");
            }
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn marker(ns: &str, text: &str, x: f64) -> Marker {
        let mut m = Marker { ns: ns.into(), text: text.into(), action: Marker::ADD, ..Default::default() };
        m.pose.position.x = x;
        m
    }

    #[test]
    fn changes_are_sent_and_gone_markers_deleted() {
        let mut s = Shown::default();
        let first = s.update(vec![marker("obstacles", "a", 1.0), marker("paths", "r", 0.0)], false);
        assert_eq!(
            first.iter().map(|m| m.action).collect::<Vec<_>>(),
            [Marker::DELETEALL, Marker::ADD, Marker::ADD]
        );
        let id_a = first.iter().find(|m| m.text == "a").unwrap().id;
        // Nothing changed: nothing to send, unless full.
        assert!(s.update(vec![marker("obstacles", "a", 1.0), marker("paths", "r", 0.0)], false).is_empty());
        assert_eq!(s.update(vec![marker("obstacles", "a", 1.0), marker("paths", "r", 0.0)], true).len(), 2);
        // `a` moved and the robot left: `a` again with its id, a DELETE of the path.
        let next = s.update(vec![marker("obstacles", "a", 2.0)], false);
        assert_eq!(next.len(), 2);
        let del = next.iter().find(|m| m.action == Marker::DELETE).unwrap();
        assert_eq!(del.ns, "paths");
        let moved = next.iter().find(|m| m.action == Marker::ADD).unwrap();
        assert_eq!((moved.id, moved.pose.position.x), (id_a, 2.0));
        assert_eq!(markers_topic("cell-a.1"), "/dmp/cell_a_1/markers");
    }
}
