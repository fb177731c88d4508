//! Tests of the Zenoh bridge on loopback (the keys, the session's configuration and the payloads' decoding are
//! tested in `dmp_proto`).

use super::*;
use dmp_proto::keys::{obstacle_key, robot_state_key};
use dmp_proto::zenoh_session::CONNECT_TIMEOUT_MS;
use dmp_proto::{codec, v1};
use std::future::IntoFuture;
use tokio::sync::watch;
use zenoh::bytes::Encoding;
use zenoh::pubsub::Publisher;

const T: Duration = Duration::from_secs(10);

async fn within<F: IntoFuture>(what: &str, f: F) -> F::Output {
    tokio::time::timeout(T, f).await.unwrap_or_else(|_| panic!("timed out: {what}"))
}

fn loopback(connect: Vec<String>) -> ZenohConfig {
    ZenohConfig {
        disabled: false,
        mode: "peer".into(),
        listen: vec!["tcp/127.0.0.1:0".into()],
        connect,
        multicast_scouting: false,
        config_file: None,
    }
}

/// A bridge on its own session, and a second session connected to it.
struct Pair {
    server: Session,
    client: Session,
    scene: crate::cells::cell::Cell,
    bridge: ZenohBridge,
    shutdown: CancellationToken,
}

async fn pair(cell: &str) -> Pair {
    let server = within("open server", open_session(&loopback(vec![]))).await.unwrap();
    let cells = Cells::new(cell, 10, 100).unwrap();
    let scene = cells.get(cell).unwrap();
    let shutdown = CancellationToken::new();
    let bridge = within(
        "bridge",
        ZenohBridge::start(
            server.clone(),
            cells,
            crate::clock::Clock::system(),
            crate::cells::state_admission::StateAdmission::new(&Default::default()),
            shutdown.clone(),
        ),
    )
    .await
    .unwrap();
    let client = within("open client", open_session(&loopback(locators(&server).await))).await.unwrap();
    Pair { server, client, scene, bridge, shutdown }
}

impl Pair {
    async fn close(self) {
        self.shutdown.cancel();
        within("bridge close", self.bridge.close()).await;
        within("client close", self.client.close()).await.unwrap();
        within("server close", self.server.close()).await.unwrap();
    }
}

/// Declares a publisher and waits until it knows a subscriber (a put sent before is lost).
async fn matched_publisher(session: &Session, key: String) -> Publisher<'static> {
    let p = within("declare publisher", session.declare_publisher(key)).await.unwrap();
    let listener = within("matching listener", p.matching_listener()).await.unwrap();
    if !within("matching status", p.matching_status()).await.unwrap().matching() {
        while !within("matching", listener.recv_async()).await.unwrap().matching() {}
    }
    p
}

/// Waits for the next scene version.
async fn next(
    rx: &mut watch::Receiver<Arc<crate::cells::cell::ObstacleSet>>,
) -> Arc<crate::cells::cell::ObstacleSet> {
    within("scene change", rx.changed()).await.unwrap();
    rx.borrow_and_update().clone()
}

