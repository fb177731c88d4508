//! ROS 2 over rmw_zenoh, with no bridge process (`--ros2-domain N`, the `[ros2]` section): the server subscribes
//! to ROS 2 topics on the Zenoh session it already has, as rmw_zenoh puts them
//! (`<domain>/<topic>/<type>/<type hash>`, a CDR payload; `dmp_ros2` holds the messages and keys), and maps them
//! into the cells' scenes.
//!
//! | topic (default) | type | effect |
//! | --- | --- | --- |
//! | `/collision_object` | `moveit_msgs/msg/CollisionObject` | objects' shapes as obstacles ([`collision`], [`shapes`]) |
//! | configured | `nav2_dynamic_msgs/msg/ObstacleArray` | tracked boxes, moving ([`obstacle_array`]) |
//! | out: `/dmp/<cell>/markers` | `visualization_msgs/msg/MarkerArray` | each cell's obstacles (true shape and isopotential) and robots' paths for RViz ([`markers`], [`marker_shapes`]) |
//! | out: `/dmp/<robot>/trajectory` | `trajectory_msgs/msg/MultiDOFJointTrajectory` | each segment sent to a robot ([`trajectory`], [`trajectories`]) |
//!
//! The streams hand their segments over through [`crate::runs::outbox`] without ever waiting (a full channel drops and counts);
//! the server is one node of ROS 2's graph ([`graph`]).
//!
//! A message whose `header.frame_id` is neither the cell's frame (`ros2.frame`, `world`) nor a frame of
//! `ros2.static_transforms` is refused; so is one that does not decode or breaks a rule. Every refusal is logged
//! at warn with the key and the reason, and counted twice: in the server's malformed Zenoh payloads (GetStats, the
//! metrics) and in [`Ros2Counters`].

pub(crate) mod collision;
pub(crate) mod graph;
pub mod marker_shapes;
pub mod markers;
pub(crate) mod obstacle_array;

pub mod paths;
pub(crate) mod shapes;
pub(crate) mod trajectories;
pub mod trajectory;

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

use dmp_ros2::keys::{COLLISION_OBJECT, OBSTACLE_ARRAY, topic_subscription};
use dmp_ros2::msgs::moveit_msgs::CollisionObject;
use dmp_ros2::msgs::nav2_dynamic_msgs::ObstacleArray;
use tracing::{debug, info, warn};
use zenoh::pubsub::Subscriber;
use zenoh::sample::Sample;
use zenoh::{Session, Wait};

use crate::cells::Cells;
use crate::clock::Clock;
use crate::config::ros2::{Ros2Config, Ros2Topic, TopicKind};
use crate::error::ServerError;
use crate::runs::outbox::Ros2Out;
use crate::zenoh_bridge::ZenohSide;

/// What the ROS 2 bridge took and refused.
#[derive(Debug, Default)]
pub struct Ros2Counters {
    /// Messages applied.
    pub applied: AtomicU64,
    /// Messages refused for their frame.
    pub refused_frames: AtomicU64,
    /// Messages refused for any reason (frames included).
    pub refused: AtomicU64,
    /// Trajectories published (one per segment sent to a robot).
    pub trajectories_published: AtomicU64,
    /// Segments not published as trajectories: the publisher was behind and the streams do not wait for it.
    pub trajectories_dropped: Arc<AtomicU64>,
}

impl Ros2Counters {
    /// A counter's value.
    pub fn get(counter: &AtomicU64) -> u64 {
        counter.load(Ordering::Relaxed)
    }
}

/// Why a message was refused.
enum Refusal {
    Frame(String),
    Other(ServerError),
}

impl From<ServerError> for Refusal {
    fn from(e: ServerError) -> Self {
        Refusal::Other(e)
    }
}

/// The state the subscribers' callbacks share.
#[derive(Debug)]
struct Inbox {
    config: Ros2Config,
    cells: Cells,
    clock: Clock,
    objects: Mutex<collision::Objects>,
    tracks: Mutex<obstacle_array::Tracks>,
    counters: Arc<Ros2Counters>,
    malformed: Arc<AtomicU64>,
}

impl Inbox {
    fn sample(&self, topic: &Ros2Topic, sample: &Sample) {
        let result = if sample.kind() == zenoh::sample::SampleKind::Delete {
            debug!(key = %sample.key_expr(), "ros2: a delete is not a message; ignored");
            return;
        } else {
            self.apply(topic, &sample.payload().to_bytes())
        };
        match result {
            Ok(()) => {
                self.counters.applied.fetch_add(1, Ordering::Relaxed);
            }
            Err(refusal) => {
                self.counters.refused.fetch_add(1, Ordering::Relaxed);
                let malformed = self.malformed.fetch_add(1, Ordering::Relaxed) + 1;
                let reason = match refusal {
                    Refusal::Frame(f) => {
                        self.counters.refused_frames.fetch_add(1, Ordering::Relaxed);
                        format!(
                            "header.frame_id: `{f}` is neither the cell's frame `{}` nor a frame of ros2.static_transforms",
                            self.config.frame
                        )
                    }
                    Refusal::Other(e) => e.to_string(),
                };
                warn!(key = %sample.key_expr(), %reason, malformed_payloads = malformed, "ros2 message refused");
            }
        }
    }

