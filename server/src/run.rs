//! Assembling and running the server: store, scene, Zenoh, the gRPC services (with health and reflection), and one
//! shutdown path for all of them.

use std::future::Future;
use std::net::SocketAddr;
use std::sync::Arc;

use dmp_proto::v1::motion_service_server::MotionServiceServer;
use dmp_proto::v1::primitive_service_server::PrimitiveServiceServer;
use dmp_proto::v1::robot_service_server::RobotServiceServer;
use dmp_proto::v1::scene_service_server::SceneServiceServer;
use dmp_proto::v1::server_service_server::ServerServiceServer;
use dmp_proto::zenoh_session::locators;
use tokio::net::TcpListener;
use tokio::task::JoinHandle;
use tokio_util::sync::CancellationToken;
use tonic::transport::Server;
use tracing::{info, warn};

use crate::access::AccessControl;
use crate::access::layer::AuthenticateLayer;
use crate::cells::Cells;
use crate::clock::Clock;
use crate::compute::Compute;
use crate::config::Config;
use crate::error::ServerError;
use crate::executing::Executing;
use crate::exposure;
use crate::memory::MemoryBudget;
use crate::metrics::ServerCollector;
use crate::robots::RobotBus;
use crate::services::motion::MotionServiceImpl;
use crate::services::primitives::PrimitiveServiceImpl;
use crate::services::robots::RobotServiceImpl;
use crate::services::scene::SceneServiceImpl;
use crate::services::server::ServerServiceImpl;
use crate::state::AppState;
use crate::state_admission::StateAdmission;
use crate::store::Store;
use crate::stream_permits::StreamPermits;
use crate::tls::server_tls;
use crate::write_batching::BatchedWrites;
use crate::zenoh_bridge::{Security, ZenohBridge, open_secured_session, reachability};

/// How long a shutdown waits for connections to drain before closing them.
const DRAIN_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(5);

/// A running server.
#[derive(Debug)]
pub struct ServerHandle {
    /// The address gRPC listens on (the real port when the configuration said 0).
    pub grpc_addr: SocketAddr,
    /// Zenoh locators the embedded peer listens on (empty without Zenoh).
    pub zenoh_locators: Vec<String>,
    /// The address the Prometheus endpoint listens on (the real port when the configuration said 0); none when
    /// it is off.
    pub metrics_addr: Option<SocketAddr>,
    state: Arc<AppState>,
    bridge_malformed: Option<Arc<std::sync::atomic::AtomicU64>>,
    ros2: Option<Arc<crate::ros2::Ros2Counters>>,
    task: JoinHandle<Result<(), ServerError>>,
}

impl ServerHandle {
    /// The shared state (tests look at the scene and the stream permits).
    pub fn state(&self) -> &Arc<AppState> {
        &self.state
    }

    /// Malformed Zenoh payloads received so far.
    pub fn malformed_payloads(&self) -> u64 {
        self.bridge_malformed.as_ref().map(|c| c.load(std::sync::atomic::Ordering::Relaxed)).unwrap_or(0)
    }

    /// Reads the access file again (what SIGHUP does): streams it no longer allows end with PERMISSION_DENIED; a
    /// file that is refused changes nothing.
    pub fn reload_access(&self) -> Result<usize, crate::access::AccessError> {
        let n = self.state.access.reload()?;
        if !self.zenoh_locators.is_empty() && self.state.access.enabled() {
            warn!(
                "the Zenoh access control changes only at a restart: Zenoh reads it once, when the session opens"
            );
        }
        Ok(n)
    }

    /// What the ROS 2 bridge took and refused; none without `ros2.domain`.
    pub fn ros2_counters(&self) -> Option<&Arc<crate::ros2::Ros2Counters>> {
        self.ros2.as_ref()
    }

    /// Streams currently open (executions and watches).
    pub fn open_streams(&self) -> usize {
        self.state.streams.open_executions() + self.state.streams.open_watches()
    }

    /// Stops: streams end, gRPC drains, Zenoh closes. Returns once everything is down.
    pub async fn shutdown(self) -> Result<(), ServerError> {
        self.state.shutdown.cancel();
        self.task.await.map_err(|e| ServerError::Internal(e.to_string()))?
    }
}

