//! `scenario run --server`: the offline experiments computed by the real server (gRPC only) give the offline
//! metrics and files.

use std::path::Path;

use dmp_client::DmpClient;
use dmp_tests::{TestServer, within};
use dmpctl::offline::run_scenario;
use dmpctl::scenario_file::load_scenario;
use dmpctl::scenario_through_server::{robot_ids, run_scenario_through_server, scenario_robot};

/// Runs `file` offline and through the server (plans and group runs step through the same `dmp::Execution` as the
/// offline rollout): the metrics must be the same, `compute_seconds` aside, and the trajectories agree to the bit
/// (`trajectory.csv` writes every position, velocity and acceleration as its shortest round-trip decimal, so equal
/// text is equal bits).
async fn same_metrics(client: &DmpClient, file: &str) -> Vec<String> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios").join(file);
    same_metrics_at(client, &path).await.1
}

/// Returns the offline metrics and the notes of the run through the server.
async fn same_metrics_at(client: &DmpClient, path: &Path) -> (dmp::metrics::Metrics, Vec<String>) {
    let file = path.display();
    let dir = tempfile::tempdir().unwrap();
    let offline = run_scenario(path, &dir.path().join("offline")).unwrap();
    let through_server = within(
        &format!("scenario run {file}"),
        run_scenario_through_server(client, path, &dir.path().join("through-server"), false),
    )
    .await
    .unwrap();
    // The run's robots (`scenario.<name>...`) have no primitive left.
    for robot in robot_ids(&load_scenario(path).unwrap()) {
        assert!(robot.starts_with("scenario."), "{robot}");
        assert!(within("list", client.list(&robot)).await.unwrap().is_empty(), "{robot} is left");
    }
    let (mut a, mut b) = (offline.metrics, through_server.metrics);
    a.compute_seconds = 0.0;
    b.compute_seconds = 0.0;
    assert_eq!(a, b, "{file}");
    for f in ["trajectory.csv", "metrics.json", "plot.svg"] {
        assert!(dir.path().join("through-server").join(f).exists(), "{f}");
    }
    let csv = |d: &str| std::fs::read_to_string(dir.path().join(d).join("trajectory.csv")).unwrap();
    assert_eq!(csv("offline"), csv("through-server"), "{file}");
    (a, through_server.notes)
}

#[tokio::test(flavor = "multi_thread")]
async fn stalls_are_reported_as_offline() {
    // 1-D: a wall on the only way to the goal, a local minimum.
    let t: Vec<f64> = (0..=100).map(|k| k as f64 / 100.0).collect();
    let x: Vec<Vec<f64>> = t.iter().map(|t| vec![*t]).collect();
    let s = serde_json::json!({
        "name": "stall 1d", "demonstration": {"t": t, "x": x}, "dmp": {"N": 10, "K": 1050, "alpha": 4},
        "rollout": {"dt": 0.001, "duration": 2.0},
        "obstacles": [{"id": "wall", "center": [0.5], "semi_axes": [0.1]}],
        "avoidance": {"method": "static_volumetric", "A": 10, "eta": 1}
    });
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("stall.json");
    std::fs::write(&file, s.to_string()).unwrap();
    let server = TestServer::grpc_only().await;
    let (metrics, _) = same_metrics_at(&server.client().await, &file).await;
    assert_eq!(metrics.stalls.len(), 1);
    server.stop().await;
}

/// `--keep` keeps the run's primitive; without it, the next run deletes every version of its robot's.
#[tokio::test(flavor = "multi_thread")]
async fn the_runs_primitives_are_deleted_unless_kept() {
    let server = TestServer::grpc_only().await;
    let client = server.client().await;
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/paper-one-obstacle/none.json");
    let dir = tempfile::tempdir().unwrap();
    let robot = scenario_robot("paper-one-obstacle-none");
    assert_eq!(robot, "scenario.paper-one-obstacle-none");
    let run = |keep| run_scenario_through_server(&client, &path, dir.path(), keep);
    within("scenario run --keep", run(true)).await.unwrap();
    let kept = within("list", client.list(&robot)).await.unwrap();
    assert_eq!(kept.iter().map(|r| r.name.as_str()).collect::<Vec<_>>(), ["paper-one-obstacle-none"]);
    within("scenario run", run(false)).await.unwrap();
    assert!(within("list", client.list(&robot)).await.unwrap().is_empty());
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread")]
async fn single_robot_scenarios_give_the_offline_metrics() {
    let server = TestServer::grpc_only().await;
    let client = server.client().await;
    for m in
        ["none", "static_point", "dynamic_point", "steering_angle", "static_volumetric", "dynamic_volumetric"]
    {
        let notes = same_metrics(&client, &format!("paper-one-obstacle/{m}.json")).await;
        assert!(notes.is_empty(), "{notes:?}");
    }
    same_metrics(&client, "moving-obstacle-dynamic-volumetric.json").await;
    same_metrics(&client, "paper-two-obstacles-steering-angle.json").await;
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread")]
async fn group_scenarios_give_the_offline_metrics() {
    let server = TestServer::grpc_only().await;
    let notes = same_metrics(&server.client().await, "youbots-three-dynamic.json").await;
    assert!(notes.is_empty(), "{notes:?}");
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread")]
async fn a_bad_scenario_is_refused_before_the_server_is_asked() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("bad.json");
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/paper-one-obstacle/none.json");
    let mut v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(src).unwrap()).unwrap();
    v["rollout"]["dt"] = 0.0.into();
    std::fs::write(&file, v.to_string()).unwrap();
    let server = TestServer::grpc_only().await;
    let client = server.client().await;
    let e =
        within("scenario run", run_scenario_through_server(&client, &file, &dir.path().join("out"), false))
            .await
            .unwrap_err();
    assert!(e.is_bad_input() && e.to_string().contains("rollout.dt"), "{e}");
    // Nothing reached the server: no primitive was learned.
    assert!(
        within("list", client.list(&scenario_robot("paper-one-obstacle-none"))).await.unwrap().is_empty()
    );
    assert!(!dir.path().join("out").exists());
    server.stop().await;
}
