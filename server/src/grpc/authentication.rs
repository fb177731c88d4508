//! The one layer every gRPC request passes before any handler: it finds who calls (a bearer token, else the
//! verified TLS client certificate) and puts the [`crate::access::Caller`] in the request's extensions for the handlers to
//! authorise. Health answers everyone (probes carry no credentials); reflection follows the observer role. A
//! request without a known identity ends here with UNAUTHENTICATED; that refusal, and a handler's
//! PERMISSION_DENIED answered before any message of the response, are audited ([`crate::access::audit`]).
//!
//! It also marks the request's connection active (the idle timeout counts from the last request), and under TLS
//! lifts the connection's information out of tonic's TLS wrapper, so that the rest of the server finds it the
//! same way with and without TLS.

use std::future::Future;
use std::pin::Pin;
use std::sync::Arc;
use std::task::{Context, Poll};

use tonic::transport::server::{TcpConnectInfo, TlsConnectInfo};

use crate::access::{AccessControl, Action, Caller, UNAUTHENTICATED, audit, credential};
use crate::connections::write_batching::BatchedConnectInfo;
use crate::error::ServerError;

/// The services that answer without credentials.
const OPEN_PREFIXES: &[&str] = &["/grpc.health.v1.Health/"];
/// The reflection services (the observer role).
const REFLECTION_PREFIXES: &[&str] = &["/grpc.reflection.v1.ServerReflection/", "/grpc.reflection.v1alpha."];

/// Wraps the services with [`Authenticate`].
#[derive(Debug, Clone)]
pub(crate) struct AuthenticateLayer {
    access: Arc<AccessControl>,
}

impl AuthenticateLayer {
    /// Authenticates against `access`.
    pub(crate) fn new(access: Arc<AccessControl>) -> Self {
        Self { access }
    }
}

impl<S> tower::Layer<S> for AuthenticateLayer {
    type Service = Authenticate<S>;

    fn layer(&self, inner: S) -> Self::Service {
        Authenticate { inner, access: self.access.clone() }
    }
}

/// See the module.
#[derive(Debug, Clone)]
pub(crate) struct Authenticate<S> {
    inner: S,
    access: Arc<AccessControl>,
}

type Connection = BatchedConnectInfo<TcpConnectInfo>;

impl<S, B> tower::Service<http::Request<B>> for Authenticate<S>
where
    S: tower::Service<http::Request<B>, Response = http::Response<tonic::body::Body>>
        + Clone
        + Send
        + 'static,
    S::Future: Send + 'static,
    S::Error: Send + 'static,
    B: Send + 'static,
{
    type Response = S::Response;
    type Error = S::Error;
    type Future = Pin<Box<dyn Future<Output = Result<Self::Response, Self::Error>> + Send>>;

    fn poll_ready(&mut self, cx: &mut Context<'_>) -> Poll<Result<(), Self::Error>> {
        self.inner.poll_ready(cx)
    }

    fn call(&mut self, mut request: http::Request<B>) -> Self::Future {
        let ext = request.extensions_mut();
        let mut common_name = None;
        if let Some(tls) = ext.get::<TlsConnectInfo<Connection>>() {
            common_name =
                tls.peer_certs().and_then(|certs| certs.first().and_then(|c| credential::common_name(c)));
            let connection = tls.get_ref().clone();
            ext.insert(connection);
        }
        let path = request.uri().path();
        if !OPEN_PREFIXES.iter().any(|p| path.starts_with(p)) {
            let reflection = REFLECTION_PREFIXES.iter().any(|p| path.starts_with(p));
            let token = request.headers().get(http::header::AUTHORIZATION).map(|v| v.to_str().ok());
            let caller = match token {
                // A header that is not a bearer token is refused, never ignored in favour of the certificate.
                Some(v) => match v.and_then(credential::bearer) {
                    Some(token) => self.access.authenticate(Some(token), None),
                    None => {
                        let e = ServerError::Unauthenticated(
                            "the `authorization` metadata must be `Bearer <token>`".into(),
                        );
                        audit::refused(UNAUTHENTICATED, "authenticate", &e);
                        Err(e)
                    }
                },
                None => self.access.authenticate(None, common_name.as_deref()),
            };
            let caller = caller.and_then(|c| {
                if reflection {
                    c.check(&Action::Reflection)
                        .inspect_err(|e| audit::refused(c.name(), Action::Reflection.kind(), e))?;
                }
                Ok(c)
            });
            match caller {
                Ok(c) => {
                    request.extensions_mut().insert(c);
                }
                // A refused request does not keep its connection from its idle timeout.
                Err(e) => {
                    let status: tonic::Status = e.into();
                    return Box::pin(std::future::ready(Ok(status.into_http())));
                }
            }
        }
        if let Some(connection) = request.extensions().get::<Connection>() {
            connection.activity.touch();
        }
        // A handler's PERMISSION_DENIED is audited here, once per request: handlers also ask `check` to filter
        // (which robots a caller may see), and those answers are not refusals.
        let who = request
            .extensions()
            .get::<Caller>()
            .map(|c| (c.name().to_owned(), request.uri().path().to_owned()));
        // The service that was made ready is the one called (tower's rule); a clone takes its place.
        let clone = self.inner.clone();
        let mut inner = std::mem::replace(&mut self.inner, clone);
        let response = inner.call(request);
        Box::pin(async move {
            let response = response.await?;
            if let Some((identity, method)) = who
                && let Some(status) = tonic::Status::from_header_map(response.headers())
                && status.code() == tonic::Code::PermissionDenied
            {
                audit::refused(&identity, &method, &status.message());
            }
            Ok(response)
        })
    }
}
