//! A typed async client of the gRPC services (`proto/dmp/v1`): primitives, robot records (`grpc/robots.rs`), scene
//! and motion.
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

use std::time::Duration;

use dmp_proto::learning::pose_demonstration_to_proto;
use dmp_proto::primitive::{primitive_from_proto, primitive_to_proto};
use dmp_proto::v1;
use dmp_proto::v1::motion_service_client::MotionServiceClient;
use dmp_proto::v1::primitive_service_client::PrimitiveServiceClient;
use dmp_proto::v1::robot_service_client::RobotServiceClient;
use dmp_proto::v1::scene_service_client::SceneServiceClient;
use dmp_proto::v1::server_service_client::ServerServiceClient;
use dmp_proto::v1::session_request::Message;
use tokio::sync::mpsc;
use tokio_stream::wrappers::ReceiverStream;
use tokio_stream::{Stream, StreamExt};
use tonic::service::interceptor::InterceptedService;
use tonic::transport::Channel;

pub use crate::connect::CONNECT_TIMEOUT;
use crate::connect::{ConnectOptions, Credentials, Transport};
use crate::error::{ClientError, chain};
pub use crate::session::{Session, SessionSender};
use crate::setpoints::Setpoints;
use crate::streams::boxed;
pub use crate::streams::{DecodedStream, GroupStream, SceneStream, SegmentStream};

/// The server `dmpctl` talks to unless told otherwise.
pub const DEFAULT_SERVER: &str = "http://127.0.0.1:50051";

/// Largest message sent or received (a 1,000,000-step 3-D plan is ~75 MB).
const MAX_MESSAGE_BYTES: usize = 256 * 1024 * 1024;

/// Messages a session may queue before [`SessionSender`] waits for the server to read.
const SESSION_QUEUE: usize = 64;

/// A client of the DMP cell's server.
#[derive(Debug, Clone)]
pub struct DmpClient {
    url: String,
    /// The channel without credentials (clients of other identities share it).
    raw: Channel,
    channel: Transport,
    primitives: PrimitiveServiceClient<Transport>,
    robots: RobotServiceClient<Transport>,
    scene: SceneServiceClient<Transport>,
    motion: MotionServiceClient<Transport>,
    server: ServerServiceClient<Transport>,
    /// The cell of the scene requests; empty means the server's default cell.
    cell: String,
}

