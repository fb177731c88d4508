//! A typed async client of the three gRPC services (`proto/dmp/v1`): primitives, scene and motion.
//!
//! [`DmpClient`] is cheap to clone and every method takes `&self`, so one client serves many concurrent calls (each
//! call clones the underlying HTTP/2 channel handle). Server-streaming calls return boxed streams whose items are
//! `Result<_, ClientError>`; dropping a stream cancels the call on the server.
//!
//! ```no_run
//! # async fn demo() -> Result<(), dmp_client::ClientError> {
//! use dmp_client::grpc::DmpClient;
//! let client = DmpClient::connect("http://127.0.0.1:50051").await?;
//! for record in client.list("panda-1").await? {
//!     println!("{} v{}", record.name, record.version);
//! }
//! # Ok(()) }
//! ```

use std::fmt;
use std::pin::Pin;
use std::time::Duration;

use dmp_proto::v1;
use dmp_proto::v1::motion_service_client::MotionServiceClient;
use dmp_proto::v1::primitive_service_client::PrimitiveServiceClient;
use dmp_proto::v1::scene_service_client::SceneServiceClient;
use dmp_proto::v1::server_service_client::ServerServiceClient;
use dmp_proto::v1::session_request::Message;
use tokio::sync::mpsc;
use tokio_stream::wrappers::ReceiverStream;
use tokio_stream::{Stream, StreamExt};
use tonic::transport::{Channel, Endpoint};

use crate::convert::{primitive_from_proto, primitive_to_proto};
use crate::error::ClientError;
use crate::setpoints::Setpoints;

/// The server `dmpctl` talks to unless told otherwise.
pub const DEFAULT_SERVER: &str = "http://127.0.0.1:50051";

/// How long [`DmpClient::connect`] waits for the server.
pub const CONNECT_TIMEOUT: Duration = Duration::from_secs(5);

/// Largest message sent or received (a 1,000,000-step 3-D plan is ~75 MB).
pub const MAX_MESSAGE_BYTES: usize = 256 * 1024 * 1024;

/// Messages a session may queue before [`SessionSender`] waits for the server to read.
const SESSION_QUEUE: usize = 64;

/// Segments of an Execute or Session call.
pub type SegmentStream = Pin<Box<dyn Stream<Item = Result<v1::Segment, ClientError>> + Send>>;

/// Steps of an ExecuteGroup call.
pub type GroupStream = Pin<Box<dyn Stream<Item = Result<v1::GroupSegment, ClientError>> + Send>>;

/// Snapshots of a WatchScene call: the current scene, then one per change.
pub type SceneStream = Pin<Box<dyn Stream<Item = Result<v1::SceneSnapshot, ClientError>> + Send>>;

/// A client of the DMP cell's server.
#[derive(Debug, Clone)]
pub struct DmpClient {
    url: String,
    primitives: PrimitiveServiceClient<Channel>,
    scene: SceneServiceClient<Channel>,
    motion: MotionServiceClient<Channel>,
    server: ServerServiceClient<Channel>,
    /// The cell of the scene requests; empty means the server's default cell.
    cell: String,
}

/// Every error of an error's chain, `: `-separated (tonic's transport error says little on its own).
fn chain(e: &dyn std::error::Error) -> String {
    let mut out = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        let text = s.to_string();
        if !out.contains(&text) {
            out.push_str(": ");
            out.push_str(&text);
        }
        source = s.source();
    }
    out
}

fn missing(what: &str) -> ClientError {
    ClientError::Protocol(format!("the answer has no `{what}`"))
}

fn boxed<T: Send + 'static>(
    s: tonic::Streaming<T>,
) -> Pin<Box<dyn Stream<Item = Result<T, ClientError>> + Send>> {
    Box::pin(s.map(|r| r.map_err(ClientError::from)))
}

impl DmpClient {
    /// Connects to `url` (`http://HOST:PORT`; a bare `HOST:PORT` means `http://`), waiting at most
    /// [`CONNECT_TIMEOUT`].
    pub async fn connect(url: impl Into<String>) -> Result<Self, ClientError> {
        Self::connect_with_timeout(url, CONNECT_TIMEOUT).await
    }

