//! The task that publishes what the streams hand over ([`crate::runs::outbox`]): each segment as a
//! `trajectory_msgs/msg/MultiDOFJointTrajectory` on its robot's topic `/dmp/<robot>/trajectory`
//! ([`super::trajectory`]; a group run's members each on their own), and the positions into the robots' paths
//! ([`super::paths`]) for the markers. A robot's publisher (and its liveliness token) is declared at its first
//! segment and undeclared when its stream ends.

use std::collections::HashMap;
use std::sync::Arc;
use std::sync::atomic::Ordering;

use dmp_ros2::keys::MULTI_DOF_JOINT_TRAJECTORY;
use tokio::sync::mpsc;
use tokio::task::JoinHandle;
use tokio_util::sync::CancellationToken;
use tracing::{debug, warn};

use super::Ros2Counters;
use super::graph::{Graph, RosPublisher};
use super::paths::Paths;
use super::trajectory::{trajectory_message, trajectory_topic};
use crate::clock::Clock;
use crate::runs::outbox::Event;

/// What the task needs.
#[derive(Debug)]
pub(crate) struct Trajectories {
    /// The node.
    pub graph: Arc<Graph>,
    /// The cells' frame.
    pub frame: String,
    /// Where the positions sent go.
    pub paths: Paths,
    /// What was published.
    pub counters: Arc<Ros2Counters>,
    /// The publishers' clock.
    pub clock: Clock,
}

impl Trajectories {
    /// Publishes what arrives on `rx` until `stop` or until every handle is gone.
    pub(crate) fn spawn(self, mut rx: mpsc::Receiver<Event>, stop: CancellationToken) -> JoinHandle<()> {
        tokio::spawn(async move {
            let mut publishers: HashMap<String, RosPublisher> = HashMap::new();
            loop {
                let event = tokio::select! {
                    _ = stop.cancelled() => break,
                    e = rx.recv() => match e { Some(e) => e, None => break },
                };
                match event {
                    Event::Sent { cell, segments, sent_unix_s } => {
                        for s in &segments {
                            let stamp = if s.start_unix_s > 0.0 { s.start_unix_s } else { sent_unix_s };
                            let msg = trajectory_message(s, &self.frame, stamp);
                            let Some(p) = self.publisher(&mut publishers, &s.robot_id).await else {
                                continue;
                            };
                            match p.put(&msg, self.clock.now_unix_s()).await {
                                Ok(()) => {
                                    self.counters.trajectories_published.fetch_add(1, Ordering::Relaxed);
                                }
                                Err(e) => {
                                    warn!(robot = %s.robot_id, error = %e, "ros2: trajectory not published")
                                }
                            }
                        }
                        self.paths.extend(&cell, &segments);
                    }
                    Event::Ended { cell, robots } => {
                        for r in &robots {
                            publishers.remove(r);
                        }
                        self.paths.remove(&cell, &robots);
                        debug!(%cell, ?robots, "ros2: trajectories ended");
                    }
                }
            }
        })
    }

    /// `robot`'s publisher, declared at its first segment; none (logged) if Zenoh refuses it.
    async fn publisher<'a>(
        &self,
        publishers: &'a mut HashMap<String, RosPublisher>,
        robot: &str,
    ) -> Option<&'a mut RosPublisher> {
        if !publishers.contains_key(robot) {
            match self.graph.publisher(&trajectory_topic(robot), &MULTI_DOF_JOINT_TRAJECTORY).await {
                Ok(p) => {
                    publishers.insert(robot.to_owned(), p);
                }
                Err(e) => {
                    warn!(%robot, error = %e, "ros2: cannot declare the trajectory's publisher");
                    return None;
                }
            }
        }
        publishers.get_mut(robot)
    }
}
