//! How a client reaches a secured server: TLS (the CA that signed the server's certificate, and for mutual TLS
//! the client's own certificate and key) and a bearer token sent with every call.
//!
//! ```no_run
//! # async fn demo() -> Result<(), dmp_client::ClientError> {
//! use dmp_client::connect::{ConnectOptions, TlsOptions};
//! use dmp_client::DmpClient;
//! let options = ConnectOptions {
//!     token: Some(std::env::var("DMP_TOKEN").unwrap_or_default()),
//!     tls: Some(TlsOptions::from_files("ca.pem".as_ref(), None, None)?),
//!     ..Default::default()
//! };
//! let client = DmpClient::connect_with("https://cell-a:50051", &options).await?;
//! # Ok(()) }
//! ```

use std::path::Path;
use std::time::Duration;

use tonic::metadata::AsciiMetadataValue;
use tonic::service::Interceptor;
use tonic::service::interceptor::InterceptedService;
use tonic::transport::{Certificate, Channel, ClientTlsConfig, Endpoint, Identity};

use crate::error::{ClientError, chain};

/// How long a connection waits for the server by default.
pub const CONNECT_TIMEOUT: Duration = Duration::from_secs(5);

/// The channel every call goes through: the credentials are added to each.
pub(crate) type Transport = InterceptedService<Channel, Credentials>;

/// TLS of a client.
#[derive(Clone, Default)]
pub struct TlsOptions {
    /// The CA that signed the server's certificate (PEM).
    pub ca_pem: Vec<u8>,
    /// The client's certificate (PEM), for mutual TLS.
    pub cert_pem: Option<Vec<u8>>,
    /// The client's private key (PEM), for mutual TLS.
    pub key_pem: Option<Vec<u8>>,
    /// The name the server's certificate must have; default: the URL's host.
    pub domain: Option<String>,
}

impl std::fmt::Debug for TlsOptions {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TlsOptions")
            .field("client_certificate", &self.cert_pem.is_some())
            .field("domain", &self.domain)
            .finish_non_exhaustive()
    }
}

impl TlsOptions {
    /// Reads the CA, and the client's certificate and key when given (both or neither).
    pub fn from_files(ca: &Path, cert: Option<&Path>, key: Option<&Path>) -> Result<Self, ClientError> {
        let read = |field: &str, path: &Path| {
            std::fs::read(path)
                .map_err(|e| ClientError::argument(field, format!("cannot read {}: {e}", path.display())))
        };
        if cert.is_some() != key.is_some() {
            return Err(ClientError::argument("tls-cert", "the client's certificate and key go together"));
        }
        Ok(Self {
            ca_pem: read("tls-ca", ca)?,
            cert_pem: cert.map(|p| read("tls-cert", p)).transpose()?,
            key_pem: key.map(|p| read("tls-key", p)).transpose()?,
            domain: None,
        })
    }
}

/// How to connect.
#[derive(Clone)]
pub struct ConnectOptions {
    /// How long to wait for the server.
    pub timeout: Duration,
    /// The bearer token sent with every call.
    pub token: Option<String>,
    /// TLS (the URL is then `https://`).
    pub tls: Option<TlsOptions>,
}

impl std::fmt::Debug for ConnectOptions {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ConnectOptions")
            .field("timeout", &self.timeout)
            .field("token", &self.token.as_ref().map(|_| "<hidden>"))
            .field("tls", &self.tls)
            .finish()
    }
}

impl Default for ConnectOptions {
    fn default() -> Self {
        Self { timeout: CONNECT_TIMEOUT, token: None, tls: None }
    }
}

/// The `authorization` metadata sent with every call (never printed).
#[derive(Clone, Default)]
pub(crate) struct Credentials {
    header: Option<AsciiMetadataValue>,
}

impl std::fmt::Debug for Credentials {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Credentials").field("token", &self.header.as_ref().map(|_| "<hidden>")).finish()
    }
}

impl Credentials {
    /// The credentials of `token` (none: nothing is sent).
    pub(crate) fn token(token: Option<&str>) -> Result<Self, ClientError> {
        let header = token
            .map(|t| {
                let mut v = AsciiMetadataValue::try_from(format!("Bearer {}", t.trim()))
                    .map_err(|_| ClientError::argument("token", "must be printable ASCII"))?;
                v.set_sensitive(true);
                Ok::<_, ClientError>(v)
            })
            .transpose()?;
        Ok(Self { header })
    }
}

impl Interceptor for Credentials {
    fn call(&mut self, mut request: tonic::Request<()>) -> Result<tonic::Request<()>, tonic::Status> {
        if let Some(h) = &self.header {
            request.metadata_mut().insert("authorization", h.clone());
        }
        Ok(request)
    }
}

/// The URL with a scheme: a bare `HOST:PORT` is `https://` with TLS, `http://` without.
pub(crate) fn normalize_url(url: &str, tls: bool) -> String {
    if url.contains("://") {
        url.to_owned()
    } else if tls {
        format!("https://{url}")
    } else {
        format!("http://{url}")
    }
}

/// Opens a channel to `url` with `options`. A server that refuses, does not answer or fails the TLS handshake gives
/// [`ClientError::Connect`]; bad options give [`ClientError::Argument`].
pub(crate) async fn open(url: &str, options: &ConnectOptions) -> Result<(Channel, String), ClientError> {
    let url = normalize_url(url, options.tls.is_some());
    let mut endpoint = Endpoint::from_shared(url.clone())
        .map_err(|e| {
            ClientError::argument("server", format!("`{url}` is not a valid address: {}", chain(&e)))
        })?
        .connect_timeout(options.timeout)
        .tcp_nodelay(true);
    match &options.tls {
        Some(tls) => {
            if !url.starts_with("https://") {
                return Err(ClientError::argument(
                    "server",
                    format!("`{url}`: TLS needs an https:// address"),
                ));
            }
            let _ = rustls::crypto::ring::default_provider().install_default();
            let mut config = ClientTlsConfig::new().ca_certificate(Certificate::from_pem(&tls.ca_pem));
            if let (Some(cert), Some(key)) = (&tls.cert_pem, &tls.key_pem) {
                config = config.identity(Identity::from_pem(cert, key));
            }
            if let Some(domain) = &tls.domain {
                config = config.domain_name(domain.clone());
            }
            endpoint = endpoint.tls_config(config).map_err(|e| {
                ClientError::argument("tls-ca", format!("invalid TLS settings: {}", chain(&e)))
            })?;
        }
        None if url.starts_with("https://") => {
            return Err(ClientError::argument("tls-ca", format!("`{url}` needs the server's CA (--tls-ca)")));
        }
        None => {}
    }
    let timeout = options.timeout;
    let channel = match tokio::time::timeout(timeout, endpoint.connect()).await {
        Err(_) => return Err(ClientError::Connect { url, message: format!("no answer within {timeout:?}") }),
        Ok(Err(e)) => return Err(ClientError::Connect { url, message: chain(&e) }),
        Ok(Ok(c)) => c,
    };
    Ok((channel, url))
}
