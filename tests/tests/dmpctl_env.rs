//! `dmpctl` reads `DMP_SERVER` and `DMP_CELL` from the environment where `--server` and `--cell` are not given, and
//! a flag beats its variable. Each `dmpctl` runs in a child process of this test binary, with its own environment.

use clap::Parser;
use dmp_tests::{TestServer, within};
use dmpctl::cli::{Cli, run_async};

/// The variable that makes [`child`] run `dmpctl` with its arguments (separated by `\x1f`).
const CHILD_ARGS: &str = "DMPCTL_ENV_TEST_ARGS";

/// In a child process only: runs `dmpctl` with the arguments of [`CHILD_ARGS`] and the environment it was given;
/// exits 0 on success, else 1 with the error on stderr.
#[test]
fn child() {
    let Ok(args) = std::env::var(CHILD_ARGS) else { return };
    let mut all = vec!["dmpctl"];
    all.extend(args.split('\x1f'));
    let cli = Cli::try_parse_from(&all).unwrap_or_else(|e| panic!("{all:?}: {e}"));
    let runtime = tokio::runtime::Runtime::new().unwrap();
    if let Err(e) = runtime.block_on(within(&all.join(" "), run_async(cli))) {
        eprintln!("DMPCTL ERROR: {e}");
        std::process::exit(1);
    }
}

/// Runs `dmpctl ARGS` in a child process with the variables `env`; its success, and its stderr.
async fn dmpctl(env: &[(&str, &str)], args: &[&str]) -> (bool, String) {
    let mut command = std::process::Command::new(std::env::current_exe().unwrap());
    command.args(["--exact", "child", "--nocapture", "--test-threads", "1"]);
    command.env_remove("DMP_SERVER").env_remove("DMP_CELL").env(CHILD_ARGS, args.join("\x1f"));
    for (k, v) in env {
        command.env(k, v);
    }
    let out =
        within("dmpctl child", tokio::task::spawn_blocking(move || command.output())).await.unwrap().unwrap();
    (out.status.success(), String::from_utf8_lossy(&out.stderr).into_owned())
}

#[tokio::test(flavor = "multi_thread")]
async fn the_server_and_the_cell_come_from_the_environment_unless_flags_say_otherwise() {
    let server = TestServer::grpc_only().await;
    let url = server.url();
    let dir = tempfile::tempdir().unwrap();
    let obstacle = dir.path().join("ball.json");
    std::fs::write(
        &obstacle,
        r#"{"id": "ball", "center": [0.5, 0.5], "semi_axes": [0.1, 0.1], "exponents": [1, 1]}"#,
    )
    .unwrap();
    let file = obstacle.to_str().unwrap();
    let env = [("DMP_SERVER", url.as_str()), ("DMP_CELL", "bench")];
    let (ok, err) = dmpctl(&env, &["scene", "put", file]).await;
    assert!(ok, "{err}");
    let client = server.client().await;
    let bench = within("list", client.clone().with_cell("bench").list_obstacles()).await.unwrap();
    assert_eq!(bench.obstacles.len(), 1, "DMP_CELL names the cell the obstacle went to");
    assert!(within("list", client.list_obstacles()).await.unwrap().obstacles.is_empty());

    // A flag beats its variable.
    let (ok, err) = dmpctl(&env, &["--cell", "other", "scene", "put", file]).await;
    assert!(ok, "{err}");
    let other = within("list", client.clone().with_cell("other").list_obstacles()).await.unwrap();
    assert_eq!(other.obstacles.len(), 1);

    // DMP_SERVER is where dmpctl goes: a server that is not there fails, naming its address.
    let (ok, err) = dmpctl(&[("DMP_SERVER", "http://127.0.0.1:9")], &["scene", "put", file]).await;
    assert!(!ok && err.contains("127.0.0.1:9"), "{err}");
    let (ok, err) =
        dmpctl(&[("DMP_SERVER", "http://127.0.0.1:9")], &["--server", &url, "scene", "put", file]).await;
    assert!(ok, "{err}");
    server.stop().await;
}
