//! `dmpctl scene put --via zenoh` against the real server: it waits until the server's scene shows what it
//! published, and exits non-zero naming the obstacle and why when the server did not apply it.

use clap::Parser;
use dmp_tests::{TestServer, within};
use dmpctl::DmpctlError;
use dmpctl::cli::{Cli, run_async};

/// Runs `dmpctl --server URL ARGS...` in-process (under the tests' timeout).
async fn run_at(url: &str, args: &[&str]) -> Result<String, DmpctlError> {
    let mut all = vec!["dmpctl", "--server", url];
    all.extend_from_slice(args);
    let cli = Cli::try_parse_from(&all).unwrap_or_else(|e| panic!("{all:?}: {e}"));
    within(&all.join(" "), run_async(cli)).await
}

#[tokio::test(flavor = "multi_thread")]
async fn a_zenoh_put_is_confirmed_by_the_servers_scene_or_fails_naming_why() {
    let server = TestServer::start().await;
    let url = server.url();
    let dir = tempfile::tempdir().unwrap();
    let file = |name: &str, json: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, json).unwrap();
        p.to_str().unwrap().to_string()
    };
    let ball = file("ball.json", r#"{"id": "ball", "center": [0.5, 0.5], "semi_axes": [0.1, 0.1]}"#);
    let said = run_at(&url, &["scene", "put", &ball, "--via", "zenoh"]).await.unwrap();
    assert!(said.contains("published `ball`") && said.contains("the server's scene shows them"), "{said}");
    let listed = within("list", server.client().await.list_obstacles()).await.unwrap();
    assert_eq!(listed.obstacles.len(), 1);

    // Moved: the scene shows the new centre, not only the id.
    let moved = file("moved.json", r#"{"id": "ball", "center": [0.6, 0.5], "semi_axes": [0.1, 0.1]}"#);
    run_at(&url, &["scene", "put", &moved, "--via", "zenoh"]).await.unwrap();

    // A centre far beyond the server's workspace: valid JSON, refused by the server; the command says so.
    let far = file("far.json", r#"{"id": "far", "center": [0, 1e9], "semi_axes": [0.1, 0.1]}"#);
    let e = run_at(&url, &["scene", "put", &far, "--via", "zenoh", "--wait-s", "1"]).await.unwrap_err();
    assert!(matches!(e, DmpctlError::NotApplied(_)) && e.exit_code() == 1, "{e}");
    let e = e.to_string();
    assert!(
        e.contains("`far` was published but did not show in the server's scene within 1 s")
            && e.contains("center[1] = 1000000000 is outside the server's workspace"),
        "{e}"
    );
    // --wait-s 0: published without confirming, as before.
    let said = run_at(&url, &["scene", "put", &far, "--via", "zenoh", "--wait-s", "0"]).await.unwrap();
    assert!(said.contains("published `far`") && !said.contains("shows"), "{said}");
    server.stop().await;
}