    fn apply(&self, topic: &Ros2Topic, bytes: &[u8]) -> Result<(), Refusal> {
        let decode_err = |e: dmp_ros2::CdrError| ServerError::invalid("payload", e.to_string());
        let cell = self.cells.get(&topic.cell)?;
        let now = self.clock.now_unix_s();
        match topic.kind {
            TopicKind::CollisionObject => {
                let msg: CollisionObject = dmp_ros2::decode(bytes).map_err(decode_err)?;
                let frame = self.frame(&msg.header.frame_id)?;
                let mut objects = self.objects.lock().unwrap_or_else(|p| p.into_inner());
                objects.apply(&cell, &msg, frame, now)?;
            }
            TopicKind::ObstacleArray => {
                let msg: ObstacleArray = dmp_ros2::decode(bytes).map_err(decode_err)?;
                let frame = self.frame(&msg.header.frame_id)?;
                let mut tracks = self.tracks.lock().unwrap_or_else(|p| p.into_inner());
                tracks.apply(&cell, &topic.topic, &msg, frame, now)?;
            }
        }
        Ok(())
    }

    fn frame(&self, frame_id: &str) -> Result<dmp_ros2::pose::Rigid, Refusal> {
        self.config.frame_to_cell(frame_id).ok_or_else(|| Refusal::Frame(frame_id.to_owned()))
    }
}

/// The subscribers of the configured topics.
#[derive(Debug)]
pub(crate) struct Ros2Bridge {
    subscribers: Vec<Subscriber<()>>,
    counters: Arc<Ros2Counters>,
    outbox: Ros2Out,
    markers: tokio::task::JoinHandle<()>,
    trajectories: tokio::task::JoinHandle<()>,
    stop: tokio_util::sync::CancellationToken,
}

impl Ros2Bridge {
    /// The bridge `config` asks for (none without `ros2.domain`), on the session of `zenoh`, into `cells`; its
    /// refusals also count in the Zenoh bridge's malformed payloads.
    pub(crate) async fn start_configured(
        zenoh: &ZenohSide,
        config: &Ros2Config,
        cells: &Cells,
        clock: Clock,
    ) -> Result<Option<Self>, ServerError> {
        if config.domain.is_none() {
            return Ok(None);
        }
        let (Some(session), Some(bridge)) = (&zenoh.session, &zenoh.bridge) else {
            return Err(ServerError::FailedPrecondition("ros2.domain needs Zenoh (not --no-zenoh)".into()));
        };
        Ok(Some(Self::start(session, config, cells.clone(), clock, bridge.malformed_counter()).await?))
    }

    /// Subscribes to every topic of `config` in its domain on `session`. Refusals are also added to `malformed`
    /// (the Zenoh bridge's counter).
    pub(crate) async fn start(
        session: &Session,
        config: &Ros2Config,
        cells: Cells,
        clock: Clock,
        malformed: Arc<AtomicU64>,
    ) -> Result<Self, ServerError> {
        config.check()?;
        let Some(domain) = config.domain else {
            return Err(ServerError::invalid("ros2.domain", "is required to start the ROS 2 bridge"));
        };
        let counters = Arc::new(Ros2Counters::default());
        let inbox = Arc::new(Inbox {
            config: config.clone(),
            cells: cells.clone(),
            clock,
            objects: Mutex::default(),
            tracks: Mutex::default(),
            counters: counters.clone(),
            malformed,
        });
        let mut subscribers = Vec::new();
        for topic in &config.topics {
            let ty = match topic.kind {
                TopicKind::CollisionObject => COLLISION_OBJECT,
                TopicKind::ObstacleArray => OBSTACLE_ARRAY,
            };
            let key = topic_subscription(domain, &topic.topic, &ty);
            let (inbox, t) = (inbox.clone(), topic.clone());
            let sub = session
                .declare_subscriber(&key)
                .callback(move |sample| inbox.sample(&t, &sample))
                .await
                .map_err(|e| ServerError::Internal(format!("zenoh: cannot subscribe to {key}: {e}")))?;
            info!(%key, cell = %topic.cell, "ros2 topic subscribed");
            subscribers.push(sub);
        }
        let stop = tokio_util::sync::CancellationToken::new();
        let graph = Arc::new(graph::Graph::declare(session.clone(), domain).await);
        let paths = paths::Paths::default();
        let (outbox, rx) = Ros2Out::channel(counters.trajectories_dropped.clone());
        let trajectories = trajectories::Trajectories {
            graph: graph.clone(),
            frame: config.frame.clone(),
            paths: paths.clone(),
            counters: counters.clone(),
            clock,
        }
        .spawn(rx, stop.clone());
        let markers = markers::spawn(graph, config.frame.clone(), cells, paths, clock, stop.clone());
        Ok(Self { subscribers, counters, outbox, markers, trajectories, stop })
    }

    /// Where the streams hand their segments over.
    pub(crate) fn outbox(&self) -> Ros2Out {
        self.outbox.clone()
    }

    /// What the bridge took and refused so far.
    pub(crate) fn counters(&self) -> Arc<Ros2Counters> {
        self.counters.clone()
    }

    /// Stops the markers' and trajectories' publishers and undeclares the subscribers, waiting for running callbacks.
    pub(crate) async fn close(self) {
        self.stop.cancel();
        if let Err(e) = self.markers.await {
            warn!(error = %e, "ros2 markers task failed");
        }
        if let Err(e) = self.trajectories.await {
            warn!(error = %e, "ros2 trajectories task failed");
        }
        let subscribers = self.subscribers;
        let done = tokio::task::spawn_blocking(move || {
            for s in subscribers {
                if let Err(e) = s.undeclare().wait_callbacks().wait() {
                    debug!(error = %e, "ros2 subscriber undeclare failed (session closed?)");
                }
            }
        })
        .await;
        if let Err(e) = done {
            warn!(error = %e, "ros2 subscriber undeclare task failed");
        }
    }
}