fn missing(what: &str) -> ClientError {
    ClientError::Protocol(format!("the answer has no `{what}`"))
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
        Self::connect_with(&url.into(), &ConnectOptions { timeout, ..Default::default() }).await
    }

    /// Connects to `url` with TLS and a token as `options` say (see [`crate::connect`]).
    pub async fn connect_with(url: &str, options: &ConnectOptions) -> Result<Self, ClientError> {
        let credentials = Credentials::token(options.token.as_deref())?;
        let (channel, url) = crate::connect::open(url, options).await?;
        Ok(Self::from_channel_with(channel, url, credentials))
    }

    /// A client over an existing channel (`url` only names it in messages) that sends `credentials` with every call.
    fn from_channel_with(channel: Channel, url: impl Into<String>, credentials: Credentials) -> Self {
        let n = MAX_MESSAGE_BYTES;
        let transport = InterceptedService::new(channel.clone(), credentials);
        Self {
            raw: channel,
            url: url.into(),
            channel: transport.clone(),
            primitives: PrimitiveServiceClient::new(transport.clone())
                .max_decoding_message_size(n)
                .max_encoding_message_size(n),
            robots: RobotServiceClient::new(transport.clone())
                .max_decoding_message_size(n)
                .max_encoding_message_size(n),
            scene: SceneServiceClient::new(transport.clone())
                .max_decoding_message_size(n)
                .max_encoding_message_size(n),
            motion: MotionServiceClient::new(transport.clone())
                .max_decoding_message_size(n)
                .max_encoding_message_size(n),
            server: ServerServiceClient::new(transport),
            cell: String::new(),
        }
    }

    /// A client on the same connection that sends `token` instead (none: no credentials): each robot of a
    /// fleet can call as its own identity without a connection of its own.
    pub fn with_token(&self, token: Option<&str>) -> Result<Self, ClientError> {
        let credentials = Credentials::token(token)?;
        Ok(Self::from_channel_with(self.raw.clone(), self.url.clone(), credentials)
            .with_cell(self.cell.clone()))
    }

    /// The same client, with its scene requests (put, delete, list, watch) and its motions in `cell` (empty: the
    /// server's default cell). A motion whose `MotionSpec::cell` is set keeps its own; an empty one gets this cell.
    pub fn with_cell(mut self, cell: impl Into<String>) -> Self {
        self.cell = cell.into();
        self
    }

    /// The cell of the scene requests and motions (empty: the server's default).
    pub fn cell(&self) -> &str {
        &self.cell
    }

    /// Puts a motion that names no cell in this client's.
    fn in_cell(&self, motion: Option<&mut v1::MotionSpec>) {
        if let Some(m) = motion
            && m.cell.is_empty()
        {
            m.cell.clone_from(&self.cell);
        }
    }

    /// The server's resource use and traffic.
    pub async fn stats(&self) -> Result<v1::ServerStats, ClientError> {
        Ok(self.server.clone().get_stats(v1::GetStatsRequest {}).await?.into_inner())
    }

    /// The standard gRPC health check of `service` (`""`: the server as a whole; or e.g. `dmp.v1.SceneService`,
    /// which is not serving while the scene's Zenoh routers are unreachable). Answered without credentials, as
    /// probes need. Returns the status's name, e.g. `SERVING` or `NOT_SERVING`.
    pub async fn health(&self, service: &str) -> Result<&'static str, ClientError> {
        use tonic_health::pb::health_check_response::ServingStatus;
        use tonic_health::pb::{HealthCheckRequest, health_client::HealthClient};
        let request = HealthCheckRequest { service: service.to_owned() };
        let status = HealthClient::new(self.raw.clone()).check(request).await?.into_inner().status;
        Ok(ServingStatus::try_from(status).map_or("UNKNOWN", |s| s.as_str_name()))
    }

    /// How the server is set up (TLS, access control, what is exposed) and who this client is to it.
    pub async fn info(&self) -> Result<v1::ServerInfo, ClientError> {
        Ok(self.server.clone().get_info(v1::GetInfoRequest {}).await?.into_inner())
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
        // Boxed: the request's future would otherwise sit twice on the caller's stack.
        Box::pin(self.learn_pose(robot, name, t, rows, &[], parameters)).await
    }

    /// Learns a pose primitive from positions and one orientation `[x, y, z, w]` per sample (none: a position
    /// primitive) as the next version of `(robot, name)`.
    pub async fn learn_pose(
        &self,
        robot: &str,
        name: &str,
        t: &[f64],
        rows: &[Vec<f64>],
        orientations: &[[f64; 4]],
        parameters: v1::LearnParameters,
    ) -> Result<v1::PrimitiveRecord, ClientError> {
        let demonstration = pose_demonstration_to_proto(t, rows, orientations)?;
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

    /// The latest version of each of a robot's primitives, sorted by name: every page, in turn.
    pub async fn list(&self, robot: &str) -> Result<Vec<v1::PrimitiveRecord>, ClientError> {
        let mut records = Vec::new();
        let mut token = String::new();
        loop {
            let page = self.list_page(robot, 0, &token).await?;
            records.extend(page.records);
            // A token that does not move on would loop forever: the server's pages are sorted by name.
            if page.next_page_token.is_empty() || page.next_page_token <= token {
                return Ok(records);
            }
            token = page.next_page_token;
        }
    }

    /// One page of a robot's primitives: at most `page_size` (0: the server's default) after `page_token` (empty:
    /// the first page). The page's `next_page_token` is empty on the last page.
    pub async fn list_page(
        &self,
        robot: &str,
        page_size: u32,
        page_token: &str,
    ) -> Result<v1::ListPrimitivesResponse, ClientError> {
        let request =
            v1::ListPrimitivesRequest { robot_id: robot.into(), page_size, page_token: page_token.into() };
        Ok(self.primitives.clone().list(request).await?.into_inner())
    }

    /// The robots that have primitives (those whose primitives this client may read), sorted by id: every page, in
    /// turn.
    pub async fn list_robots(&self) -> Result<Vec<v1::RobotSummary>, ClientError> {
        let mut robots = Vec::new();
        let mut token = String::new();
        loop {
            let request = v1::ListRobotsRequest { page_size: 0, page_token: token.clone() };
            let page = self.primitives.clone().list_robots(request).await?.into_inner();
            robots.extend(page.robots);
            // A token that does not move on would loop forever: the server's pages are sorted by id.
            if page.next_page_token.is_empty() || page.next_page_token <= token {
                return Ok(robots);
            }
            token = page.next_page_token;
        }
    }

    /// Deletes every version of `(robot, name)`; returns how many there were.
    pub async fn delete(&self, robot: &str, name: &str) -> Result<u64, ClientError> {
        let request = v1::DeletePrimitiveRequest { robot_id: robot.into(), name: name.into() };
        Ok(self.primitives.clone().delete(request).await?.into_inner().versions_deleted)
    }

    /// Deletes every version of every primitive of `robot` (what the tools do with their own robots when they
    /// end); returns how many versions there were.
    pub async fn delete_robot_primitives(&self, robot: &str) -> Result<u64, ClientError> {
        let mut deleted = 0;
        for record in self.list(robot).await? {
            deleted += self.delete(robot, &record.name).await?;
        }
        Ok(deleted)
    }

    // --- Motion -----------------------------------------------------------------------------------------------

    /// The whole trajectory at once.
    pub async fn plan(&self, mut request: v1::PlanRequest) -> Result<v1::PlanResponse, ClientError> {
        self.in_cell(request.motion.as_mut());
        Ok(self.motion.clone().plan(request).await?.into_inner())
    }

    /// Streams a primitive's execution in segments (see [`Setpoints`] for which points are current).
    pub async fn execute(&self, mut request: v1::ExecuteRequest) -> Result<SegmentStream, ClientError> {
        self.in_cell(request.motion.as_mut());
        Ok(boxed(self.motion.clone().execute(request).await?.into_inner()))
    }

    /// Opens a session started by `start`: commands go through the returned [`Session`]'s sender, segments come
    /// from its stream.
    pub async fn session(&self, start: v1::ExecuteRequest) -> Result<Session, ClientError> {
        let (sender, segments) = self.session_decoded::<v1::Segment>(start).await?;
        Ok(Session { sender, segments })
    }

    /// A session whose segments are decoded as `T`: any message with `dmp.v1.Segment`'s field numbers, such as a
    /// view that keeps the setpoint arrays as raw bytes (a load generator that only times the segments need not
    /// decode 90 numbers a segment). Otherwise the same call as [`DmpClient::session`].
    pub async fn session_decoded<T>(
        &self,
        mut start: v1::ExecuteRequest,
    ) -> Result<(SessionSender, DecodedStream<T>), ClientError>
    where
        T: prost::Message + Default + Send + 'static,
    {
        self.in_cell(start.motion.as_mut());
        let (tx, rx) = mpsc::channel(SESSION_QUEUE);
        // The start message is queued before the call, so the server has it as soon as the stream opens.
        tx.try_send(v1::SessionRequest { message: Some(Message::Start(start)) })
            .map_err(|_| ClientError::Closed("the session queue".into()))?;
        let mut grpc = tonic::client::Grpc::new(self.channel.clone())
            .max_decoding_message_size(MAX_MESSAGE_BYTES)
            .max_encoding_message_size(MAX_MESSAGE_BYTES);
        grpc.ready().await.map_err(|e| ClientError::Connect { url: self.url.clone(), message: chain(&e) })?;
        let path = tonic::codegen::http::uri::PathAndQuery::from_static("/dmp.v1.MotionService/Session");
        let codec = tonic_prost::ProstCodec::<v1::SessionRequest, T>::default();
        let response = grpc.streaming(tonic::Request::new(ReceiverStream::new(rx)), path, codec).await?;
        Ok((SessionSender { tx }, boxed(response.into_inner())))
    }

    /// Executes several robots on one shared phase.
    pub async fn execute_group(
        &self,
        mut request: v1::ExecuteGroupRequest,
    ) -> Result<GroupStream, ClientError> {
        for member in &mut request.members {
            self.in_cell(member.motion.as_mut());
        }
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

mod robots;

#[cfg(test)]
mod tests;