    /// Connects to `url`, waiting at most `timeout`. A server that refuses or does not answer gives
    /// [`ClientError::Connect`]; an address that does not parse gives [`ClientError::Argument`].
    pub async fn connect_with_timeout(
        url: impl Into<String>,
        timeout: Duration,
    ) -> Result<Self, ClientError> {
        let mut url = url.into();
        if !url.contains("://") {
            url = format!("http://{url}");
        }
        let endpoint = Endpoint::from_shared(url.clone())
            .map_err(|e| {
                ClientError::argument("server", format!("`{url}` is not a valid address: {}", chain(&e)))
            })?
            .connect_timeout(timeout)
            .tcp_nodelay(true);
        let channel = match tokio::time::timeout(timeout, endpoint.connect()).await {
            Err(_) => {
                return Err(ClientError::Connect { url, message: format!("no answer within {timeout:?}") });
            }
            Ok(Err(e)) => return Err(ClientError::Connect { url, message: chain(&e) }),
            Ok(Ok(c)) => c,
        };
        Ok(Self::from_channel(channel, url))
    }

    /// A client over an existing channel (`url` only names it in messages).
    pub fn from_channel(channel: Channel, url: impl Into<String>) -> Self {
        let n = MAX_MESSAGE_BYTES;
        Self {
            url: url.into(),
            primitives: PrimitiveServiceClient::new(channel.clone())
                .max_decoding_message_size(n)
                .max_encoding_message_size(n),
            scene: SceneServiceClient::new(channel.clone())
                .max_decoding_message_size(n)
                .max_encoding_message_size(n),
            motion: MotionServiceClient::new(channel.clone())
                .max_decoding_message_size(n)
                .max_encoding_message_size(n),
            server: ServerServiceClient::new(channel),
            cell: String::new(),
        }
    }

    /// The same client, with its scene requests (put, delete, list, watch) in `cell` (empty: the server's
    /// default cell). Motions name their cell in `MotionSpec::cell`.
    pub fn with_cell(mut self, cell: impl Into<String>) -> Self {
        self.cell = cell.into();
        self
    }

    /// The cell of the scene requests (empty: the server's default).
    pub fn cell(&self) -> &str {
        &self.cell
    }

    /// The server's resource use and traffic.
    pub async fn stats(&self) -> Result<v1::ServerStats, ClientError> {
        Ok(self.server.clone().get_stats(v1::GetStatsRequest {}).await?.into_inner())
    }

    /// The server's address.
    pub fn url(&self) -> &str {
        &self.url
    }

    // --- Primitives -------------------------------------------------------------------------------------------

    /// Learns a primitive from one demonstration (`t[k]` is the time of row `rows[k]`) and stores it as the next
    /// version of `(robot, name)`; returns once it is durable.
    pub async fn learn(
        &self,
        robot: &str,
        name: &str,
        t: &[f64],
        rows: &[Vec<f64>],
        parameters: v1::LearnParameters,
    ) -> Result<v1::PrimitiveRecord, ClientError> {
        let dim = rows.first().map_or(0, Vec::len);
        if t.len() != rows.len() {
            return Err(ClientError::argument(
                "demonstration.t",
                format!("has {} times for {} rows of positions", t.len(), rows.len()),
            ));
        }
        if let Some(i) = rows.iter().position(|r| r.len() != dim) {
            return Err(ClientError::argument(
                format!("demonstration.x[{i}]"),
                format!("has {} coordinates, expected {dim} like the first row", rows[i].len()),
            ));
        }
        let demonstration = v1::Demonstration {
            t: t.to_vec(),
            positions: rows.iter().flatten().copied().collect(),
            dim: dim as u32,
        };
        let request = v1::LearnRequest {
            robot_id: robot.into(),
            name: name.into(),
            demonstration: Some(demonstration),
            parameters: Some(parameters),
        };
        let r = self.primitives.clone().learn(request).await?.into_inner();
        r.record.ok_or_else(|| missing("record"))
    }

    /// Stores a primitive learned elsewhere as the next version of `(robot, name)`.
    pub async fn put_primitive(
        &self,
        robot: &str,
        name: &str,
        primitive: &dmp::Primitive,
    ) -> Result<v1::PrimitiveRecord, ClientError> {
        let request = v1::PutPrimitiveRequest {
            robot_id: robot.into(),
            name: name.into(),
            primitive: Some(primitive_to_proto(primitive)),
        };
        let r = self.primitives.clone().put(request).await?.into_inner();
        r.record.ok_or_else(|| missing("record"))
    }

