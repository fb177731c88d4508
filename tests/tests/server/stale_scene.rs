//! A scene that goes stale or vanishes: `stale_after_s` with each policy, the scene service's health following the
//! configured Zenoh router, and a damaged store file refused at start. (Catching up with obstacles published
//! before a start: `catch_up.rs`.)

use std::collections::BTreeMap;
use std::future::IntoFuture;
use std::path::Path;

use dmp_client::zenoh_pub::ObstaclePublisher;
use dmp_proto::v1;
use dmp_proto::zenoh_session::locators;
use dmp_server::config::Config;
use dmp_server::config::scene::{CellSceneConfig, StalePolicy};
use dmp_server::server::{ServerHandle, start};
use dmp_tests::{T, config, within};
use tokio_stream::StreamExt;
use tonic_health::pb::HealthCheckRequest;
use tonic_health::pb::health_check_response::ServingStatus;
use tonic_health::pb::health_client::HealthClient;

use crate::{ellipse, line, spec, until};

pub(crate) fn has_obstacle(handle: &ServerHandle, cell: &str, id: &str) -> bool {
    handle.cells().get(cell).unwrap().snapshot().obstacles.contains_key(id)
}

pub(crate) async fn start_connected(dir: &Path, connect: Vec<String>) -> ServerHandle {
    let mut c = config(dir);
    c.zenoh.connect = connect;
    within("server start", start(c)).await.expect("server starts")
}

/// A Zenoh router in the test process on `endpoint` (multicast off).
pub(crate) async fn router(endpoint: &str) -> zenoh::Session {
    let mut c = zenoh::Config::default();
    c.insert_json5("mode", "\"router\"").unwrap();
    c.insert_json5("listen/endpoints", &format!("[\"{endpoint}\"]")).unwrap();
    c.insert_json5("scouting/multicast/enabled", "false").unwrap();
    c.insert_json5("scouting/gossip/enabled", "false").unwrap();
    within("router open", zenoh::open(c).into_future()).await.unwrap()
}

async fn scene_health(client: &mut HealthClient<tonic::transport::Channel>) -> ServingStatus {
    let request = HealthCheckRequest { service: "dmp.v1.SceneService".into() };
    let status = within("health check", client.check(request)).await.unwrap().into_inner().status;
    ServingStatus::try_from(status).unwrap()
}

async fn until_health(client: &mut HealthClient<tonic::transport::Channel>, want: ServingStatus) {
    within("health status", async {
        while scene_health(client).await != want {
            tokio::time::sleep(std::time::Duration::from_millis(20)).await;
        }
    })
    .await
}

#[tokio::test(flavor = "multi_thread")]
async fn the_scene_is_not_serving_while_the_configured_router_is_unreachable() {
    let first = router("tcp/127.0.0.1:0").await;
    let endpoint = locators(&first).await[0].clone();
    let dir = tempfile::tempdir().unwrap();
    let handle = start_connected(dir.path(), vec![endpoint.clone()]).await;
    let endpoint_url =
        tonic::transport::Endpoint::from_shared(format!("http://{}", handle.grpc_addr)).unwrap();
    let channel = within("connect", endpoint_url.connect()).await.unwrap();
    let mut health = HealthClient::new(channel);
    assert_eq!(scene_health(&mut health).await, ServingStatus::Serving);

    within("router close", first.close().into_future()).await.unwrap();
    until_health(&mut health, ServingStatus::NotServing).await;
    // The other services are not concerned.
    let other = HealthCheckRequest { service: "dmp.v1.PrimitiveService".into() };
    let status = within("health check", health.check(other)).await.unwrap().into_inner().status;
    assert_eq!(status, ServingStatus::Serving as i32);

    // Back on the same port: Zenoh reconnects, and the scene serves again.
    let second = router(&endpoint).await;
    until_health(&mut health, ServingStatus::Serving).await;

    within("shutdown", handle.shutdown()).await.unwrap();
    within("router close", second.close().into_future()).await.unwrap();
}

/// A server whose obstacles go stale after 0.3 s: the default cell stops its robots, cell `keep` keeps (flags) and
/// cell `drop` drops them.
fn stale_config(c: &mut Config) {
    c.scene.stale_after_s = 0.3;
    c.scene.stale_policy = StalePolicy::Stop;
    c.scene.cells = BTreeMap::from([
        ("keep".into(), CellSceneConfig { stale_after_s: None, stale_policy: Some(StalePolicy::Keep) }),
        ("drop".into(), CellSceneConfig { stale_after_s: None, stale_policy: Some(StalePolicy::Drop) }),
    ]);
}

