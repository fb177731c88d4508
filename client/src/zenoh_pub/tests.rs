//! The publisher against real Zenoh sessions on loopback.

use super::*;
use dmp_proto::zenoh_session::CONNECT_TIMEOUT_MS;
use zenoh::sample::SampleKind;

const WAIT: Duration = Duration::from_secs(10);

/// A subscriber peer on loopback, without scouting, as the server would be; returns it and its locator.
async fn subscriber_peer() -> (zenoh::Session, String) {
    let config = session_config(&SessionOptions::loopback_peer(Vec::new())).unwrap();
    let s = zenoh::open(config).await.unwrap();
    let locator = s.info().locators().await[0].to_string();
    (s, locator)
}

#[test]
fn a_publisher_connecting_to_the_server_scouts_nothing_and_listens_on_nothing() {
    let direct = publisher_options(&["tcp/127.0.0.1:7447".into()], &[]);
    assert_eq!((direct.listen, direct.multicast_scouting), (Some(vec![]), false));
    let lan = publisher_options(&[], &[]);
    assert_eq!((lan.listen, lan.multicast_scouting), (None, true));
    let listening = publisher_options(&[], &["tcp/127.0.0.1:0".into()]);
    assert_eq!(listening.listen, Some(vec!["tcp/127.0.0.1:0".to_string()]));
}

#[tokio::test(flavor = "multi_thread")]
async fn puts_and_deletes_reach_a_subscriber_with_their_encodings() {
    let (server, locator) = subscriber_peer().await;
    let sub = server.declare_subscriber(obstacles_of("cellA")).await.unwrap();
    let publisher = ObstaclePublisher::open("cellA", &[locator], &[]).await.unwrap();
    publisher.wait_for_subscriber(WAIT).await.unwrap();

    let spec: ObstacleSpec = serde_json::from_value(
        serde_json::json!({"id": "box1", "center": [0.5, 0.5], "semi_axes": [0.2, 0.1]}),
    )
    .unwrap();
    publisher.put_spec(&spec, 2.5).await.unwrap();
    let proto = JsonObstacle { spec: spec.clone(), margin: 0.05, ttl_s: 0.0 }.to_proto();
    publisher.put_proto(&v1::Obstacle { id: "box2".into(), ..proto.clone() }).await.unwrap();
    publisher.delete("box1").await.unwrap();
    // Closing right after the last put loses nothing.
    publisher.close().await.unwrap();

    let s = tokio::time::timeout(WAIT, sub.recv_async()).await.unwrap().unwrap();
    assert_eq!(s.key_expr().as_str(), obstacle_key("cellA", "box1"));
    assert_eq!(s.encoding(), &Encoding::APPLICATION_JSON);
    let v: serde_json::Value = serde_json::from_slice(&s.payload().to_bytes()).unwrap();
    assert_eq!(v["ttl_s"], 2.5);
    assert_eq!(v["semi_axes"], serde_json::json!([0.2, 0.1]));

    let s = tokio::time::timeout(WAIT, sub.recv_async()).await.unwrap().unwrap();
    assert_eq!(s.key_expr().as_str(), obstacle_key("cellA", "box2"));
    assert_eq!(s.encoding().to_string(), codec::PROTOBUF_ENCODING);
    let o: v1::Obstacle = codec::decode(&s.payload().to_bytes()).unwrap();
    assert_eq!(o.id, "box2");
    assert_eq!(o.margin, 0.05);
    assert_eq!(o.shape, proto.shape);

    let s = tokio::time::timeout(WAIT, sub.recv_async()).await.unwrap().unwrap();
    assert_eq!(s.kind(), SampleKind::Delete);
    assert_eq!(s.key_expr().as_str(), obstacle_key("cellA", "box1"));
    server.close().await.unwrap();
}

#[tokio::test(flavor = "multi_thread")]
async fn waiting_without_a_subscriber_times_out_and_bad_ids_are_refused() {
    let (other, locator) = subscriber_peer().await;
    // A subscriber of another cell does not count.
    let _sub = other.declare_subscriber(obstacles_of("elsewhere")).await.unwrap();
    let publisher = ObstaclePublisher::open("cellB", &[locator], &[]).await.unwrap();
    let e = publisher.wait_for_subscriber(Duration::from_millis(300)).await.unwrap_err();
    assert!(e.to_string().contains("dmp/cellB/obstacles"), "{e}");
    let e = publisher.delete("a/b").await.unwrap_err();
    assert!(e.is_bad_input() && e.to_string().contains("id"), "{e}");
    publisher.close().await.unwrap();
    other.close().await.unwrap();
}

