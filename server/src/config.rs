//! The server's configuration: a TOML file, then flags on top (see `bin/dmp-server.rs`).

pub mod command_line;
pub mod default_limits;
pub(crate) mod ros2;
pub mod scene;

use std::net::SocketAddr;
use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use crate::config::default_limits::{DefaultLimits, check_margin};
use crate::config::scene::SceneConfig;

/// Everything the server needs to start.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Config {
    /// Address of the gRPC server.
    pub grpc_addr: SocketAddr,
    /// Directory of the embedded store.
    pub data_dir: PathBuf,
    /// The robot cell this server serves: Zenoh keys are `dmp/<cell>/...`; with `cells`, the default one of them
    /// (the first of `cells` when it is not among them).
    pub cell: String,
    /// The cells this server serves (`--cells a,b`); a request for another cell is refused, naming the server of
    /// the plant that serves it when one is known. Empty: any cell, created on first use.
    pub cells: Vec<String>,
    /// Several servers on one Zenoh network ([`crate::plant`]).
    pub plant: PlantConfig,
    /// Address of the Prometheus endpoint (`GET /metrics`, plain HTTP, no authentication); none: off.
    pub metrics_addr: Option<SocketAddr>,
    /// The OTLP/gRPC collector the tracing spans go to, e.g. `http://collector:4317`; none: off.
    pub otlp_endpoint: Option<String>,
    /// The Zenoh session.
    pub zenoh: ZenohConfig,
    /// Defaults applied when a request names no avoidance method.
    pub defaults: Defaults,
    /// Bounds on requests and resources.
    pub limits: RequestLimits,
    /// The compute threads and what they may be asked to do.
    pub compute: ComputeConfig,
    /// Obstacles that nobody updates any more ([`crate::cells::staleness`]).
    pub scene: SceneConfig,
    /// TLS, the access file, and what may listen beyond loopback ([`crate::access::exposure`]).
    pub security: SecurityConfig,
    /// ROS 2 over rmw_zenoh ([`crate::ros2`]); off unless its domain is set.
    pub ros2: crate::config::ros2::Ros2Config,
}

/// Several servers on one Zenoh network: discovery, replicated primitives, neighbouring cells.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PlantConfig {
    /// This server's id in the plant (`--server-id`): with it (and Zenoh), the server declares its liveliness
    /// token and its cells' queryables, and replicates primitives with the others. None: a lone server.
    pub server_id: Option<String>,
    /// The gRPC address the plant is told to reach this server at, e.g. `https://cell-a.plant:50051`
    /// (`--advertise-addr`) [default: the bound address, `http://` or `https://`].
    pub advertise_addr: Option<String>,
    /// For each cell this server serves, the cells whose robots its robots also avoid (robot states cross
    /// servers on their Zenoh keys). List both directions for robots of two cells to avoid each other.
    pub neighbours: std::collections::BTreeMap<String, Vec<String>>,
}

impl Config {
    /// The default cell: `cell`, unless `cells` is given without it, then the first of `cells`.
    pub(crate) fn default_cell(&self) -> &str {
        match self.cells.first() {
            Some(first) if !self.cells.contains(&self.cell) => first,
            _ => &self.cell,
        }
    }

    /// Checks the plant's names: the cells, the server id, the neighbours (naming the field at fault).
    pub(crate) fn check_plant(&self) -> Result<(), dmp_proto::WireError> {
        use dmp_proto::keys::check_name;
        for (i, c) in self.cells.iter().enumerate() {
            check_name(&format!("cells[{i}]"), c)?;
        }
        if let Some(id) = &self.plant.server_id {
            check_name("plant.server_id", id)?;
        }
        for (cell, others) in &self.plant.neighbours {
            check_name("plant.neighbours", cell)?;
            for (i, o) in others.iter().enumerate() {
                check_name(&format!("plant.neighbours.{cell}[{i}]"), o)?;
            }
        }
        Ok(())
    }
}