#[tokio::test(flavor = "multi_thread")]
async fn stale_obstacles_are_kept_and_flagged_or_dropped() {
    let dir = tempfile::tempdir().unwrap();
    let mut c = config(dir.path());
    stale_config(&mut c);
    let handle = within("server start", start(c)).await.unwrap();
    let perception =
        within("zenoh open", ObstaclePublisher::open("keep", &handle.zenoh_locators, &[])).await.unwrap();
    within("subscriber", perception.wait_for_subscriber(T)).await.unwrap();
    let mut moving = ellipse("o", vec![0.5, 0.5], vec![0.1, 0.1]);
    moving.velocity = vec![1.0, 0.0];
    within("put keep", perception.put_proto_in("keep", &moving)).await.unwrap();
    within("put drop", perception.put_proto_in("drop", &moving)).await.unwrap();
    until("put", || has_obstacle(&handle, "keep", "o") && has_obstacle(&handle, "drop", "o")).await;

    let keep = handle.cells().get("keep").unwrap();
    until("flagged stale", || keep.snapshot().stale_ids().any(|id| id == "o")).await;
    assert!(has_obstacle(&handle, "keep", "o"), "kept");
    // Frozen: a moving obstacle without a ttl does not drift on.
    let frozen = keep.snapshot().obstacles["o"].proto_at(0.0).center.clone();
    let later = keep.snapshot().obstacles["o"].proto_at(1.0e9).center.clone();
    assert_eq!(frozen, later);
    until("dropped", || !has_obstacle(&handle, "drop", "o")).await;

    // An update makes it fresh again.
    within("refresh", perception.put_proto_in("keep", &moving)).await.unwrap();
    until("fresh", || keep.snapshot().stale_ids().next().is_none()).await;
    within("shutdown", handle.shutdown()).await.unwrap();
    within("close", perception.close()).await.unwrap();
}

#[tokio::test(flavor = "multi_thread")]
async fn a_stale_scene_under_stop_holds_the_robot_until_fresh_data_arrives() {
    let dir = tempfile::tempdir().unwrap();
    let mut c = config(dir.path());
    stale_config(&mut c);
    let handle = within("server start", start(c)).await.unwrap();
    let client =
        within("connect", dmp_client::grpc::DmpClient::connect(format!("http://{}", handle.grpc_addr)))
            .await
            .unwrap();
    within("put", client.put_primitive("youbot", "corridor", &line(vec![0.0, 0.0], vec![1.0, 0.0], 1.0)))
        .await
        .unwrap();
    let perception =
        within("zenoh open", ObstaclePublisher::open("default", &handle.zenoh_locators, &[])).await.unwrap();
    within("subscriber", perception.wait_for_subscriber(T)).await.unwrap();
    // Out of the robot's way: what matters is that nobody updates it.
    within("put", perception.put_proto(&ellipse("far", vec![0.5, 0.9], vec![0.05, 0.05]))).await.unwrap();
    until("put", || has_obstacle(&handle, "default", "far")).await;

    let request = v1::ExecuteRequest {
        motion: Some(spec("youbot", "corridor")),
        pacing: v1::Pacing::Realtime as i32,
        max_duration_s: 6.0,
        ..Default::default()
    };
    let mut stream = within("execute", client.execute(request)).await.unwrap();
    let mut next = async || within("segment", stream.next()).await.expect("a segment").unwrap();
    // Until the scene goes stale: that segment carries the one warning.
    let first_stale = loop {
        let s = next().await;
        if s.scene_stale {
            break s;
        }
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    };
    let kinds: Vec<_> = first_stale.warnings.iter().map(|w| (w.kind, w.obstacle_id.as_str())).collect();
    assert_eq!(kinds, [(v1::warning::Kind::SceneStale as i32, "far")]);
    // The robot decelerates and holds where it is, short of the goal.
    let held = loop {
        let s = next().await;
        assert!(s.scene_stale && s.warnings.is_empty(), "stale once, warned once");
        if s.velocities.iter().all(|v| v.abs() < 1e-6) {
            break s;
        }
    };
    let at = held.positions[held.positions.len() - 2];
    assert!(at < 0.9, "held at x = {at}");
    for _ in 0..5 {
        let s = next().await;
        assert!(s.scene_stale && s.velocities.iter().all(|v| v.abs() < 1e-6), "still holding");
        assert!((s.positions[s.positions.len() - 2] - at).abs() < 1e-6);
    }

    // Fresh data (here: the node removes the stale obstacle): the robot goes on to its goal.
    within("delete", perception.delete("far")).await.unwrap();
    let mut last = next().await;
    while let Some(s) = within("segment", stream.next()).await {
        last = s.unwrap();
    }
    assert!(!last.scene_stale);
    assert_eq!(last.status, v1::SegmentStatus::GoalReached as i32, "ended with {:?}", last.status);
    within("shutdown", handle.shutdown()).await.unwrap();
    within("close", perception.close()).await.unwrap();
}

#[tokio::test(flavor = "multi_thread")]
async fn an_empty_or_truncated_store_file_is_refused_with_how_to_start_fresh() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join(dmp_server::store::FILE_NAME);
    std::fs::write(&file, b"").unwrap();
    let e = within("start", start(config(dir.path()))).await.unwrap_err().to_string();
    assert!(e.contains("move it away or delete it to start with an empty store"), "{e}");

    std::fs::remove_file(&file).unwrap();
    let handle = within("start", start(config(dir.path()))).await.unwrap();
    let client =
        within("connect", dmp_client::grpc::DmpClient::connect(format!("http://{}", handle.grpc_addr)))
            .await
            .unwrap();
    within("put", client.put_primitive("r", "p", &line(vec![0.0], vec![1.0], 1.0))).await.unwrap();
    within("shutdown", handle.shutdown()).await.unwrap();
    let full = std::fs::read(&file).unwrap();
    std::fs::write(&file, &full[..full.len() / 2]).unwrap();
    let e = within("start", start(config(dir.path()))).await.unwrap_err().to_string();
    assert!(e.contains("move it away or delete it to start with an empty store"), "{e}");
}