/// Starts the server on the system's clock and returns once it serves (health SERVING).
pub async fn start(config: Config) -> Result<ServerHandle, ServerError> {
    start_with_clock(config, Clock::system()).await
}

/// Starts the server on `clock` (tests run real time on tokio's paused clock) and returns once it serves.
pub async fn start_with_clock(config: Config, clock: Clock) -> Result<ServerHandle, ServerError> {
    // Refused before anything listens: exposure without protection, a bad access file, bad TLS files.
    let exposure = exposure::check(&config)?;
    for reason in &exposure.warnings {
        warn!(reason = %reason, "INSECURE (--insecure): anyone who reaches the server can steer every robot");
    }
    let access = match &config.security.access {
        Some(path) => {
            AccessControl::load(path).map_err(|e| ServerError::FailedPrecondition(e.to_string()))?
        }
        None => AccessControl::open(),
    };
    let access = Arc::new(access);
    let tls = server_tls(&config.security)?;
    let listener = TcpListener::bind(config.grpc_addr).await.map_err(|e| {
        ServerError::FailedPrecondition(format!("cannot listen on {}: {e}", config.grpc_addr))
    })?;
    let grpc_addr = listener.local_addr().map_err(|e| ServerError::Internal(e.to_string()))?;
    let dir = config.data_dir.clone();
    let max_versions = config.limits.max_versions;
    let store = tokio::task::spawn_blocking(move || Store::open(&dir).map(|s| s.keep_versions(max_versions)))
        .await
        .map_err(|e| ServerError::Internal(e.to_string()))??;
    config.scene.check()?;
    let memory = MemoryBudget::new(config.limits.max_server_bytes);
    config.check_plant()?;
    let directory = crate::plant::directory::Directory::default();
    let cells =
        Cells::with_limits(config.default_cell(), &config.limits, memory.clone(), config.scene.clone())?
            .serving(&config.cells)
            .with_neighbours(&config.plant.neighbours)
            .with_directory(directory.clone());
    let shutdown = CancellationToken::new();
    let state_admission = StateAdmission::new(&config.limits);

    let (session, bridge, robots, zenoh_locators) = if config.zenoh.disabled {
        // Without Zenoh the bridge's reaper is not there: obstacles put over gRPC with a ttl still expire.
        crate::zenoh_bridge::spawn_reaper(cells.clone(), clock, shutdown.clone());
        (None, None, RobotBus::new(None), Vec::new())
    } else {
        let access = access.current();
        let security = Security { config: &config.security, access: access.as_deref() };
        let session = open_secured_session(&config.zenoh, &security).await?;
        let bridge = ZenohBridge::start(
            session.clone(),
            cells.clone(),
            clock,
            state_admission.clone(),
            shutdown.clone(),
        )
        .await?;
        let locs = locators(&session).await;
        let robots = RobotBus::new(Some((session.clone(), config.defaults.robot_state_period_s)))
            .mirroring(cells.clone());
        (Some(session), Some(bridge), robots, locs)
    };
    let bridge_malformed = bridge.as_ref().map(|b| b.malformed_counter());
    let ros2_bridge = match (&session, &bridge_malformed, config.ros2.domain) {
        (Some(s), Some(m), Some(_)) => {
            Some(crate::ros2::Ros2Bridge::start(s, &config.ros2, cells.clone(), clock, m.clone()).await?)
        }
        (None, _, Some(_)) => {
            return Err(ServerError::FailedPrecondition("ros2.domain needs Zenoh (not --no-zenoh)".into()));
        }
        _ => None,
    };
    let ros2 = ros2_bridge.as_ref().map(|b| b.counters());
    let ros2_out = ros2_bridge.as_ref().map(|b| b.outbox()).unwrap_or_default();
    // A server of a plant: its version clock, its announcement, and the replication of its store.
    let (store, plant) = match (&session, &config.plant.server_id) {
        (Some(s), Some(id)) => {
            let store = store.stamped(id, crate::plant::version_clock(s));
            let scheme = if tls.is_some() { "https" } else { "http" };
            let server = dmp_proto::v1::PlantServer {
                server_id: id.clone(),
                grpc_address: config
                    .plant
                    .advertise_addr
                    .clone()
                    .unwrap_or_else(|| format!("{scheme}://{grpc_addr}")),
                cells: crate::plant::announced_cells(&cells),
                ..Default::default()
            };
            let scene = bridge.as_ref().map(|b| b.obstacle_sink()).ok_or_else(|| {
                ServerError::Internal("a server of a plant without its Zenoh bridge".into())
            })?;
            let plant = crate::plant::Plant::start(
                s,
                server,
                (directory, cells.clone(), scene),
                store.clone(),
                config.limits.clone(),
                shutdown.clone(),
            )
            .await?;
            (store, Some(plant))
        }
        (None, Some(_)) => {
            return Err(ServerError::FailedPrecondition(
                "plant.server_id needs Zenoh (not --no-zenoh)".into(),
            ));
        }
        _ => (store, None),
    };
    let replicator = plant.as_ref().map(|p| p.replicator());

    let compute = Compute::start(&config.compute)
        .map_err(|e| ServerError::Internal(format!("cannot start the compute threads: {e}")))?;
    let state = Arc::new(AppState {
        zenoh_locators: zenoh_locators.clone(),
        compute,
        streams: StreamPermits::new(&config.limits),
        memory,
        config,
        store,
        cells,
        replicator,
        robots,
        shutdown: shutdown.clone(),
        counters: Default::default(),
        histograms: Default::default(),
        clock,
        executing: Executing::default(),
        state_admission,
        access: access.clone(),
        exposure,
        ros2_out,
    });
    let max = state.config.limits.max_message_bytes;
    let metrics_addr = match state.config.metrics_addr {
        Some(addr) => {
            let mut registry = prometheus_client::registry::Registry::default();
            registry
                .register_collector(Box::new(ServerCollector::new(state.clone(), bridge_malformed.clone())));
            Some(crate::metrics::endpoint::serve(addr, registry, shutdown.clone()).await?.0)
        }
        None => None,
    };

    let (health, health_service) = tonic_health::server::health_reporter();
    health.set_serving::<PrimitiveServiceServer<PrimitiveServiceImpl>>().await;
    health.set_serving::<RobotServiceServer<RobotServiceImpl>>().await;
    health.set_serving::<SceneServiceServer<SceneServiceImpl>>().await;
    health.set_serving::<MotionServiceServer<MotionServiceImpl>>().await;
    health.set_serving::<ServerServiceServer<ServerServiceImpl>>().await;
    health.set_service_status("", tonic_health::ServingStatus::Serving).await;
    // The scene serves only while the configured Zenoh routers or peers are reachable.
    if let Some(s) = &session {
        let z = &state.config.zenoh;
        reachability::spawn(s, &z.connect, z.mode == "client", health.clone(), shutdown.clone()).await?;
    }
    let reflection = tonic_reflection::server::Builder::configure()
        .register_encoded_file_descriptor_set(dmp_proto::FILE_DESCRIPTOR_SET)
        .build_v1()
        .map_err(|e| ServerError::Internal(e.to_string()))?;

    let limits = &state.config.limits;
    let mut server = Server::builder();
    if let Some(tls) = tls {
        server = server.tls_config(tls).map_err(|e| {
            ServerError::FailedPrecondition(format!("security: invalid TLS certificate or key: {e}"))
        })?;
    }
    let router = server
        // A span per request: what `--otlp-endpoint` exports (and what is logged inside it carries the path).
        .trace_fn(|request| tracing::info_span!("grpc", rpc = %request.uri().path()))
        .http2_keepalive_interval(seconds(limits.http2_keepalive_interval_s))
        .http2_keepalive_timeout(seconds(limits.http2_keepalive_timeout_s))
        // Every request is authenticated before any handler, and marks its connection active (the idle timeout
        // counts from the last one).
        .layer(AuthenticateLayer::new(access))
        .add_service(health_service)
        .add_service(reflection)
        .add_service(
            PrimitiveServiceServer::new(PrimitiveServiceImpl::new(state.clone()))
                .max_decoding_message_size(max)
                .max_encoding_message_size(max),
        )
        .add_service(
            RobotServiceServer::new(RobotServiceImpl::new(state.clone()))
                .max_decoding_message_size(max)
                .max_encoding_message_size(max),
        )
        .add_service(
            SceneServiceServer::new(SceneServiceImpl::new(state.clone()))
                .max_decoding_message_size(max)
                .max_encoding_message_size(max),
        )
        .add_service(
            MotionServiceServer::new(MotionServiceImpl::new(state.clone()))
                .max_decoding_message_size(max)
                .max_encoding_message_size(max),
        )
        .add_service(ServerServiceServer::new(ServerServiceImpl::new(state.clone())));
    // Segments are small and latency-critical: no Nagle delay on accepted connections; the server batches its
    // own writes instead, and writes at once what cannot wait (`write_batching`).
    let idle_timeout = seconds(limits.idle_timeout_s);
    let incoming = tokio_stream::StreamExt::map(
        tonic::transport::server::TcpIncoming::from(listener)
            .with_nodelay(Some(true))
            .with_keepalive(seconds(limits.tcp_keepalive_s)),
        move |conn| conn.map(|c| BatchedWrites::new(c).with_idle_timeout(idle_timeout)),
    );
    let stop = shutdown.clone();
    let task = tokio::spawn(async move {
        // On shutdown: NOT_SERVING first, so that balancers stop sending, then drain (streams end on the same
        // signal), at most DRAIN_TIMEOUT.
        let signal = {
            let stop = stop.clone();
            async move {
                stop.cancelled().await;
                health.set_service_status("", tonic_health::ServingStatus::NotServing).await;
            }
        };
        let served = router.serve_with_incoming_shutdown(incoming, signal);
        let deadline = async {
            stop.cancelled().await;
            tokio::time::sleep(DRAIN_TIMEOUT).await;
        };
        let served = tokio::select! {
            r = served => r.map_err(|e| ServerError::Internal(format!("gRPC server: {e}"))),
            _ = deadline => {
                warn!(timeout = ?DRAIN_TIMEOUT, "connections still open after the drain timeout: closing them");
                Ok(())
            }
        };
        if let Some(p) = plant {
            p.close().await;
        }
        if let Some(b) = ros2_bridge {
            b.close().await;
        }
        if let Some(b) = bridge {
            b.close().await;
        }
        if let Some(s) = session
            && let Err(e) = s.close().await
        {
            warn!(error = %e, "closing the Zenoh session");
        }
        info!("server stopped");
        served
    });
    let security = &state.config.security;
    info!(
        grpc = %grpc_addr,
        zenoh = ?zenoh_locators,
        cell = %state.cells.default_cell(),
        cells = ?state.cells.served(),
        server_id = ?state.config.plant.server_id,
        metrics = ?metrics_addr,
        tls = security.tls_cert.is_some(),
        mutual_tls = security.tls_client_ca.is_some(),
        access_control = state.access.enabled(),
        insecure = state.exposure.insecure(),
        "serving"
    );
    Ok(ServerHandle { grpc_addr, zenoh_locators, metrics_addr, state, bridge_malformed, ros2, task })
}

/// Runs the server until `shutdown` completes (the binary passes SIGINT or SIGTERM), then stops it cleanly. Each
/// item of `hangups` (SIGHUP) reloads the access file.
pub async fn run(
    config: Config,
    shutdown: impl Future<Output = ()> + Send + 'static,
    mut hangups: impl tokio_stream::Stream<Item = ()> + Send + Unpin,
) -> Result<(), ServerError> {
    let handle = start(config).await?;
    tokio::pin!(shutdown);
    loop {
        tokio::select! {
            _ = &mut shutdown => break,
            Some(()) = tokio_stream::StreamExt::next(&mut hangups) => {
                info!("SIGHUP: reloading the access file");
                // A refused file is logged and changes nothing.
                let _ = handle.reload_access();
            }
        }
    }
    info!("shutting down: draining streams, closing Zenoh");
    handle.shutdown().await
}

/// A duration of `s` seconds; None for 0 (or anything not a positive finite number): the feature is off.
fn seconds(s: f64) -> Option<std::time::Duration> {
    (s.is_finite() && s > 0.0).then(|| std::time::Duration::from_secs_f64(s))
}
