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

/// The last row of `DIR/trajectory.csv`: t, then the positions.
fn last_row(dir: &std::path::Path) -> Vec<f64> {
    let csv = std::fs::read_to_string(dir.join("trajectory.csv")).unwrap();
    csv.lines().last().unwrap().split(',').map(|c| c.parse().unwrap()).collect()
}

#[tokio::test(flavor = "multi_thread")]
async fn a_schedule_changes_the_goal_and_tau_and_stops_the_run() {
    let server = TestServer::grpc_only().await;
    let url = server.url();
    let dir = tempfile::tempdir().unwrap();
    learn_line(&url, dir.path()).await;
    let out = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let motion = ["stream", "--robot", "r", "--name", "p", "--quiet", "--no-limits"];

    let mut args = motion.to_vec();
    let goal = out("goal");
    args.extend(["--goal-at", "0.3=0.5,-0.5", "--out", &goal]);
    let said = run_at(&url, &args).await.unwrap();
    assert!(said.contains("verdict GOAL_REACHED"), "{said}");
    let last = last_row(dir.path().join("goal").as_path());
    assert!((last[1] - 0.5).abs() < 0.01 && (last[2] + 0.5).abs() < 0.01, "{last:?}");

    // tau 1 s (the demonstration's) to 3 s from t = 0.1 s: the goal is reached far later than at 1 s (the
    // maximum duration, 3 tau, is the first tau's: 10 s gives it time).
    let mut args = motion.to_vec();
    let slow = out("slow");
    args.extend(["--tau-at", "0.1=3", "--max-duration-s", "10", "--out", &slow]);
    let said = run_at(&url, &args).await.unwrap();
    let last = last_row(dir.path().join("slow").as_path());
    assert!(said.contains("verdict GOAL_REACHED") && last[0] > 2.0, "{said}\n{last:?}");

    // A stop asked for is not a problem: exit 0, the verdict says it stopped, far from the goal.
    let mut args = motion.to_vec();
    let stop = out("stop");
    args.extend(["--stop-at", "0.2", "--out", &stop]);
    let said = run_at(&url, &args).await.unwrap();
    let last = last_row(dir.path().join("stop").as_path());
    assert!(said.contains("verdict STOPPED") && last[0] < 0.8 && last[1] < 0.9, "{said}\n{last:?}");

    // A bad schedule is refused by the parser, naming the flag's form.
    let e = Cli::try_parse_from([
        "dmpctl",
        "stream",
        "--robot",
        "r",
        "--name",
        "p",
        "--out",
        &stop,
        "--goal-at",
        "1,2",
    ])
    .unwrap_err()
    .to_string();
    assert!(e.contains("T=VALUE"), "{e}");
    server.stop().await;
}

/// The variable that makes [`child`] run `dmpctl` with its arguments (separated by `\x1f`).
const CHILD_ARGS: &str = "DMPCTL_CLI_STREAM_ARGS";

/// In a child process only: runs `dmpctl` with the arguments of [`CHILD_ARGS`] (its stdin the parent's pipe);
/// prints the summary on stdout, exits 0, or 1 with the error on stderr.
#[test]
fn child() {
    let Ok(args) = std::env::var(CHILD_ARGS) else { return };
    let mut all = vec!["dmpctl"];
    all.extend(args.split('\x1f'));
    let cli = Cli::try_parse_from(&all).unwrap_or_else(|e| panic!("{all:?}: {e}"));
    let runtime = tokio::runtime::Runtime::new().unwrap();
    match runtime.block_on(within(&all.join(" "), run_async(cli))) {
        Ok(line) => println!("SUMMARY: {line}"),
        Err(e) => {
            eprintln!("DMPCTL ERROR: {e}");
            std::process::exit(1);
        }
    }
}

#[tokio::test(flavor = "multi_thread")]
async fn commands_on_stdin_change_the_run_and_a_bad_line_is_named_and_ignored() {
    use std::io::Write;
    let server = TestServer::grpc_only().await;
    let url = server.url();
    let dir = tempfile::tempdir().unwrap();
    learn_line(&url, dir.path()).await;
    let out = dir.path().join("out");
    let args = [
        "--server",
        &url,
        "stream",
        "--robot",
        "r",
        "--name",
        "p",
        "--quiet",
        "--no-limits",
        "--realtime",
        "--stdin",
        "--out",
        out.to_str().unwrap(),
    ];
    let mut command = std::process::Command::new(std::env::current_exe().unwrap());
    command.args(["--exact", "child", "--nocapture", "--test-threads", "1"]);
    command.env(CHILD_ARGS, args.join("\x1f"));
    command.stdin(std::process::Stdio::piped());
    command.stdout(std::process::Stdio::piped()).stderr(std::process::Stdio::piped());
    let mut child = command.spawn().unwrap();
    // A real-time run of 1 s: the lines arrive long before it ends. Stdin stays open: its end does not stop it.
    let mut stdin = child.stdin.take().unwrap();
    stdin.write_all(b"jump 1\n\ngoal 0.5 -0.5\n").unwrap();
    stdin.flush().unwrap();
    let out_ = within("dmpctl child", tokio::task::spawn_blocking(move || child.wait_with_output()))
        .await
        .unwrap()
        .unwrap();
    drop(stdin);
    let (stdout, stderr) = (String::from_utf8_lossy(&out_.stdout), String::from_utf8_lossy(&out_.stderr));
    assert!(out_.status.success(), "{stdout}\n{stderr}");
    assert!(stderr.contains("stdin line 1 `jump 1` ignored: unknown command `jump`"), "{stderr}");
    assert!(stdout.contains("verdict GOAL_REACHED"), "{stdout}");
    let last = last_row(&out);
    assert!((last[1] - 0.5).abs() < 0.01 && (last[2] + 0.5).abs() < 0.01, "{last:?}");
    server.stop().await;
}
