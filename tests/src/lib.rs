//! The fixture of the end-to-end tests (and of the latency example): the real server in-process on loopback, and
//! timeouts. Every test that needs a running server starts it here.

pub mod browser;

use std::future::Future;
use std::path::Path;
use std::time::Duration;

use dmp_client::DmpClient;
use dmp_server::config::Config;
use dmp_server::server::ServerHandle;

pub mod scrape;

/// The longest any single await of a test may take.
pub const T: Duration = Duration::from_secs(120);

/// `f`, or a panic naming `what` after [`T`].
pub async fn within<F: Future>(what: &str, f: F) -> F::Output {
    tokio::time::timeout(T, f).await.unwrap_or_else(|_| panic!("timed out: {what}"))
}

/// The server on `127.0.0.1:0`, its store in `dir`, Zenoh on a loopback port with multicast scouting off.
pub fn config(dir: &Path) -> Config {
    let mut c = Config {
        grpc_addr: "127.0.0.1:0".parse().unwrap(),
        data_dir: dir.to_path_buf(),
        ..Default::default()
    };
    c.zenoh.listen = vec!["tcp/127.0.0.1:0".into()];
    c.zenoh.multicast_scouting = false;
    c
}

/// Secures `c` with the set `dmp-server access init` wrote in `set`: its access file, TLS with its server
/// certificate, client certificates of its CA (mutual TLS), and Zenoh on a `tls/` loopback endpoint.
pub fn secure(c: &mut Config, set: &Path) {
    c.zenoh.listen = vec!["tls/127.0.0.1:0".into()];
    c.security.access = Some(set.join("access.toml"));
    c.security.tls_cert = Some(set.join("server.pem"));
    c.security.tls_key = Some(set.join("server.key"));
    c.security.tls_client_ca = Some(set.join("ca.pem"));
}

/// The real server, in-process, its store in a temporary directory removed when it is dropped.
#[derive(Debug)]
pub struct TestServer {
    handle: ServerHandle,
    _dir: tempfile::TempDir,
}

impl TestServer {
    /// Starts a server of [`config`]: gRPC and Zenoh on loopback (it serves when this returns).
    pub async fn start() -> Self {
        Self::start_with(|_| {}).await
    }

    /// Starts a server of [`config`] without Zenoh (gRPC only).
    pub async fn grpc_only() -> Self {
        Self::start_with(|c| c.zenoh.disabled = true).await
    }

    /// Starts a server of [`config`] changed by `adjust`.
    pub async fn start_with(adjust: impl FnOnce(&mut Config)) -> Self {
        let dir = tempfile::tempdir().expect("a temporary directory");
        let mut c = config(dir.path());
        adjust(&mut c);
        let handle = within("server start", dmp_server::server::start(c)).await.expect("server starts");
        Self { handle, _dir: dir }
    }

    /// The running server: its addresses, its Zenoh locators.
    pub fn handle(&self) -> &ServerHandle {
        &self.handle
    }

    /// Its gRPC address as an `http://` URL.
    pub fn url(&self) -> String {
        format!("http://{}", self.handle.grpc_addr)
    }

    /// A client connected to it.
    pub async fn client(&self) -> DmpClient {
        within("connect", DmpClient::connect(self.url())).await.expect("connects")
    }

    /// Stops it and waits until it is down.
    pub async fn stop(self) {
        within("server shutdown", self.handle.shutdown()).await.expect("shuts down");
    }
}
