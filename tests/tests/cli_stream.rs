//! `dmpctl stream` against the real server: the summary names each warning by kind, and the changes made during
//! a stream (a schedule of `--goal-at`, `--tau-at`, `--stop-at`, or commands on stdin) reach the run.

use clap::Parser;
use dmp_proto::v1;
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

/// The summary line of a stream, whether it ended well (exit 0) or with problems (exit 3).
fn summary(r: Result<String, DmpctlError>) -> String {
    match r {
        Ok(line) => line,
        Err(DmpctlError::Problems { summary, .. }) => summary,
        Err(e) => panic!("{e}"),
    }
}

/// Learns `r/p`, a 2-D straight line from (0, 0) to (1, 1) over 1 s, through `dmpctl learn`.
async fn learn_line(url: &str, dir: &std::path::Path) {
    let csv: String = std::iter::once("t,x1,x2".to_string())
        .chain((0..=100).map(|k| {
            let t = k as f64 / 100.0;
            format!("{t},{t},{t}")
        }))
        .collect::<Vec<_>>()
        .join("\n");
    let path = dir.join("line.csv");
    std::fs::write(&path, csv).unwrap();
    run_at(url, &["learn", "--robot", "r", "--name", "p", "--csv", path.to_str().unwrap()]).await.unwrap();
}

#[tokio::test(flavor = "multi_thread")]
async fn the_summary_names_each_warning_by_kind() {
    let server = TestServer::grpc_only().await;
    let url = server.url();
    let dir = tempfile::tempdir().unwrap();
    learn_line(&url, dir.path()).await;
    // A 3-D obstacle in a 2-D robot's cell: the robot cannot use it, and says so.
    let ball = v1::Obstacle {
        id: "ball3".into(),
        shape: Some(v1::obstacle::Shape::Superquadric(v1::Superquadric {
            semi_axes: vec![0.1, 0.1, 0.1],
            exponents: vec![1.0, 1.0, 1.0],
        })),
        center: vec![5.0, 5.0, 5.0],
        ..Default::default()
    };
    within("put", server.client().await.put_obstacle(ball)).await.unwrap();
    let out = dir.path().join("out");
    let said = summary(
        run_at(&url, &["stream", "--robot", "r", "--name", "p", "--quiet", "--out", out.to_str().unwrap()])
            .await,
    );
    assert!(said.contains("warnings: 1 (1 obstacle ignored: `ball3`"), "{said}");
    server.stop().await;
}