    /// One primitive: `version` 0 is the latest.
    pub async fn get(
        &self,
        robot: &str,
        name: &str,
        version: u64,
    ) -> Result<v1::PrimitiveRecord, ClientError> {
        let request = v1::GetPrimitiveRequest { robot_id: robot.into(), name: name.into(), version };
        Ok(self.primitives.clone().get(request).await?.into_inner())
    }

    /// The latest version of each of a robot's primitives, sorted by name.
    pub async fn list(&self, robot: &str) -> Result<Vec<v1::PrimitiveRecord>, ClientError> {
        let request = v1::ListPrimitivesRequest { robot_id: robot.into() };
        Ok(self.primitives.clone().list(request).await?.into_inner().records)
    }

    /// Deletes every version of `(robot, name)`; returns how many there were.
    pub async fn delete(&self, robot: &str, name: &str) -> Result<u64, ClientError> {
        let request = v1::DeletePrimitiveRequest { robot_id: robot.into(), name: name.into() };
        Ok(self.primitives.clone().delete(request).await?.into_inner().versions_deleted)
    }

    // --- Motion -----------------------------------------------------------------------------------------------

    /// The whole trajectory at once.
    pub async fn plan(&self, request: v1::PlanRequest) -> Result<v1::PlanResponse, ClientError> {
        Ok(self.motion.clone().plan(request).await?.into_inner())
    }

    /// Streams a primitive's execution in segments (see [`Setpoints`] for which points are current).
    pub async fn execute(&self, request: v1::ExecuteRequest) -> Result<SegmentStream, ClientError> {
        Ok(boxed(self.motion.clone().execute(request).await?.into_inner()))
    }

    /// Opens a session started by `start`: commands go through the returned [`Session`]'s sender, segments come
    /// from its stream.
    pub async fn session(&self, start: v1::ExecuteRequest) -> Result<Session, ClientError> {
        let (tx, rx) = mpsc::channel(SESSION_QUEUE);
        // The start message is queued before the call, so the server has it as soon as the stream opens.
        tx.try_send(v1::SessionRequest { message: Some(Message::Start(start)) })
            .map_err(|_| ClientError::Closed("the session queue".into()))?;
        let segments = boxed(self.motion.clone().session(ReceiverStream::new(rx)).await?.into_inner());
        Ok(Session { sender: SessionSender { tx }, segments })
    }

    /// Executes several robots on one shared phase.
    pub async fn execute_group(&self, request: v1::ExecuteGroupRequest) -> Result<GroupStream, ClientError> {
        Ok(boxed(self.motion.clone().execute_group(request).await?.into_inner()))
    }

    // --- Scene ------------------------------------------------------------------------------------------------

    /// Adds or replaces an obstacle of the cell's scene.
    pub async fn put_obstacle(&self, obstacle: v1::Obstacle) -> Result<v1::SceneChange, ClientError> {
        let request = v1::PutObstacleRequest { obstacle: Some(obstacle), cell: self.cell.clone() };
        Ok(self.scene.clone().put_obstacle(request).await?.into_inner())
    }

    /// Removes an obstacle (`changed` is false when there was none of that id).
    pub async fn delete_obstacle(&self, id: &str) -> Result<v1::SceneChange, ClientError> {
        let request = v1::DeleteObstacleRequest { id: id.into(), cell: self.cell.clone() };
        Ok(self.scene.clone().delete_obstacle(request).await?.into_inner())
    }

    /// The current obstacles.
    pub async fn list_obstacles(&self) -> Result<v1::SceneSnapshot, ClientError> {
        Ok(self
            .scene
            .clone()
            .list_obstacles(v1::ListObstaclesRequest { cell: self.cell.clone() })
            .await?
            .into_inner())
    }

    /// The current scene, then the scene after every change.
    pub async fn watch_scene(&self) -> Result<SceneStream, ClientError> {
        let events = self
            .scene
            .clone()
            .watch_scene(v1::WatchSceneRequest { cell: self.cell.clone() })
            .await?
            .into_inner();
        Ok(Box::pin(
            events.map(|r| r.map_err(ClientError::from)?.snapshot.ok_or_else(|| missing("snapshot"))),
        ))
    }
}

