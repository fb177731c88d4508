//! `dmpctl`'s messages for the mistakes a newcomer makes, each naming the fix: a semicolon-separated CSV, times in
//! nanoseconds, `NaN` in JSON, `http://` to a TLS server, a `tcp/` Zenoh endpoint against a `tls/` one. None names a
//! source file.

use clap::Parser;
use dmp_server::access::init::{InitOptions, init};
use dmp_tests::{TestServer, secure, within};
use dmpctl::DmpctlError;
use dmpctl::cli::{Cli, run_async};

/// Runs `dmpctl ARGS...` in-process (under the tests' timeout); the error's message, as `dmpctl` prints it.
async fn fails(args: &[&str]) -> String {
    let mut all = vec!["dmpctl"];
    all.extend_from_slice(args);
    let cli = Cli::try_parse_from(&all).unwrap_or_else(|e| panic!("{all:?}: {e}"));
    let e: DmpctlError =
        within(&all.join(" "), run_async(cli)).await.map(|ok| panic!("{all:?}: {ok}")).unwrap_err();
    let message = dmp_client::without_source_paths(&e.to_string());
    assert_eq!(message, e.to_string(), "a source location in the message");
    assert!(!message.contains(".cargo/registry") && !message.contains(".rs:"), "{message}");
    message
}

#[tokio::test(flavor = "multi_thread")]
async fn files_in_the_wrong_form_are_named_with_the_fix() {
    let server = TestServer::grpc_only().await;
    let url = server.url();
    let dir = tempfile::tempdir().unwrap();
    let file = |name: &str, text: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        p.to_str().unwrap().to_string()
    };
    let learn = |csv: String| {
        [
            "--server".to_string(),
            url.clone(),
            "learn".into(),
            "--robot".into(),
            "r".into(),
            "--name".into(),
            "p".into(),
            "--csv".into(),
            csv,
        ]
    };

    let semicolons = file("semi.csv", "t;x1;x2\n0;0;0\n0,5;0,5;0,5\n1;1;1\n");
    let args = learn(semicolons);
    let e = fails(&args.iter().map(String::as_str).collect::<Vec<_>>()).await;
    assert!(
        e.contains("semi.csv: line 1: the delimiter must be a comma; this line is separated by `;`"),
        "{e}"
    );

    let nanoseconds =
        file("ns.csv", "t,x1\n1795000000000000000,0\n1795000000500000000,0.5\n1795000001000000000,1\n");
    let args = learn(nanoseconds);
    let e = fails(&args.iter().map(String::as_str).collect::<Vec<_>>()).await;
    assert!(
        e.contains("ns.csv: line 2, column 1: the times look like nanoseconds since the Unix epoch"),
        "{e}"
    );

    let nan = file("nan.json", "{\"id\": \"ball\",\n \"center\": [0.5, NaN],\n \"semi_axes\": [0.1, 0.1]}\n");
    let e = fails(&["--server", &url, "scene", "put", &nan]).await;
    assert!(
        e.contains("nan.json:2:")
            && e.contains("center[1]: `NaN` is not a number in JSON (JSON has no NaN or Infinity)"),
        "{e}"
    );
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread")]
async fn plaintext_against_tls_says_use_tls() {
    let set = tempfile::tempdir().unwrap();
    let options =
        InitOptions { cells: vec!["cell-a".into()], robots: vec!["panda-1".into()], ..Default::default() };
    within("init", async { init(set.path(), &options) }).await.unwrap();
    let server = TestServer::start_with(|c| {
        c.cell = "cell-a".into();
        secure(c, set.path());
    })
    .await;
    let grpc = server.handle().grpc_addr;
    let e = fails(&["--server", &format!("http://{grpc}"), "info"]).await;
    assert!(e.contains(&format!("speaks TLS: use https://{grpc}")), "{e}");

    let locator = server
        .handle()
        .zenoh_locators
        .iter()
        .find(|l| l.starts_with("tls/"))
        .expect("a tls/ locator")
        .clone();
    let plain = locator.replacen("tls/", "tcp/", 1);
    let ball = set.path().join("ball.json");
    std::fs::write(&ball, r#"{"id": "ball", "center": [0.5, 0.5], "semi_axes": [0.1, 0.1]}"#).unwrap();
    let e = fails(&[
        "--cell",
        "cell-a",
        "--zenoh-connect",
        &plain,
        "scene",
        "put",
        ball.to_str().unwrap(),
        "--via",
        "zenoh",
        "--wait-s",
        "0",
    ])
    .await;
    let addr = locator.trim_start_matches("tls/");
    assert!(e.contains(&format!("{addr} listens with TLS")) && e.contains(&format!("tls/{addr}")), "{e}");
    server.stop().await;
}