/// TLS and access control. Without an access file and TLS the server listens on loopback only, unless `insecure`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SecurityConfig {
    /// The access file: identities, roles, cells and robots (`--access`).
    pub access: Option<PathBuf>,
    /// The server's TLS certificate chain, PEM (`--tls-cert`).
    pub tls_cert: Option<PathBuf>,
    /// The server's TLS private key, PEM (`--tls-key`).
    pub tls_key: Option<PathBuf>,
    /// The CA that signs client certificates, PEM (`--tls-client-ca`): mutual TLS, the certificate's common name
    /// naming an identity. Clients without a certificate may still present a token.
    pub tls_client_ca: Option<PathBuf>,
    /// Listen beyond loopback without TLS or an access file (`--insecure`): repeated in the log and in GetInfo.
    pub insecure: bool,
}

impl Default for Config {
    fn default() -> Self {
        Self {
            grpc_addr: "127.0.0.1:50051".parse().expect("a valid literal address"),
            data_dir: PathBuf::from("data"),
            cell: "default".into(),
            cells: Vec::new(),
            plant: PlantConfig::default(),
            metrics_addr: None,
            otlp_endpoint: None,
            zenoh: ZenohConfig::default(),
            defaults: Defaults::default(),
            limits: RequestLimits::default(),
            compute: ComputeConfig::default(),
            scene: SceneConfig::default(),
            security: SecurityConfig::default(),
            ros2: Default::default(),
        }
    }
}

/// Where the embedded peer listens by default: Zenoh's well-known port, on loopback (secure by default: other hosts
/// reach it once it listens on another address, which takes TLS and an access file, or `--insecure`).
pub(crate) const DEFAULT_ZENOH_LISTEN: &str = "tcp/127.0.0.1:7447";

/// The embedded Zenoh peer (or client of a router network).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ZenohConfig {
    /// Run without Zenoh at all (gRPC only).
    pub disabled: bool,
    /// `peer` or `client`.
    pub mode: String,
    /// Endpoints to listen on; default [`DEFAULT_ZENOH_LISTEN`]. Empty: Zenoh's own default (a random port).
    pub listen: Vec<String>,
    /// Endpoints to connect to (routers or peers).
    pub connect: Vec<String>,
    /// Multicast scouting (finding peers on the LAN, and being found). Off by default; on, it takes TLS listeners
    /// with an access file, or `--insecure`.
    pub multicast_scouting: bool,
    /// A stock Zenoh configuration file (JSON5, `--zenoh-config`) to start from: the settings above are applied on
    /// top of it, and its `access_control`, if enabled, replaces the one generated from the access file.
    pub config_file: Option<PathBuf>,
}

impl ZenohConfig {
    /// What `dmp_proto::zenoh_session::session_config` builds the session from: an empty `listen` is Zenoh's
    /// default for the mode.
    pub(crate) fn session_options(&self) -> dmp_proto::zenoh_session::SessionOptions {
        dmp_proto::zenoh_session::SessionOptions {
            mode: self.mode.clone(),
            listen: (!self.listen.is_empty()).then(|| self.listen.clone()),
            connect: self.connect.clone(),
            multicast_scouting: self.multicast_scouting,
            config_file: self.config_file.clone(),
            tls: None,
            access_control: None,
        }
    }

    /// Whether an endpoint of the session is a `tls/` one.
    pub(crate) fn uses_tls(&self) -> bool {
        self.listen.iter().chain(&self.connect).any(|e| e.starts_with("tls/"))
    }
}

impl Default for ZenohConfig {
    fn default() -> Self {
        Self {
            disabled: false,
            mode: "peer".into(),
            listen: vec![DEFAULT_ZENOH_LISTEN.into()],
            connect: Vec::new(),
            multicast_scouting: false,
            config_file: None,
        }
    }
}

