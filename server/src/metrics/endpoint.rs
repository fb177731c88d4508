//! The HTTP endpoint Prometheus scrapes: `GET /metrics` on `--metrics-addr`, plain HTTP/1.1 (hyper, as tonic's
//! own HTTP stack), on the server's async runtime (never on the compute threads).
//!
//! A scraper cannot hurt the robots: at most [`MAX_CONNECTIONS`] connections at once (more are closed on accept),
//! each for at most [`CONNECTION_TIMEOUT`], its request headers within [`HEADER_TIMEOUT`]; a scrape reads atomics
//! and each cell's current snapshot, and writes a text of a few lines per cell (at most `limits.max_cells`).

use std::convert::Infallible;
use std::net::SocketAddr;
use std::sync::Arc;
use std::time::Duration;

use http_body_util::Full;
use hyper::body::Bytes;
use hyper::server::conn::http1;
use hyper::service::service_fn;
use hyper::{Method, Request, Response, StatusCode};
use hyper_util::rt::{TokioIo, TokioTimer};
use prometheus_client::registry::Registry;
use tokio::net::TcpListener;
use tokio::sync::Semaphore;
use tokio::task::JoinHandle;
use tokio_util::sync::CancellationToken;
use tracing::{debug, info, warn};

use crate::error::ServerError;

/// Most scrape connections open at once.
pub(crate) const MAX_CONNECTIONS: usize = 4;
/// Longest a scrape connection may stay open (Prometheus reconnects).
pub(crate) const CONNECTION_TIMEOUT: Duration = Duration::from_secs(60);
/// Longest a client may take to send its request's headers.
pub(crate) const HEADER_TIMEOUT: Duration = Duration::from_secs(5);
/// The content type of the OpenMetrics text format.
pub(crate) const CONTENT_TYPE: &str = "application/openmetrics-text; version=1.0.0; charset=utf-8";

/// Listens on `addr` and serves `registry` until `stop`; returns the address bound (the real port for port 0).
pub(crate) async fn serve(
    addr: SocketAddr,
    registry: Registry,
    stop: CancellationToken,
) -> Result<(SocketAddr, JoinHandle<()>), ServerError> {
    let listener = TcpListener::bind(addr).await.map_err(|e| {
        ServerError::FailedPrecondition(format!("metrics_addr: cannot listen on {addr}: {e}"))
    })?;
    let bound = listener.local_addr().map_err(|e| ServerError::Internal(e.to_string()))?;
    info!(metrics = %bound, "serving Prometheus metrics over plain HTTP (GET /metrics), without authentication");
    let registry = Arc::new(registry);
    let slots = Arc::new(Semaphore::new(MAX_CONNECTIONS));
    let task = tokio::spawn(async move {
        loop {
            let stream = tokio::select! {
                accepted = listener.accept() => match accepted {
                    Ok((stream, _)) => stream,
                    Err(e) => {
                        // Out of file descriptors, for instance: wait a little rather than spin.
                        warn!(error = %e, "metrics endpoint: accept failed");
                        tokio::time::sleep(Duration::from_millis(100)).await;
                        continue;
                    }
                },
                _ = stop.cancelled() => break,
            };
            let Ok(slot) = slots.clone().try_acquire_owned() else {
                debug!("metrics endpoint: {MAX_CONNECTIONS} connections open, closing a new one");
                continue;
            };
            let registry = registry.clone();
            let stop = stop.clone();
            tokio::spawn(async move {
                let _slot = slot;
                let service = service_fn(move |request| {
                    let registry = registry.clone();
                    async move { Ok::<_, Infallible>(respond(&registry, &request)) }
                });
                let connection = http1::Builder::new()
                    .timer(TokioTimer::new())
                    .header_read_timeout(HEADER_TIMEOUT)
                    .serve_connection(TokioIo::new(stream), service);
                tokio::select! {
                    r = tokio::time::timeout(CONNECTION_TIMEOUT, connection) => {
                        if let Ok(Err(e)) = r {
                            debug!(error = %e, "metrics endpoint: connection ended");
                        }
                    }
                    _ = stop.cancelled() => {}
                }
            });
        }
    });
    Ok((bound, task))
}

/// `GET /metrics`: the metrics now; anything else: 404 or 405.
fn respond<B>(registry: &Registry, request: &Request<B>) -> Response<Full<Bytes>> {
    let reply = |status: StatusCode, content_type: &str, body: String| {
        let mut r = Response::new(Full::new(Bytes::from(body)));
        *r.status_mut() = status;
        if let Ok(v) = content_type.parse() {
            r.headers_mut().insert(hyper::header::CONTENT_TYPE, v);
        }
        r
    };
    let text = "text/plain; charset=utf-8";
    if request.uri().path() != "/metrics" {
        return reply(StatusCode::NOT_FOUND, text, "not found: the metrics are at /metrics\n".into());
    }
    if request.method() != Method::GET && request.method() != Method::HEAD {
        return reply(StatusCode::METHOD_NOT_ALLOWED, text, "only GET\n".into());
    }
    let mut body = String::new();
    match prometheus_client::encoding::text::encode(&mut body, registry) {
        Ok(()) => reply(StatusCode::OK, CONTENT_TYPE, body),
        Err(e) => {
            warn!(error = %e, "metrics endpoint: cannot encode the metrics");
            reply(StatusCode::INTERNAL_SERVER_ERROR, text, "cannot encode the metrics\n".into())
        }
    }
}