#[tokio::test(flavor = "multi_thread")]
async fn serve_latest_answers_queries_with_what_was_put_and_not_deleted() {
    // The querying side connects to the publisher (the direction the server's catch-up is tested in).
    let config = session_config(&SessionOptions::loopback_peer(Vec::new())).unwrap();
    let mut publisher = ObstaclePublisher::open_with("cellQ", config).await.unwrap();
    let locator = publisher.session().info().locators().await[0].to_string();
    let server =
        zenoh::open(session_config(&SessionOptions::loopback_peer(vec![locator])).unwrap()).await.unwrap();
    let spec = |id: &str| -> ObstacleSpec {
        serde_json::from_value(serde_json::json!({"id": id, "center": [0.5, 0.5], "semi_axes": [0.2, 0.1]}))
            .unwrap()
    };
    publisher.put_spec(&spec("a"), 0.0).await.unwrap();
    publisher.put_spec(&spec("b"), 0.0).await.unwrap();
    publisher.serve_latest().await.unwrap();
    let proto = JsonObstacle { spec: spec("c"), margin: 0.0, ttl_s: 0.0 }.to_proto();
    publisher.put_proto_in("other", &proto).await.unwrap();
    publisher.delete("b").await.unwrap();

    // Polls until the queryable is known to the querying side (an empty answer before).
    let mut keys = Vec::new();
    tokio::time::timeout(WAIT, async {
        while keys.is_empty() {
            let replies = server.get("dmp/*/obstacles/**").await.unwrap();
            while let Ok(r) = replies.recv_async().await {
                let s = r.result().unwrap();
                keys.push((s.key_expr().to_string(), s.encoding().to_string()));
            }
        }
    })
    .await
    .unwrap();
    keys.sort();
    assert_eq!(
        keys,
        [
            (obstacle_key("cellQ", "a"), Encoding::APPLICATION_JSON.to_string()),
            (obstacle_key("other", "c"), codec::PROTOBUF_ENCODING.to_string()),
        ]
    );
    // A query of one cell gets that cell's only.
    let replies = tokio::time::timeout(WAIT, server.get("dmp/other/obstacles/*")).await.unwrap().unwrap();
    let r = tokio::time::timeout(WAIT, replies.recv_async()).await.unwrap().unwrap();
    assert_eq!(r.result().unwrap().key_expr().as_str(), obstacle_key("other", "c"));
    assert!(tokio::time::timeout(WAIT, replies.recv_async()).await.unwrap().is_err(), "one reply");
    publisher.close().await.unwrap();
    server.close().await.unwrap();
}

#[tokio::test(flavor = "multi_thread")]
async fn serve_latest_puts_again_what_is_live_when_a_subscriber_appears() {
    let config = session_config(&SessionOptions::loopback_peer(Vec::new())).unwrap();
    let mut publisher = ObstaclePublisher::open_with("cellR", config).await.unwrap();
    publisher.serve_latest().await.unwrap();
    let spec = |id: &str| -> ObstacleSpec {
        serde_json::from_value(serde_json::json!({"id": id, "center": [0.5, 0.5], "semi_axes": [0.2, 0.1]}))
            .unwrap()
    };
    // Before any subscriber: these puts reach no one.
    publisher.put_spec(&spec("kept"), 0.0).await.unwrap();
    publisher.put_spec(&spec("deleted"), 0.0).await.unwrap();
    // Its ttl_s of 1 ms ends long before a subscriber can have opened its session.
    publisher.put_spec(&spec("expired"), 0.001).await.unwrap();
    publisher.delete("deleted").await.unwrap();

    // A subscriber that only subscribes (it does not query) gets what is live once it is known.
    let locator = publisher.session().info().locators().await[0].to_string();
    let server =
        zenoh::open(session_config(&SessionOptions::loopback_peer(vec![locator])).unwrap()).await.unwrap();
    let sub = server.declare_subscriber("dmp/*/obstacles/**").await.unwrap();
    let s = tokio::time::timeout(WAIT, sub.recv_async()).await.unwrap().unwrap();
    assert_eq!((s.kind(), s.key_expr().as_str()), (SampleKind::Put, obstacle_key("cellR", "kept").as_str()));
    let more = tokio::time::timeout(Duration::from_millis(300), sub.recv_async()).await;
    assert!(more.is_err(), "only the live obstacle is sent again: {more:?}");
    publisher.close().await.unwrap();
    server.close().await.unwrap();
}

#[tokio::test(flavor = "multi_thread")]
async fn an_unreachable_endpoint_fails_fast() {
    // Port 1 on loopback: nothing listens there.
    let started = std::time::Instant::now();
    let e = ObstaclePublisher::open("c", &["tcp/127.0.0.1:1".into()], &[]).await.unwrap_err();
    assert!(started.elapsed() < Duration::from_millis(CONNECT_TIMEOUT_MS + 5000), "{e}");
    assert!(!e.is_bad_input());
}