/// The engine's primitive of a record.
pub fn record_primitive(record: &v1::PrimitiveRecord) -> Result<dmp::Primitive, ClientError> {
    let p = record.primitive.as_ref().ok_or_else(|| missing("primitive"))?;
    primitive_from_proto(p).map_err(|e| ClientError::Protocol(format!("primitive of the record: {e}")))
}

/// Reads a segment stream to its end, applying supersession; `on_segment` sees every segment first (e.g. to
/// print it). Fails at the first error of the stream or inconsistent segment.
pub async fn collect_setpoints<S>(
    mut stream: S,
    mut on_segment: impl FnMut(&v1::Segment),
) -> Result<Setpoints, ClientError>
where
    S: Stream<Item = Result<v1::Segment, ClientError>> + Unpin,
{
    let mut s = Setpoints::new();
    while let Some(seg) = stream.next().await {
        let seg = seg?;
        on_segment(&seg);
        s.push(&seg)?;
    }
    Ok(s)
}

/// The sending half of a session: commands and measured states. Cloneable; a send fails once the session ended.
#[derive(Debug, Clone)]
pub struct SessionSender {
    tx: mpsc::Sender<v1::SessionRequest>,
}

impl SessionSender {
    /// Sends one message.
    pub async fn send(&self, message: Message) -> Result<(), ClientError> {
        self.tx
            .send(v1::SessionRequest { message: Some(message) })
            .await
            .map_err(|_| ClientError::Closed("the session".into()))
    }

    /// Changes the goal, from the current state.
    pub async fn set_goal(&self, goal: Vec<f64>) -> Result<(), ClientError> {
        self.send(Message::SetGoal(v1::SetGoal { goal })).await
    }

    /// Changes tau (larger is slower), from the current state.
    pub async fn set_tau(&self, tau: f64) -> Result<(), ClientError> {
        self.send(Message::SetTau(v1::SetTau { tau })).await
    }

    /// Holds position.
    pub async fn pause(&self) -> Result<(), ClientError> {
        self.send(Message::Pause(v1::Pause {})).await
    }

    /// Resumes after a pause.
    pub async fn resume(&self) -> Result<(), ClientError> {
        self.send(Message::Resume(v1::Resume {})).await
    }

    /// Ends the run: the robot decelerates to rest and the stream closes.
    pub async fn stop(&self) -> Result<(), ClientError> {
        self.send(Message::Stop(v1::Stop {})).await
    }

    /// Reports the robot's measured state.
    pub async fn state(&self, state: v1::RobotState) -> Result<(), ClientError> {
        self.send(Message::State(state)).await
    }
}

/// An open session: a [`SessionSender`] and the stream of segments. Dropping both ends the call.
pub struct Session {
    sender: SessionSender,
    segments: SegmentStream,
}

impl fmt::Debug for Session {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Session").field("sender", &self.sender).finish_non_exhaustive()
    }
}

impl Session {
    /// A sender of commands (clone it to command from another task).
    pub fn sender(&self) -> SessionSender {
        self.sender.clone()
    }

    /// The next segment; `None` once the server closed the stream.
    pub async fn next_segment(&mut self) -> Option<Result<v1::Segment, ClientError>> {
        self.segments.next().await
    }

    /// The two halves.
    pub fn into_parts(self) -> (SessionSender, SegmentStream) {
        (self.sender, self.segments)
    }

    /// Changes the goal.
    pub async fn set_goal(&self, goal: Vec<f64>) -> Result<(), ClientError> {
        self.sender.set_goal(goal).await
    }

    /// Changes tau.
    pub async fn set_tau(&self, tau: f64) -> Result<(), ClientError> {
        self.sender.set_tau(tau).await
    }

    /// Holds position.
    pub async fn pause(&self) -> Result<(), ClientError> {
        self.sender.pause().await
    }

    /// Resumes.
    pub async fn resume(&self) -> Result<(), ClientError> {
        self.sender.resume().await
    }

    /// Stops.
    pub async fn stop(&self) -> Result<(), ClientError> {
        self.sender.stop().await
    }