fn ball(id: &str, center: [f64; 3]) -> v1::Obstacle {
    v1::Obstacle {
        id: id.into(),
        shape: Some(v1::obstacle::Shape::Solid(v1::SolidPrimitive { r#type: 2, dimensions: vec![0.1] })),
        center: center.to_vec(),
        ..Default::default()
    }
}

#[tokio::test(flavor = "multi_thread")]
async fn a_bad_connect_endpoint_fails_fast() {
    // Port 1 on loopback: nothing listens there.
    let t0 = std::time::Instant::now();
    let e = within("open", open_session(&loopback(vec!["tcp/127.0.0.1:1".into()]))).await.unwrap_err();
    assert!(matches!(e, ServerError::FailedPrecondition(_)), "{e}");
    assert!(t0.elapsed() < Duration::from_millis(CONNECT_TIMEOUT_MS + 2000), "{:?}", t0.elapsed());
}

#[tokio::test(flavor = "multi_thread")]
async fn zenoh_obstacles_are_put_replaced_deleted_and_expire() {
    let p = pair("cell1").await;
    let mut rx = p.scene.subscribe();

    let json = matched_publisher(&p.client, obstacle_key("cell1", "box1")).await;
    let body = r#"{"center": [0.5, 0.5, 0.0], "semi_axes": [0.1, 0.2, 0.3], "exponents": [2, 2, 2]}"#;
    within("put", json.put(body).encoding(Encoding::APPLICATION_JSON)).await.unwrap();
    let s = next(&mut rx).await;
    assert_eq!(s.obstacles["box1"].proto.center, vec![0.5, 0.5, 0.0]);

    // The JSON of an unset encoding, a protobuf replacement, then a protobuf of another obstacle.
    within("put", json.put(body.replace("0.5, 0.5", "0.7, 0.5"))).await.unwrap();
    let s = next(&mut rx).await;
    assert_eq!(s.obstacles["box1"].proto.center, vec![0.7, 0.5, 0.0]);
    let pb = codec::encode(&ball("", [1.0, 2.0, 3.0]));
    within("put", json.put(pb).encoding(Encoding::APPLICATION_PROTOBUF)).await.unwrap();
    let s = next(&mut rx).await;
    assert_eq!(s.obstacles["box1"].proto.center, vec![1.0, 2.0, 3.0]);
    assert!(matches!(s.obstacles["box1"].proto.shape, Some(v1::obstacle::Shape::Solid(_))));
    let key = obstacle_key("cell1", "ball");
    let pb = codec::encode(&ball("ball", [0.0; 3]));
    within("put", p.client.put(&key, pb).encoding(Encoding::APPLICATION_PROTOBUF)).await.unwrap();
    let s = next(&mut rx).await;
    assert_eq!(s.obstacles.keys().collect::<Vec<_>>(), ["ball", "box1"]);

    within("delete", json.delete()).await.unwrap();
    let s = next(&mut rx).await;
    assert_eq!(s.obstacles.keys().collect::<Vec<_>>(), ["ball"]);

    // A time to live: the put, then the reaper's removal.
    let ttl = r#"{"center": [0, 0, 0], "semi_axes": [0.1, 0.1, 0.1], "ttl_s": 0.2, "margin": 0.05}"#;
    within("put", p.client.put(obstacle_key("cell1", "brief"), ttl)).await.unwrap();
    let s = next(&mut rx).await;
    assert!(s.obstacles.contains_key("brief"));
    let s = next(&mut rx).await;
    assert_eq!(s.obstacles.keys().collect::<Vec<_>>(), ["ball"], "expired");
    assert_eq!(p.bridge.malformed_payloads(), 0);
    p.close().await;
}

#[tokio::test(flavor = "multi_thread")]
async fn malformed_payloads_are_counted_and_change_nothing() {
    // `cargo test malformed -- --nocapture` shows each refusal and its reason.
    let _ = tracing_subscriber::fmt().with_test_writer().with_env_filter("dmp_server=warn").try_init();
    let p = pair("cell2").await;
    let mut rx = p.scene.subscribe();
    let publisher = matched_publisher(&p.client, obstacle_key("cell2", "x")).await;
    let good = r#"{"center": [0, 0], "semi_axes": [0.1, 0.1]}"#;
    within("put", publisher.put(good)).await.unwrap();
    let before = next(&mut rx).await;

    let bad: [(&str, &[u8], Encoding); 8] = [
        ("x", b"{\"center\": [0, 0], \"semi_axes\": [0.1,", Encoding::default()),
        ("x", br#"{"center": [0, 0], "semi_axes": [-0.1, 0.1]}"#, Encoding::APPLICATION_JSON),
        ("x", br#"{"center": [1e999, 0], "semi_axes": [0.1, 0.1]}"#, Encoding::default()),
        ("x", br#"{"center": [0, 0, 0], "semi_axes": [0.1, 0.1]}"#, Encoding::default()),
        ("x", br#"{"id": "y", "center": [0, 0], "semi_axes": [0.1, 0.1]}"#, Encoding::default()),
        ("x", b"\xff\xff\xff\xff garbage", Encoding::APPLICATION_PROTOBUF),
        ("x", b"\x08\x96\x01", Encoding::default()),
        ("z", b"not json", Encoding::TEXT_PLAIN),
    ];
    for (id, payload, encoding) in bad.clone() {
        let key = obstacle_key("cell2", id);
        within("put", p.client.put(key, payload).encoding(encoding)).await.unwrap();
    }
    let mut nan = ball("x", [f64::NAN, 0.0, 0.0]);
    within("put", publisher.put(codec::encode(&nan)).encoding(Encoding::APPLICATION_PROTOBUF)).await.unwrap();
    nan.center = vec![0.0; 3];
    nan.margin = f64::INFINITY;
    within("put", publisher.put(codec::encode(&nan)).encoding(Encoding::APPLICATION_PROTOBUF)).await.unwrap();
    let robot = v1::RobotState { robot_id: "r1".into(), position: vec![f64::NAN], ..Default::default() };
    within("put", p.client.put(robot_state_key("cell2", "r1"), codec::encode(&robot))).await.unwrap();
    within("put", p.client.put(robot_state_key("cell2", "r2"), "garbage")).await.unwrap();

    // A sentinel sent after them on the same session: when it arrives, every one before it was handled.
    within("put", p.client.put(obstacle_key("cell2", "sentinel"), good)).await.unwrap();
    let after = next(&mut rx).await;
    assert_eq!(p.bridge.malformed_payloads(), bad.len() as u64 + 4);
    assert_eq!(after.version, before.version + 1, "only the sentinel changed the scene");
    assert_eq!(after.obstacles.keys().collect::<Vec<_>>(), ["sentinel", "x"]);
    assert_eq!(after.obstacles["x"].proto, before.obstacles["x"].proto);
    assert!(p.scene.other_robots("", crate::clock::system_unix_s(), 1e9).is_empty());
    p.close().await;
}

#[tokio::test(flavor = "multi_thread")]
async fn robot_states_arrive_and_leave() {
    let p = pair("cell3").await;
    let mut rx = p.scene.subscribe();
    let publisher = matched_publisher(&p.client, robot_state_key("cell3", "r1")).await;
    let state = v1::RobotState {
        robot_id: "r1".into(),
        stamp_unix_s: crate::clock::system_unix_s(),
        position: vec![0.1, 0.2, 0.3],
        velocity: vec![1.0, 0.0, 0.0],
        footprint: Some(v1::Superquadric { semi_axes: vec![0.1; 3], exponents: vec![] }),
        ..Default::default()
    };
    within("put", publisher.put(codec::encode(&state)).encoding(Encoding::APPLICATION_PROTOBUF))
        .await
        .unwrap();
    // An id-less state takes the key's.
    let r2 = v1::RobotState { robot_id: String::new(), position: vec![0.0; 3], ..state.clone() };
    within("put", p.client.put(robot_state_key("cell3", "r2"), codec::encode(&r2))).await.unwrap();
    // Robot states do not wake the scene's readers: a sentinel obstacle sent after them does.
    let sentinel = r#"{"center": [0, 0], "semi_axes": [0.1, 0.1]}"#;
    within("put", p.client.put(obstacle_key("cell3", "s"), sentinel)).await.unwrap();
    next(&mut rx).await;
    let others = p.scene.other_robots("r2", crate::clock::system_unix_s(), 60.0);
    assert_eq!(others.len(), 1);
    assert_eq!(others[0].state, state);
    assert!(others[0].footprint.is_some());
    assert_eq!(p.scene.other_robots("r1", crate::clock::system_unix_s(), 60.0)[0].state.robot_id, "r2");

    within("delete", publisher.delete()).await.unwrap();
    within("delete", p.client.delete(obstacle_key("cell3", "s"))).await.unwrap();
    next(&mut rx).await;
    let others = p.scene.other_robots("", crate::clock::system_unix_s(), 60.0);
    assert_eq!(others.iter().map(|r| r.state.robot_id.as_str()).collect::<Vec<_>>(), ["r2"]);
    assert_eq!(p.bridge.malformed_payloads(), 0);
    p.close().await;
}

#[tokio::test(flavor = "multi_thread")]
async fn a_client_mode_session_reaches_the_bridge() {
    let p = pair("cell5").await;
    let mut cfg = loopback(locators(&p.server).await);
    cfg.mode = "client".into();
    cfg.listen.clear();
    let client = within("open client mode", open_session(&cfg)).await.unwrap();
    let mut rx = p.scene.subscribe();
    let publisher = matched_publisher(&client, obstacle_key("cell5", "c")).await;
    within("put", publisher.put(r#"{"center": [0], "semi_axes": [1]}"#)).await.unwrap();
    assert!(next(&mut rx).await.obstacles.contains_key("c"));
    drop(publisher);
    within("client mode close", client.close()).await.unwrap();
    p.close().await;
}

#[tokio::test(flavor = "multi_thread")]
async fn the_reaper_stops_on_shutdown() {
    let p = pair("cell4").await;
    p.shutdown.cancel();
    within("reaper", async {
        while !p.bridge.reaper.is_finished() {
            tokio::task::yield_now().await;
        }
    })
    .await;
    p.close().await;
}