/// What a motion request gets where it sets nothing: its avoidance, its limits and its safety distance.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Defaults {
    /// For the scene's obstacles: the paper's dynamic volumetric potential with its synthetic-test gains.
    pub avoidance: dmp::Avoidance,
    /// For other robots: the dynamic volumetric potential with the youBot test's gains.
    pub robot_avoidance: dmp::Avoidance,
    /// Internal RK4 step of streamed runs, seconds (requests may ask for another); output points in between are
    /// interpolated exactly. Rounded to a multiple of the output `dt` and at most one segment. The default, 1 ms,
    /// is the engine's own step: coarser steps are much cheaper but lose accuracy where a repulsive term is stiff
    /// (a robot pressed against an obstacle or another robot), so they are opt-in.
    pub integration_step_s: f64,
    /// Shortest time between two states of one robot published on Zenoh, seconds (the local cell sees every
    /// segment's state).
    pub robot_state_period_s: f64,
    /// The safety distance a run keeps from every obstacle's true shape, metres, where neither its request
    /// (`MotionSpec.margin`) nor its robot's record sets one; negative: none.
    pub margin_m: f64,
    /// The default profile: the limits a run keeps on the fields that neither its request nor its robot's record
    /// sets.
    pub limits: DefaultLimits,
}

impl Defaults {
    /// The default profile and safety distance are valid; the error names the key.
    pub(crate) fn check(&self) -> Result<(), crate::error::ServerError> {
        self.limits.check()?;
        check_margin(self.margin_m)
    }
}

impl Default for Defaults {
    fn default() -> Self {
        use dmp::avoidance::DynamicVolumetric;
        Self {
            avoidance: dmp::Avoidance::new(dmp::Method::DynamicVolumetric(DynamicVolumetric {
                lambda: 10.0,
                beta: 2.0,
                eta: 0.5,
            })),
            robot_avoidance: dmp::Avoidance::new(dmp::Method::DynamicVolumetric(DynamicVolumetric {
                lambda: 60.0,
                beta: 2.0,
                eta: 0.2,
            })),
            integration_step_s: 0.001,
            robot_state_period_s: 0.02,
            margin_m: 0.01,
            limits: DefaultLimits::default(),
        }
    }
}

/// Bounds: every request is checked against them.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RequestLimits {
    /// Largest gRPC message, bytes.
    pub max_message_bytes: usize,
    /// Most samples in a demonstration.
    pub max_samples: usize,
    /// Largest dimension of a primitive.
    pub max_dim: usize,
    /// Largest N.
    pub max_basis: usize,
    /// Most obstacles in a cell's scene.
    pub max_obstacles: usize,
    /// Most cells.
    pub max_cells: usize,
    /// Most concurrent executions (Execute, Session, ExecuteGroup); watches have `max_watches`.
    pub max_streams: usize,
    /// Longest plan or run, in steps.
    pub max_steps: usize,
    /// Segments buffered per stream before the producer waits for the reader (backpressure).
    pub stream_buffer: usize,
    /// Half-width of the workspace box, metres: every coordinate of a start, goal, obstacle centre or robot state
    /// must be within `[-workspace_m, workspace_m]`.
    pub workspace_m: f64,
    /// Largest segment a stream may send, bytes (its positions, velocities and accelerations: points x dimension
    /// x 24).
    pub max_segment_bytes: usize,
    /// Most memory one stream may hold, bytes: its buffered segments, its history for rollbacks and its run.
    pub max_stream_bytes: usize,
    /// Most memory one cell's obstacles may hold, bytes.
    pub max_scene_bytes: usize,
    /// Most memory all streams and scenes together may hold, bytes.
    pub max_server_bytes: usize,
    /// Versions kept per primitive (robot id and name): a Learn or Put beyond removes the oldest.
    pub max_versions: usize,
    /// Records per List page when the request asks for none.
    pub list_page_size: usize,
    /// Most records per List page.
    pub max_list_page_size: usize,
    /// Most concurrent WatchScene streams, a pool apart from the executions' `max_streams`.
    pub max_watches: usize,
    /// Most concurrent streams (executions and watches) on one connection.
    pub max_streams_per_connection: usize,
    /// Most concurrent streams (executions and watches) of one client (its IP address, over all its
    /// connections).
    pub max_streams_per_client: usize,
    /// Interval of the HTTP/2 pings the server sends on every connection, seconds (0: none).
    pub http2_keepalive_interval_s: f64,
    /// How long a ping may go unanswered before the connection is closed, seconds.
    pub http2_keepalive_timeout_s: f64,
    /// Idle time before TCP keepalive probes start on a connection, seconds (0: none).
    pub tcp_keepalive_s: f64,
    /// A connection without an open stream and without a request for this long is closed, seconds (0: never).
    pub idle_timeout_s: f64,
    /// Largest difference, seconds, between a robot state's stamp and the server's clock, either way: a state
    /// further off (Zenoh or Session `state`) is dropped and counted (`ServerStats.robot_states_dropped`).
    pub max_state_skew_s: f64,
    /// Largest speed of a robot state, metres per second, on every coordinate of its velocity: a state moving
    /// faster is dropped and counted (cell-mates are extrapolated along their velocity, so a huge one would throw
    /// a robot's image across the cell).
    pub max_state_speed_m_s: f64,
}

