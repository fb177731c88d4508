//! The fixture shared by the end-to-end tests: the real server's configuration on loopback, and timeouts.

use std::future::Future;
use std::path::Path;
use std::time::Duration;

use dmp_server::config::Config;

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
