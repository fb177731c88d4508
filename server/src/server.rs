//! Assembling and running the server: store, scene, Zenoh, the gRPC services (with health and reflection), and one
//! shutdown path for all of them.

use std::future::Future;
use std::net::SocketAddr;
use std::sync::Arc;

use tokio::net::TcpListener;
use tokio::task::JoinHandle;
use tokio_util::sync::CancellationToken;
use tonic_health::server::HealthReporter;
use tracing::{info, warn};

use crate::access::AccessControl;
use crate::access::exposure;
use crate::cells::Cells;
use crate::cells::directory::Directory;
use crate::cells::state_admission::StateAdmission;
use crate::clock::Clock;
use crate::config::Config;
use crate::connections::stream_permits::StreamPermits;
use crate::error::ServerError;
use crate::grpc;
use crate::grpc::shared::ServiceState;
use crate::grpc::tls::server_tls;
use crate::memory::MemoryBudget;
use crate::metrics;
use crate::plant::Plant;
use crate::ros2::{Ros2Bridge, Ros2Counters};
use crate::runs::compute::Compute;
use crate::runs::context::RunContext;
use crate::runs::executing::Executing;
use crate::store::Store;
use crate::zenoh_bridge::ZenohSide;

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
    state: Arc<ServiceState>,
    bridge_malformed: Option<Arc<std::sync::atomic::AtomicU64>>,
    ros2: Option<Arc<Ros2Counters>>,
    task: JoinHandle<Result<(), ServerError>>,
}

impl ServerHandle {
    /// The cells this server serves, with their scenes.
    pub fn cells(&self) -> &Cells {
        &self.state.cells
    }

    /// The store of primitives and robot records.
    pub fn store(&self) -> &Store {
        &self.state.store
    }

    /// The compute pools and their admission budgets.
    pub fn compute(&self) -> &Compute {
        &self.state.runs.compute
    }

    /// The effective configuration.
    pub fn config(&self) -> &Config {
        &self.state.config
    }

    /// The server's memory account.
    pub fn memory(&self) -> &MemoryBudget {
        &self.state.memory
    }

