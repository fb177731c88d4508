//! The gRPC side: the services, one file each ([`motion`], [`primitives`], [`robots`], [`scene`], [`server`]), what
//! they share ([`shared`]), the layer that authenticates every request ([`authentication`]), TLS ([`tls`]), what a
//! streamed execution asks for ([`stream_request`]), a session's commands checked ([`session_commands`]), a held
//! tool from the wire ([`tool`]); and here, the router that serves them with health and reflection.

pub(crate) mod authentication;
mod limits_in_force;
pub(crate) mod motion;
pub(crate) mod primitives;
mod resolved_motion;
pub(crate) mod robots;
pub(crate) mod scene;
pub(crate) mod server;
pub(crate) mod session_commands;
pub(crate) mod shared;
mod stream_request;
pub(crate) mod tls;
pub(crate) mod tool;

use std::sync::Arc;
use std::time::Duration;

use dmp_proto::v1::motion_service_server::MotionServiceServer;
use dmp_proto::v1::primitive_service_server::PrimitiveServiceServer;
use dmp_proto::v1::robot_service_server::RobotServiceServer;
use dmp_proto::v1::scene_service_server::SceneServiceServer;
use dmp_proto::v1::server_service_server::ServerServiceServer;
use tokio::net::TcpListener;
use tokio_util::sync::CancellationToken;
use tonic::transport::server::{Router, ServerTlsConfig, TcpIncoming};
use tonic::transport::{Error, Server};
use tonic_health::ServingStatus;
use tonic_health::pb::health_server::{Health, HealthServer};
use tonic_health::server::HealthReporter;
use tower::layer::util::{Identity, Stack};
use zenoh::Session;

use self::authentication::AuthenticateLayer;
use self::motion::MotionServiceImpl;
use self::primitives::PrimitiveServiceImpl;
use self::robots::RobotServiceImpl;
use self::scene::SceneServiceImpl;
use self::server::ServerServiceImpl;
use self::shared::ServiceState;
use crate::access::AccessControl;
use crate::config::{RequestLimits, ZenohConfig};
use crate::connections::write_batching::BatchedWrites;
use crate::error::ServerError;
use crate::zenoh_bridge::reachability;

/// The accepted connections: no Nagle delay (segments are small and latency-critical; the server batches its own
/// writes instead, and writes at once what cannot wait), TCP keep-alive, and the idle timeout.
pub(crate) type Incoming = std::pin::Pin<
    Box<dyn tokio_stream::Stream<Item = Result<BatchedWrites<tokio::net::TcpStream>, std::io::Error>> + Send>,
>;

/// The services behind the authentication layer.
pub(crate) type GrpcRouter = Router<Stack<AuthenticateLayer, Identity>>;

/// The health service, every service SERVING; the scene only while the configured Zenoh routers or peers are
/// reachable (checked on `session` until `shutdown`).
pub(crate) async fn health(
    session: Option<&Session>,
    zenoh: &ZenohConfig,
    shutdown: &CancellationToken,
) -> Result<(HealthReporter, HealthServer<impl Health>), ServerError> {
    let (health, service) = tonic_health::server::health_reporter();
    health.set_serving::<PrimitiveServiceServer<PrimitiveServiceImpl>>().await;
    health.set_serving::<RobotServiceServer<RobotServiceImpl>>().await;
    health.set_serving::<SceneServiceServer<SceneServiceImpl>>().await;
    health.set_serving::<MotionServiceServer<MotionServiceImpl>>().await;
    health.set_serving::<ServerServiceServer<ServerServiceImpl>>().await;
    health.set_service_status("", ServingStatus::Serving).await;
    if let Some(s) = session {
        reachability::spawn(s, &zenoh.connect, zenoh.mode == "client", health.clone(), shutdown.clone())
            .await?;
    }
    Ok((health, service))
}

/// Every service over `state`, with `health` and reflection, behind the layer that authenticates each request
/// against `access`, over `tls` when given.
pub(crate) fn router(
    state: &Arc<ServiceState>,
    tls: Option<ServerTlsConfig>,
    access: Arc<AccessControl>,
    health: HealthServer<impl Health>,
) -> Result<GrpcRouter, ServerError> {
    let reflection = tonic_reflection::server::Builder::configure()
        .register_encoded_file_descriptor_set(dmp_proto::FILE_DESCRIPTOR_SET)
        .build_v1()
        .map_err(|e| ServerError::Internal(e.to_string()))?;
    let limits = &state.config.limits;
    let max = limits.max_message_bytes;
    let mut server = Server::builder();
    if let Some(tls) = tls {
        server = server.tls_config(tls).map_err(|e: Error| {
            ServerError::FailedPrecondition(format!("security: invalid TLS certificate or key: {e}"))
        })?;
    }
    Ok(server
        // A span per request: what `--otlp-endpoint` exports (and what is logged inside it carries the path).
        .trace_fn(|request| tracing::info_span!("grpc", rpc = %request.uri().path()))
        .http2_keepalive_interval(seconds(limits.http2_keepalive_interval_s))
        .http2_keepalive_timeout(seconds(limits.http2_keepalive_timeout_s))
        // Every request is authenticated before any handler, and marks its connection active (the idle timeout
        // counts from the last one).
        .layer(AuthenticateLayer::new(access))
        .add_service(health)
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
        .add_service(ServerServiceServer::new(ServerServiceImpl::new(state.clone()))))
}

/// The connections accepted on `listener`, as [`Incoming`] says, bounded by `limits`.
pub(crate) fn incoming(listener: TcpListener, limits: &RequestLimits) -> Incoming {
    let idle_timeout = seconds(limits.idle_timeout_s);
    Box::pin(tokio_stream::StreamExt::map(
        TcpIncoming::from(listener).with_nodelay(Some(true)).with_keepalive(seconds(limits.tcp_keepalive_s)),
        move |conn| conn.map(|c| BatchedWrites::new(c).with_idle_timeout(idle_timeout)),
    ))
}

/// A duration of `s` seconds; None for 0 (or anything not a positive finite number): the feature is off.
fn seconds(s: f64) -> Option<Duration> {
    (s.is_finite() && s > 0.0).then(|| Duration::from_secs_f64(s))
}
