//! `dmpctl plan` and `dmpctl stream` gate on the server's verdict as `scenario run` and `sim` gate on theirs: exit
//! code 3 for a collision (unless `--allow-collision`), a stall, a missed goal or a braking stop, with the reason on
//! stderr; 0 for a run that reached its goal.

use clap::Parser;
use dmp_proto::v1;
use dmp_tests::{TestServer, within};
use dmpctl::DmpctlError;
use dmpctl::cli::{Cli, run_async};

/// Runs `dmpctl --server URL ARGS...` (under the tests' timeout).
async fn run_at(url: &str, args: &[&str]) -> Result<String, DmpctlError> {
    let mut all = vec!["dmpctl", "--server", url];
    all.extend_from_slice(args);
    let cli = Cli::try_parse_from(&all).unwrap_or_else(|e| panic!("{all:?}: {e}"));
    within(&all.join(" "), run_async(cli)).await
}

/// A thin wall across the straight line from (0, 0) to (1, 0).
fn wall() -> v1::Obstacle {
    v1::Obstacle {
        id: "wall".into(),
        shape: Some(v1::obstacle::Shape::Superquadric(v1::Superquadric {
            semi_axes: vec![0.05, 0.5],
            exponents: vec![4.0, 4.0],
        })),
        center: vec![0.5, 0.0],
        ..Default::default()
    }
}

#[tokio::test(flavor = "multi_thread")]
async fn plan_and_stream_exit_3_on_a_collision_or_a_missed_goal_and_0_at_the_goal() {
    let server = TestServer::grpc_only().await;
    let url = server.url();
    let client = server.client().await;
    let line =
        dmp::Primitive::straight_line(50, 4.0, vec![3050.0; 2], None, 1.0, vec![0.0, 0.0], vec![1.0, 0.0])
            .unwrap();
    within("put", client.put_primitive("r", "line", &line)).await.unwrap();
    within("wall", client.put_obstacle(wall())).await.unwrap();
    let dir = tempfile::tempdir().unwrap();
    let d = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let plan = |out: String, extra: &[&str]| {
        // The DMP's own timing (no limits): the line arrives well within 3 s.
        let mut args: Vec<String> =
            ["plan", "--robot", "r", "--name", "line", "--duration-s", "3", "--no-limits", "--out"]
                .map(String::from)
                .to_vec();
        args.push(out);
        args.extend(extra.iter().map(|s| s.to_string()));
        args
    };

    // Straight through the wall: exit 3, the collision named, the outputs written all the same.
    let args = plan(d("through"), &["--avoidance", "none"]);
    let e = run_at(&url, &args.iter().map(String::as_str).collect::<Vec<_>>()).await.unwrap_err();
    assert_eq!(e.exit_code(), 3, "{e}");
    let DmpctlError::Problems { summary, problems } = &e else { panic!("{e}") };
    assert!(summary.contains("collisions: wall") && summary.contains("verdict COLLISION"), "{summary}");
    assert!(
        problems
            .iter()
            .any(|p| p.contains("collision with obstacle 'wall'") && p.contains("--allow-collision")),
        "{problems:?}"
    );
    assert!(dir.path().join("through/trajectory.csv").exists());
    // Allowed, the collision is no problem; the line still reaches its goal beyond the wall.
    let args = plan(d("allowed"), &["--avoidance", "none", "--allow-collision"]);
    let said = run_at(&url, &args.iter().map(String::as_str).collect::<Vec<_>>()).await.unwrap();
    assert!(said.contains("verdict COLLISION"), "{said}");

    // Without the wall (the scene ignored), at the goal and at rest: exit 0.
    let args =
        plan(d("free"), &["--ignore-scene", "--goal-tolerance", "0.01", "--goal-speed-tolerance", "0.1"]);
    let said = run_at(&url, &args.iter().map(String::as_str).collect::<Vec<_>>()).await.unwrap();
    assert!(said.contains("collisions: none") && said.contains("verdict GOAL_REACHED"), "{said}");

    // Too short for its goal: exit 3, out of time, the distance on stderr.
    let short = ["plan", "--robot", "r", "--name", "line", "--ignore-scene", "--duration-s", "0.3", "--out"];
    let mut args = short.to_vec();
    let out = d("short");
    args.push(&out);
    let e = run_at(&url, &args).await.unwrap_err();
    assert_eq!(e.exit_code(), 3, "{e}");
    assert!(
        e.to_string().contains("goal not reached: ended ") && e.to_string().contains("OUT_OF_TIME"),
        "{e}"
    );

    // A stream towards the wall at the server's defaults: it brakes before the safety distance and is held there to
    // the end: exit 3, blocked, no collision.
    let stream = ["stream", "--robot", "r", "--name", "line", "--avoidance", "none", "--out"];
    let mut args = stream.to_vec();
    let out = d("stream");
    args.push(&out);
    let e = run_at(&url, &args).await.unwrap_err();
    assert_eq!(e.exit_code(), 3, "{e}");
    let DmpctlError::Problems { summary, problems } = &e else { panic!("{e}") };
    assert!(summary.contains("verdict BLOCKED") && !summary.contains("collisions: wall"), "{summary}");
    assert!(problems.iter().any(|p| p.contains("held before an obstacle's safety distance")), "{problems:?}");
    // Without limits or margin: through the wall, exit 3 with the collision, not "last status STOPPED" and 0.
    let mut args = stream.to_vec();
    let out = d("stream-through");
    args.push(&out);
    args.push("--no-limits");
    let e = run_at(&url, &args).await.unwrap_err();
    assert_eq!(e.exit_code(), 3, "{e}");
    let DmpctlError::Problems { summary, problems } = &e else { panic!("{e}") };
    assert!(summary.contains("collisions: wall (") && summary.contains("COLLISION segments"), "{summary}");
    assert!(problems.iter().any(|p| p.contains("collision with obstacle 'wall'")), "{problems:?}");
    server.stop().await;
}
