//! A reload of the access file (SIGHUP) against the Zenoh side of a secured server. Zenoh 1.10.2 cannot change
//! the access control of an open session nor close a peer's transport, and its samples carry no authenticated
//! identity (`server/src/zenoh_bridge/revocation.rs` says why): what the server can do is name, on the audit log,
//! every peer the reload revoked, those still connected at once and those connecting later as they come.

use std::future::IntoFuture;
use std::path::Path;
use std::time::Instant;

use dmp_proto::zenoh_session::{SessionOptions, ZenohTls, session_config};
use dmp_tests::within;

use super::audit_log::{capture, lines_with};
use super::{secured_cell_a, until};

/// A peer connecting to `locator` with the certificate of `identity`.
async fn peer(set: &Path, locator: &str, identity: &str) -> zenoh::Session {
    let mut options = SessionOptions::loopback_peer(vec![locator.to_owned()]);
    options.listen = Some(Vec::new());
    options.tls = Some(ZenohTls {
        root_ca: set.join("ca.pem"),
        cert: set.join(format!("{identity}.pem")),
        key: set.join(format!("{identity}.key")),
        mutual: true,
    });
    let mut config = session_config(&options).unwrap();
    config.insert_json5("connect/timeout_ms", "2000").unwrap();
    within("open", zenoh::open(config).into_future()).await.unwrap()
}

/// Removes `identity`'s block from the access file of `set`.
fn remove_identity(set: &Path, identity: &str) {
    let path = set.join("access.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let needle = format!("name = \"{identity}\"");
    let kept: Vec<&str> = text.split("[[identity]]").filter(|block| !block.contains(&needle)).collect();
    std::fs::write(&path, kept.join("[[identity]]")).unwrap();
}

#[tokio::test(flavor = "multi_thread")]
async fn a_reload_names_the_revoked_zenoh_peers_within_a_second_open_and_new() {
    capture();
    let set = tempfile::tempdir().unwrap();
    let data = tempfile::tempdir().unwrap();
    let (h, locator, _) = secured_cell_a(set.path(), data.path(), &["revoking-bot"]).await;
    let eyes = peer(set.path(), &locator, "perception").await;
    let observer = peer(set.path(), &locator, "observer").await;
    let zid = |s: &zenoh::Session| format!("zid={}", s.zid());

    remove_identity(set.path(), "perception");
    let reloaded = Instant::now();
    h.reload_access().unwrap();
    let open = ["action=zenoh session", "identity=perception", &zid(&eyes)];
    until("the open session is audited", || !lines_with(&open).is_empty()).await;
    let took = reloaded.elapsed();
    eprintln!("revoked open session audited {took:?} after the reload");
    assert!(took.as_secs_f64() < 1.0, "{took:?}");
    let line = &lines_with(&open)[0];
    assert!(line.contains("level=WARN") && line.contains("common_name=perception"), "{line}");
    assert!(line.contains("until the server restarts"), "{line}");
    // The observer, still in the file, is not named.
    assert!(lines_with(&[&zid(&observer)]).is_empty());

    // A new session of the revoked identity (its certificate is still the CA's) is named as it connects.
    let again = peer(set.path(), &locator, "perception").await;
    let again_zid = format!("zid {}", again.zid());
    let new = ["action=zenoh session", "identity=perception", "a new session connected", &again_zid];
    until("the new session is audited", || !lines_with(&new).is_empty()).await;

    for s in [eyes, observer, again] {
        within("close", s.close().into_future()).await.unwrap();
    }
    within("shutdown", h.shutdown()).await.unwrap();
}