    /// Reports the measured state.
    pub async fn state(&self, state: v1::RobotState) -> Result<(), ClientError> {
        self.sender.state(state).await
    }
}

impl Stream for Session {
    type Item = Result<v1::Segment, ClientError>;

    fn poll_next(
        mut self: Pin<&mut Self>,
        cx: &mut std::task::Context<'_>,
    ) -> std::task::Poll<Option<Self::Item>> {
        self.segments.as_mut().poll_next(cx)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use std::future::Future;

    use dmp_server::config::Config;
    use dmp_server::run::ServerHandle;

    use super::*;

    /// Bound on every await of the tests (a hung call fails the test instead of hanging it).
    const T: Duration = Duration::from_secs(30);

    /// Points per segment of the server's streams by default: segments of 10 ms at dt = 1 ms.
    const SEGMENT_POINTS: usize = 10;

    /// `f` under the tests' timeout.
    pub(crate) async fn within<F: Future>(what: &str, f: F) -> F::Output {
        tokio::time::timeout(T, f).await.unwrap_or_else(|_| panic!("timed out: {what}"))
    }

    /// The real server, in-process on `127.0.0.1:0`, gRPC only (no Zenoh), its store in a temporary directory.
    #[derive(Debug)]
    pub(crate) struct TestServer {
        handle: ServerHandle,
        _dir: tempfile::TempDir,
    }

    impl TestServer {
        /// Starts a server (it serves when this returns).
        pub(crate) async fn start() -> Self {
            let dir = tempfile::tempdir().unwrap();
            let mut config = Config {
                grpc_addr: "127.0.0.1:0".parse().unwrap(),
                data_dir: dir.path().to_path_buf(),
                ..Default::default()
            };
            config.zenoh.disabled = true;
            let handle = within("server start", dmp_server::run::start(config)).await.expect("server starts");
            Self { handle, _dir: dir }
        }

        /// Its address as an `http://` URL.
        pub(crate) fn url(&self) -> String {
            format!("http://{}", self.handle.grpc_addr)
        }

        /// A client connected to it.
        pub(crate) async fn client(&self) -> DmpClient {
            within("connect", DmpClient::connect(self.url())).await.unwrap()
        }

        /// Stops it and waits until it is down.
        pub(crate) async fn stop(self) {
            within("server shutdown", self.handle.shutdown()).await.unwrap();
        }
    }

    fn demo() -> (Vec<f64>, Vec<Vec<f64>>) {
        let t: Vec<f64> = (0..=200).map(|k| k as f64 / 200.0).collect();
        let x = t.iter().map(|t| vec![t * t, (3.0 * t).sin()]).collect();
        (t, x)
    }

    #[tokio::test(flavor = "multi_thread")]
    async fn primitives_learn_get_list_put_delete() {
        let server = TestServer::start().await;
        // A bare HOST:PORT means http://.
        let c = within("connect", DmpClient::connect(server.handle.grpc_addr.to_string())).await.unwrap();
        let (t, x) = demo();
        let params = v1::LearnParameters { n_basis: 20, ..Default::default() };
        let r = within("learn", c.learn("r1", "wave", &t, &x, params)).await.unwrap();
        assert_eq!((r.version, r.robot_id.as_str(), r.name.as_str()), (1, "r1", "wave"));
        let p = record_primitive(&r).unwrap();
        assert_eq!((p.dim, p.n_basis), (2, 20));
        let again = within("put", c.put_primitive("r1", "wave", &p)).await.unwrap();
        assert_eq!(again.version, 2);
        assert_eq!(record_primitive(&within("get", c.get("r1", "wave", 1)).await.unwrap()).unwrap(), p);
        let other = within("put other", c.put_primitive("r2", "other", &p)).await.unwrap();
        assert_eq!((other.robot_id.as_str(), other.version), ("r2", 1));
        let listed = within("list", c.list("r1")).await.unwrap();
        assert_eq!(listed.iter().map(|r| (r.name.as_str(), r.version)).collect::<Vec<_>>(), [("wave", 2)]);
        assert_eq!(within("delete", c.delete("r1", "wave")).await.unwrap(), 2);
        assert!(within("list after delete", c.list("r1")).await.unwrap().is_empty());

        let e = within("get deleted", c.get("r1", "wave", 0)).await.unwrap_err();
        assert_eq!(e.code(), Some(tonic::Code::NotFound));
        assert!(e.is_bad_input() && e.to_string().contains("wave"), "{e}");
        let e = within("learn one sample", c.learn("r1", "one", &t[..1], &x[..1], Default::default()))
            .await
            .unwrap_err();
        assert_eq!(e.code(), Some(tonic::Code::InvalidArgument), "{e}");
        assert!(e.is_bad_input());
        let mut ragged = x.clone();
        ragged[3].push(1.0);
        let e =
            within("learn ragged", c.learn("r1", "bad", &t, &ragged, Default::default())).await.unwrap_err();
        assert!(e.to_string().contains("demonstration.x[3]"), "{e}");
        server.stop().await;
    }

    #[tokio::test(flavor = "multi_thread")]
    async fn execute_streams_reassemble_into_the_plan() {
        let server = TestServer::start().await;
        let c = server.client().await;
        let (t, x) = demo();
        within("learn", c.learn("r", "p", &t, &x, Default::default())).await.unwrap();
        let motion = v1::MotionSpec { robot_id: "r".into(), primitive: "p".into(), ..Default::default() };
        let plan = within(
            "plan",
            c.plan(v1::PlanRequest { motion: Some(motion.clone()), dt: 0.002, duration: 0.5 }),
        )
        .await
        .unwrap();
        let planned = crate::setpoints::segments_to_trajectory(plan.trajectory.as_ref()).unwrap();
        assert_eq!(planned.len(), 251);
        let request =
            v1::ExecuteRequest { motion: Some(motion), dt: 0.002, max_duration_s: 0.5, ..Default::default() };
        let stream = within("execute", c.execute(request)).await.unwrap();
        let mut seen = 0;
        let s = within("read the stream", collect_setpoints(stream, |_| seen += 1)).await.unwrap();
        // The default 10 ms segment is 5 points at dt = 2 ms: 50 segments, then the point at exactly 0.5 s.
        assert_eq!(seen, 51);
        // The goal is not reached by 0.5 s: the run ends at its maximum duration.
        assert_eq!(s.last_status(), Some(v1::SegmentStatus::Stopped));
        let streamed = s.into_trajectory();
        assert_eq!((streamed.x.clone(), streamed.xd.clone()), (planned.x.clone(), planned.xd.clone()));
        assert!(streamed.t.iter().zip(&planned.t).all(|(a, b)| (a - b).abs() < 1e-12));
        server.stop().await;
    }

    /// The row of `traj` at time `t` (a multiple of `dt`).
    fn row(traj: &dmp::Trajectory, t: f64, dt: f64) -> usize {
        let k = (t / dt).round() as usize;
        assert!((traj.t[k] - t).abs() < 1e-9 * dt.max(1.0), "row {k} is at {}, not {t}", traj.t[k]);
        k
    }

    #[tokio::test(flavor = "multi_thread")]
    async fn a_session_sends_commands_and_receives_superseding_segments() {
        let server = TestServer::start().await;
        let c = server.client().await;
        let (t, x) = demo();
        within("learn", c.learn("r", "p", &t, &x, Default::default())).await.unwrap();
        // Real time, computed a second ahead of the wall clock: the first second is sent at once and a command
        // supersedes most of it. tau = 4 (four times slower than the demonstration): the new goal is seconds away,
        // so the run cannot reach it before it is stopped.
        let motion = v1::MotionSpec {
            robot_id: "r".into(),
            primitive: "p".into(),
            tau: 4.0,
            ignore_scene: true,
            ..Default::default()
        };
        // Where the run goes without commands.
        let plan = v1::PlanRequest { motion: Some(motion.clone()), dt: 0.001, duration: 2.0 };
        let plan = within("plan", c.plan(plan)).await.unwrap();
        let planned = crate::setpoints::segments_to_trajectory(plan.trajectory.as_ref()).unwrap();
        let start = v1::ExecuteRequest {
            motion: Some(motion),
            pacing: v1::Pacing::Realtime as i32,
            lookahead_s: 1.0,
            ..Default::default()
        };
        let mut session = within("session", c.session(start)).await.unwrap();
        let mut s = Setpoints::new();
        let first = within("segment 0", session.next_segment()).await.unwrap().unwrap();
        assert_eq!((first.sequence, first.start_time, first.dt), (0, 0.0, 0.001));
        s.push(&first).unwrap();
        assert_eq!(s.trajectory().unwrap().len(), SEGMENT_POINTS);
        let sender = session.sender();
        let goal = [9.0, 8.0];
        within("set goal", sender.set_goal(goal.to_vec())).await.unwrap();

        // Segments sent before the goal arrived come first; the first one computed after it starts at the robot's
        // current time, before the end of what was sent: it supersedes the rest.
        let mut sequence = 0;
        let (seg, before) = loop {
            let seg = within("segment", session.next_segment()).await.expect("the run goes on").unwrap();
            sequence += 1;
            assert_eq!(seg.sequence, sequence);
            assert_eq!(seg.status(), v1::SegmentStatus::Running);
            let before = s.trajectory().unwrap().clone();
            s.push(&seg).unwrap();
            if seg.start_time < before.t[before.len() - 1] + 0.5 * seg.dt {
                break (seg, before);
            }
        };
        assert!(seg.start_time > 0.0, "applied from the current state, not from the start");
        // Until then, the setpoints sent were the plan's.
        assert_eq!(before.x, planned.x[..before.x.len()]);
        let k = row(&before, seg.start_time, seg.dt);
        let traj = s.trajectory().unwrap();
        assert_eq!(traj.len(), k + SEGMENT_POINTS, "rows from {} s on are superseded", seg.start_time);
        // Continuous: it starts from the state already sent for that time; only the acceleration changes.
        assert_eq!((traj.position(k), traj.velocity(k)), (before.position(k), before.velocity(k)));
        assert!(traj.acceleration(k) != before.acceleration(k));
        // Half a second later, the run is well on its way to the new goal, far from the plan.
        let later = seg.start_time + 0.5;
        while s.trajectory().unwrap().t.last().unwrap() + 0.5 * seg.dt < later {
            let seg = within("segment", session.next_segment()).await.expect("the run goes on").unwrap();
            assert_eq!(seg.status(), v1::SegmentStatus::Running);
            s.push(&seg).unwrap();
        }
        let traj = s.trajectory().unwrap();
        let was = planned.position(row(&planned, later, seg.dt));
        let now = traj.position(row(traj, later, seg.dt));
        for i in 0..2 {
            assert!(now[i] > was[i] + 0.5, "not heading for the new goal: {now:?} (was {was:?})");
        }

        // Stop: superseding again, the robot decelerates to rest and the stream ends with STOPPED.
        within("stop", session.stop()).await.unwrap();
        let (_, mut rest) = session.into_parts();
        let mut superseded = false;
        let mut last = None;
        while let Some(seg) = within("segment", rest.next()).await {
            let seg = seg.unwrap();
            superseded |= seg.start_time + 0.5 * seg.dt < *s.trajectory().unwrap().t.last().unwrap();
            s.push(&seg).unwrap();
            last = Some(seg);
        }
        assert!(superseded, "the stop did not supersede what was sent ahead");
        assert_eq!(last.expect("segments after the stop").status(), v1::SegmentStatus::Stopped);
        let traj = s.trajectory().unwrap();
        let v = traj.velocity(traj.len() - 1);
        assert!(v.iter().map(|v| v * v).sum::<f64>().sqrt() < 2e-3, "not at rest: {v:?}");
        // The session is over: once the server has dropped the call, commands fail.
        drop(rest);
        let e = within("a command after the end", async {
            loop {
                if let Err(e) = sender.pause().await {
                    break e;
                }
            }
        })
        .await;
        assert!(matches!(e, ClientError::Closed(_)), "{e}");
        drop(sender);
        server.stop().await;
    }

    #[tokio::test(flavor = "multi_thread")]
    async fn connection_failures_and_bad_addresses() {
        let e = within("connect", DmpClient::connect("http://127.0.0.1:1")).await.unwrap_err();
        assert!(matches!(e, ClientError::Connect { .. }) && !e.is_bad_input(), "{e}");
        assert!(e.to_string().contains("http://127.0.0.1:1"), "{e}");
        let e = within("connect", DmpClient::connect("http://not a host")).await.unwrap_err();
        assert!(e.is_bad_input(), "{e}");
    }
}
