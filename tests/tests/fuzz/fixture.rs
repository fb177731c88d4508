//! The real server for the gRPC targets: in-process, gRPC only, with bounds small enough that every case takes
//! milliseconds; after each case it must still answer health with SERVING and report no failed computation.

use std::future::Future;
use std::time::Duration;

use proptest::test_runner::{TestCaseError, TestCaseResult};
use tonic::transport::{Channel, Endpoint};
use tonic::{Code, Status};

use dmp_proto::v1;
use dmp_proto::v1::server_service_client::ServerServiceClient;
use dmp_tests::{TestServer, within};
use tonic_health::pb::health_check_response::ServingStatus;
use tonic_health::pb::health_client::HealthClient;

use crate::wire::all_finite;

/// The longest one await of a case may take before the case counts as a hang.
pub const WAIT: Duration = Duration::from_secs(20);

/// `f`, or a failed case naming `what` after [`WAIT`].
pub async fn bounded<F: Future>(what: &str, f: F) -> Result<F::Output, TestCaseError> {
    tokio::time::timeout(WAIT, f)
        .await
        .map_err(|_| TestCaseError::fail(format!("hang: {what} took more than {WAIT:?}")))
}

/// A refusal is fine when it is a clear status; INTERNAL, UNKNOWN (a panic) and the others are failures.
pub fn refused(what: &str, s: &Status) -> TestCaseResult {
    match s.code() {
        Code::InvalidArgument
        | Code::NotFound
        | Code::ResourceExhausted
        | Code::FailedPrecondition
        | Code::OutOfRange
        | Code::AlreadyExists => Ok(()),
        _ => Err(TestCaseError::fail(format!("{what}: {:?}: {}", s.code(), s.message()))),
    }
}

/// Fails unless a segment is well formed and every number in it is finite.
pub fn check_segment(s: &v1::Segment) -> TestCaseResult {
    let d = s.dim as usize;
    if d == 0 || !s.positions.len().is_multiple_of(d) {
        return Err(TestCaseError::fail(format!("segment of dim {d} with {} positions", s.positions.len())));
    }
    for (what, v) in [("velocities", &s.velocities), ("accelerations", &s.accelerations)] {
        if !v.is_empty() && v.len() != s.positions.len() {
            return Err(TestCaseError::fail(format!("segment {what}: {} values", v.len())));
        }
    }
    all_finite("segment.positions", &s.positions)?;
    all_finite("segment.velocities", &s.velocities)?;
    all_finite("segment.accelerations", &s.accelerations)?;
    all_finite("segment.start_time, dt", &[s.start_time, s.dt, s.start_unix_s])
}

/// Fails unless every number of an obstacle the server reports is finite.
pub fn check_obstacle(o: &v1::Obstacle) -> TestCaseResult {
    all_finite("obstacle.center", &o.center)?;
    all_finite("obstacle.rotation", &o.rotation)?;
    all_finite("obstacle.velocity", &o.velocity)?;
    all_finite("obstacle.margin, ttl_s", &[o.margin, o.ttl_s])?;
    let shape = match &o.shape {
        Some(v1::obstacle::Shape::Superquadric(s)) => [s.semi_axes.clone(), s.exponents.clone()].concat(),
        Some(v1::obstacle::Shape::Nested(n)) => [n.semi_axes.clone(), vec![n.n, n.m]].concat(),
        Some(v1::obstacle::Shape::Solid(s)) => s.dimensions.clone(),
        None => return Err(TestCaseError::fail(format!("obstacle `{}` without a shape", o.id))),
    };
    all_finite("obstacle.shape", &shape)
}

/// Fails unless a stored record holds a valid, finite primitive.
pub fn check_record(r: &v1::PrimitiveRecord) -> TestCaseResult {
    let p = r.primitive.as_ref().ok_or_else(|| TestCaseError::fail("record without primitive"))?;
    dmp_proto::primitive::primitive_from_proto(p)
        .map_err(|e| TestCaseError::fail(format!("the server returned an invalid primitive: {e}")))?;
    all_finite("primitive", &[p.alpha, p.tau])?;
    all_finite("primitive.weights", &p.weights)
}

/// The real server and its runtime; one per target.
#[derive(Debug)]
pub struct Fuzzed {
    rt: tokio::runtime::Runtime,
    server: Option<TestServer>,
    /// A connection to it.
    pub channel: Channel,
}

impl Fuzzed {
    /// Starts the server (gRPC only, small bounds) and connects.
    pub fn start() -> Self {
        let rt = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(2)
            .enable_all()
            .build()
            .expect("a runtime");
        let server = rt.block_on(TestServer::start_with(|c| {
            c.zenoh.disabled = true;
            c.limits.max_steps = 20_000;
            c.limits.max_samples = 2_000;
            c.limits.max_obstacles = 50;
            c.limits.max_streams = 64;
            c.compute.max_request_work = 1e8;
            // Cell `c1` (of `requests::CELLS`) is declared, empty: motions run there too, not only refusals.
            c.scene.cells.insert("c1".into(), Default::default());
        }));
        let endpoint = Endpoint::from_shared(server.url()).expect("a URL");
        let channel = rt.block_on(within("connect", endpoint.connect())).expect("connects");
        Self { rt, server: Some(server), channel }
    }

    /// Runs one case (under [`WAIT`] in all), then checks that the server still serves and no computation failed.
    pub fn case(&self, f: impl Future<Output = TestCaseResult>) -> TestCaseResult {
        self.rt.block_on(async {
            let failed_before = self.still_serving().await?;
            bounded("the case", f).await??;
            let failed = self.still_serving().await? - failed_before;
            if failed > 0 {
                return Err(TestCaseError::fail(format!("{failed} computations failed (a panic)")));
            }
            Ok(())
        })
    }

    /// Runs `f` on the server's runtime (set-up before the cases).
    pub fn block_on<F: Future>(&self, f: F) -> F::Output {
        self.rt.block_on(f)
    }

    /// Checks that the server serves; returns its count of failed computations.
    async fn still_serving(&self) -> Result<u64, TestCaseError> {
        let mut health = HealthClient::new(self.channel.clone());
        let request = tonic_health::pb::HealthCheckRequest { service: String::new() };
        let status = bounded("health", health.check(request))
            .await?
            .map_err(|s| TestCaseError::fail(format!("health check failed: {s}")))?
            .into_inner()
            .status;
        if status != ServingStatus::Serving as i32 {
            return Err(TestCaseError::fail(format!("health is {status}, not SERVING")));
        }
        let mut server = ServerServiceClient::new(self.channel.clone());
        let stats = bounded("stats", server.get_stats(v1::GetStatsRequest {}))
            .await?
            .map_err(|s| TestCaseError::fail(format!("GetStats failed: {s}")))?
            .into_inner();
        all_finite("stats", &[stats.uptime_s, stats.cpu_seconds])?;
        Ok(stats.jobs_failed)
    }

    /// Stops the server and checks that it shuts down cleanly.
    pub fn stop(mut self) {
        let server = self.server.take().expect("running");
        self.rt.block_on(server.stop());
    }
}