impl Default for RequestLimits {
    fn default() -> Self {
        Self {
            max_message_bytes: 16 * 1024 * 1024,
            max_samples: 200_000,
            max_dim: 64,
            max_basis: 1000,
            max_obstacles: 1000,
            max_cells: 1000,
            max_streams: 2000,
            max_steps: dmp::rollout::MAX_ROLLOUT_STEPS,
            stream_buffer: 4,
            workspace_m: 1000.0,
            max_segment_bytes: 4 * 1024 * 1024,
            max_stream_bytes: 32 * 1024 * 1024,
            max_scene_bytes: 64 * 1024 * 1024,
            max_server_bytes: 2 * 1024 * 1024 * 1024,
            max_versions: 16,
            list_page_size: 100,
            max_list_page_size: 1000,
            max_watches: 500,
            max_streams_per_connection: 2000,
            max_streams_per_client: 2500,
            http2_keepalive_interval_s: 30.0,
            http2_keepalive_timeout_s: 20.0,
            tcp_keepalive_s: 60.0,
            idle_timeout_s: 600.0,
            max_state_skew_s: 1.0,
            max_state_speed_m_s: 10.0,
        }
    }
}

/// The compute threads (stepping, plans and learns never run on the async workers) and the budgets that requests
/// are admitted against. Work is counted in work units (`compute::cost`): about the time of one Gaussian of the
/// forcing term in one dimension.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ComputeConfig {
    /// Threads stepping the real-time streams; 0 means one per core.
    pub realtime_threads: usize,
    /// Threads for plans, learns and as-fast-as-read streams; 0 means one per core.
    pub batch_threads: usize,
    /// Added to the batch threads' niceness (Linux): they take only the time the real-time threads leave.
    pub batch_nice: i32,
    /// Work units per second that real-time streams may take together, per real-time thread.
    pub realtime_work_per_thread_s: f64,
    /// Most work units of one computation: one wake-up of a stream (a segment and its refill), so that no stream
    /// holds a compute thread for long.
    pub max_job_work: f64,
    /// Most work units of one request: a plan, a learn, or an as-fast-as-read stream in all.
    pub max_request_work: f64,
    /// Most work units of plans and learns queued or running at once.
    pub batch_queue_work: f64,
}

impl Default for ComputeConfig {
    fn default() -> Self {
        Self {
            realtime_threads: 0,
            batch_threads: 0,
            batch_nice: 10,
            realtime_work_per_thread_s: 6e8,
            max_job_work: 2e7,
            max_request_work: 1e10,
            batch_queue_work: 3e10,
        }
    }
}