    /// Segments sent so far (a group segment counts once per member).
    pub fn segments_sent(&self) -> u64 {
        self.state.runs.counters.segments_sent.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// Executions open now.
    pub fn open_executions(&self) -> usize {
        self.state.runs.streams.open_executions()
    }

    /// Scene watches open now.
    pub fn open_watches(&self) -> usize {
        self.state.runs.streams.open_watches()
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
    pub fn ros2_counters(&self) -> Option<&Arc<Ros2Counters>> {
        self.ros2.as_ref()
    }

    /// Streams currently open (executions and watches).
    pub fn open_streams(&self) -> usize {
        self.state.runs.streams.open_executions() + self.state.runs.streams.open_watches()
    }

    /// Stops: streams end, gRPC drains, Zenoh closes. Returns once everything is down.
    pub async fn shutdown(self) -> Result<(), ServerError> {
        self.state.runs.shutdown.cancel();
        self.task.await.map_err(|e| ServerError::Internal(e.to_string()))?
    }
}

/// Starts the server on the system's clock and returns once it serves (health SERVING).
pub async fn start(config: Config) -> Result<ServerHandle, ServerError> {
    start_with_clock(config, Clock::system()).await
}

/// Starts the server on `clock` (tests run real time on tokio's paused clock) and returns once it serves: each step
/// lives in the module it concerns, in the order of the layers.
pub(crate) async fn start_with_clock(config: Config, clock: Clock) -> Result<ServerHandle, ServerError> {
    // Refused before anything listens: exposure without protection, a bad default profile, a bad access file,
    // bad TLS files.
    let exposure = exposure::check(&config)?;
    config.defaults.check()?;
    for reason in &exposure.warnings {
        warn!(reason = %reason, "INSECURE (--insecure): anyone who reaches the server can steer every robot");
    }
    let access = Arc::new(AccessControl::from_config(&config.security)?);
    let tls = server_tls(&config.security)?;
    let listener = TcpListener::bind(config.grpc_addr).await.map_err(|e| {
        ServerError::FailedPrecondition(format!("cannot listen on {}: {e}", config.grpc_addr))
    })?;
    let grpc_addr = listener.local_addr().map_err(|e| ServerError::Internal(e.to_string()))?;
    let store = Store::open_configured(&config).await?;
    let memory = MemoryBudget::new(config.limits.max_server_bytes);
    let directory = Directory::default();
    let cells = Cells::from_config(&config, memory.clone(), directory.clone())?;
    let shutdown = CancellationToken::new();
    let state_admission = StateAdmission::new(&config.limits);
    let zenoh = ZenohSide::start(&config, &access, &cells, clock, &state_admission, &shutdown).await?;
    let ros2 = Ros2Bridge::start_configured(&zenoh, &config.ros2, &cells, clock).await?;
    let ros2_counters = ros2.as_ref().map(|b| b.counters());
    let advertised = config
        .plant
        .advertise_addr
        .clone()
        .unwrap_or_else(|| format!("{}://{grpc_addr}", if tls.is_some() { "https" } else { "http" }));
    let sink = zenoh.bridge.as_ref().map(|b| b.obstacle_sink());
    let (store, plant) = Plant::join(
        &config,
        (zenoh.session.as_ref(), sink),
        advertised,
        (directory, &cells),
        store,
        &shutdown,
    )
    .await?;
    let compute = Compute::start(&config.compute)
        .map_err(|e| ServerError::Internal(format!("cannot start the compute threads: {e}")))?;
    let runs = Arc::new(RunContext {
        clock,
        compute,
        robots: zenoh.robots.clone(),
        ros2_out: ros2.as_ref().map(|b| b.outbox()).unwrap_or_default(),
        shutdown: shutdown.clone(),
        streams: StreamPermits::new(&config.limits),
        counters: Default::default(),
        histograms: Default::default(),
    });
    let state = Arc::new(ServiceState {
        zenoh_locators: zenoh.locators.clone(),
        runs,
        memory,
        store,
        cells,
        replicator: plant.as_ref().map(|p| p.replicator()),
        executing: Executing::default(),
        state_admission,
        access: access.clone(),
        exposure,
        config,
    });
    let malformed = zenoh.bridge.as_ref().map(|b| b.malformed_counter());
    let metrics_addr = metrics::serve_configured(&state, malformed.clone()).await?;
    let health = grpc::health(zenoh.session.as_ref(), &state.config.zenoh, &shutdown).await?;
    let router = grpc::router(&state, tls, access, health.1)?;
    let incoming = grpc::incoming(listener, &state.config.limits);
    let closing = Closing { plant, ros2_bridge: ros2, zenoh };
    let task = tokio::spawn(serve(router, incoming, health.0, closing, shutdown));
    log_serving(&state, grpc_addr, metrics_addr);
    Ok(ServerHandle {
        grpc_addr,
        zenoh_locators: state.zenoh_locators.clone(),
        metrics_addr,
        state,
        bridge_malformed: malformed,
        ros2: ros2_counters,
        task,
    })
}

/// What closes once the gRPC server has drained, in this order.
struct Closing {
    plant: Option<Plant>,
    ros2_bridge: Option<Ros2Bridge>,
    zenoh: ZenohSide,
}

/// Serves `router` on `incoming` until `shutdown`: NOT_SERVING first, so that balancers stop sending, then drain
/// (streams end on the same signal), at most [`DRAIN_TIMEOUT`]; then closes the plant, ROS 2 and Zenoh.
async fn serve(
    router: grpc::GrpcRouter,
    incoming: grpc::Incoming,
    health: HealthReporter,
    closing: Closing,
    shutdown: CancellationToken,
) -> Result<(), ServerError> {
    let signal = {
        let stop = shutdown.clone();
        async move {
            stop.cancelled().await;
            health.set_service_status("", tonic_health::ServingStatus::NotServing).await;
        }
    };
    let served = router.serve_with_incoming_shutdown(incoming, signal);
    let deadline = async {
        shutdown.cancelled().await;
        tokio::time::sleep(DRAIN_TIMEOUT).await;
    };
    let served = tokio::select! {
        r = served => r.map_err(|e| ServerError::Internal(format!("gRPC server: {e}"))),
        _ = deadline => {
            warn!(timeout = ?DRAIN_TIMEOUT, "connections still open after the drain timeout: closing them");
            Ok(())
        }
    };
    if let Some(p) = closing.plant {
        p.close().await;
    }
    if let Some(b) = closing.ros2_bridge {
        b.close().await;
    }
    closing.zenoh.close().await;
    info!("server stopped");
    served
}

/// The one line that says the server serves, and how it is exposed.
fn log_serving(state: &ServiceState, grpc_addr: SocketAddr, metrics_addr: Option<SocketAddr>) {
    let security = &state.config.security;
    info!(
        grpc = %grpc_addr,
        zenoh = ?state.zenoh_locators,
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
