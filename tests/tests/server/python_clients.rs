//! Stock Python clients against a secured server: grpcio (TLS, a token in metadata) as a robot and eclipse-zenoh
//! (the perception config of `access init`, mutual TLS) as a perception node. The script is
//! `tests/python/stock_clients.py`; it needs the virtual environment of the README's test command
//! (`.venv`, from `tests/python/requirements.txt`), or a Python with those packages in `DMP_TEST_PYTHON`.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

use dmp_client::DmpClient;
use dmp_client::connect::{ConnectOptions, TlsOptions};
use dmp_server::access::init::{InitOptions, init};
use dmp_server::server::ServerHandle;
use dmp_tests::within;

use crate::{line, secured_cell_a, until};

pub(crate) fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap().to_owned()
}

/// The Python with grpcio, grpcio-tools and eclipse-zenoh.
pub(crate) fn python() -> PathBuf {
    let python = std::env::var_os("DMP_TEST_PYTHON")
        .map_or_else(|| workspace().join(".venv/bin/python"), PathBuf::from);
    assert!(
        python.exists(),
        "{} does not exist: the stock Python clients need the README's test command's set-up \
         (python3 -m venv .venv && .venv/bin/pip install -r tests/python/requirements.txt), or DMP_TEST_PYTHON",
        python.display()
    );
    python
}

fn in_scene(h: &ServerHandle, cell: &str, id: &str) -> bool {
    h.cells().find(cell).unwrap().is_some_and(|c| c.snapshot().obstacles.contains_key(id))
}

#[tokio::test(flavor = "multi_thread")]
async fn stock_python_clients_work_as_a_robot_and_as_perception() {
    let python = python();
    let set = tempfile::tempdir().unwrap();
    let other = tempfile::tempdir().unwrap();
    let s = set.path();
    let data = tempfile::tempdir().unwrap();
    let (h, locator, tokens) = secured_cell_a(s, data.path(), &["panda-1", "panda-2"]).await;
    init(other.path(), &InitOptions { cells: vec!["cell-a".into()], ..Default::default() }).unwrap();
    std::fs::copy(other.path().join("ca.pem"), s.join("other-ca.pem")).unwrap();

    // The admin stores the robot's primitive (the robot may only read it).
    let admin_token = tokens.iter().find(|(n, _)| n == "admin").unwrap().1.clone();
    let tls = TlsOptions::from_files(&s.join("ca.pem"), None, None).unwrap();
    let options = ConnectOptions { tls: Some(tls), token: Some(admin_token), ..Default::default() };
    let admin = within("connect", DmpClient::connect_with(&format!("https://{}", h.grpc_addr), &options))
        .await
        .unwrap();
    within("put", admin.put_primitive("panda-1", "reach", &line(vec![0.0, 0.0], vec![1.0, 0.5], 0.5)))
        .await
        .unwrap();

    let mut child = Command::new(&python)
        .env("GRPC_VERBOSITY", "ERROR")
        .arg(workspace().join("tests/python/stock_clients.py"))
        .arg(workspace().join("proto"))
        .arg(s)
        .arg(format!("127.0.0.1:{}", h.grpc_addr.port()))
        .arg(&locator)
        .args(["cell-a", "panda-1", "panda-2"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .expect("python starts");
    // The script's checks, line by line, until the perception node has published.
    let stdout = child.stdout.take().unwrap();
    let lines = tokio::task::spawn_blocking(move || {
        let mut seen = Vec::new();
        for l in BufReader::new(stdout).lines() {
            let l = l.unwrap();
            eprintln!("python: {l}");
            let done = l == "ok: perception published";
            seen.push(l);
            if done {
                break;
            }
        }
        seen
    });
    let lines =
        tokio::time::timeout(Duration::from_secs(120), lines).await.expect("python within 2 min").unwrap();
    assert_eq!(
        lines.last().map(String::as_str),
        Some("ok: perception published"),
        "the script stopped: {lines:?}"
    );
    assert!(lines.iter().all(|l| l.starts_with("ok: ")), "{lines:?}");
    assert_eq!(lines.len(), 10, "every check of the script ran: {lines:?}");

    // Its last put arrives after the others (one link, in order): the denied ones and the deleted one are absent.
    until("the perception node's obstacle arrives", || in_scene(&h, "cell-a", "py-seen")).await;
    assert!(!in_scene(&h, "cell-a", "py-gone"), "a delete over Zenoh was lost");
    assert!(!in_scene(&h, "cell-b", "py-elsewhere"), "perception of cell-a changed cell-b");
    let cell = h.cells().find("cell-a").unwrap().unwrap();
    let robots = cell.other_robots("", f64::MAX / 4.0, f64::MAX);
    assert!(
        robots.iter().all(|r| r.state.robot_id != "py-ghost"),
        "a robot state was taken from a perception node"
    );

    drop(child.stdin.take());
    let status = tokio::task::spawn_blocking(move || child.wait()).await.unwrap().unwrap();
    assert!(status.success(), "python exited with {status}");
    within("shutdown", h.shutdown()).await.unwrap();
}
