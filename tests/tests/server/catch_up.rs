//! Catching up with the scene after a (re)start: obstacles published once, before the server started or while it
//! was down, reach it whichever side connects to which, through the perception node's
//! `ObstaclePublisher::serve_latest` (it answers the server's query, and puts them again when the server's
//! subscriber appears).

use dmp_client::zenoh_pub::ObstaclePublisher;
use dmp_proto::zenoh_session::{SessionOptions, locators, session_config};
use dmp_server::server::{ServerHandle, start};
use dmp_tests::{config, within};

use crate::stale_scene::{has_obstacle, router, start_connected};
use crate::{ellipse, until};

/// A perception node on a loopback port of its own (no scouting) that answers the server's queries.
async fn perception_node() -> ObstaclePublisher {
    let config = session_config(&SessionOptions::loopback_peer(Vec::new())).unwrap();
    let mut p = within("perception open", ObstaclePublisher::open_with("default", config)).await.unwrap();
    within("queryable", p.serve_latest()).await.unwrap();
    p
}

#[tokio::test(flavor = "multi_thread")]
async fn an_obstacle_published_before_the_server_started_reaches_it_on_start_and_after_a_restart() {
    let perception = perception_node().await;
    // Published before any server exists: as a put it reaches no one.
    within("put", perception.put_proto(&ellipse("box", vec![0.5, 0.5], vec![0.1, 0.1]))).await.unwrap();
    let connect = locators(perception.session()).await;
    let dir = tempfile::tempdir().unwrap();

    let handle = start_connected(dir.path(), connect.clone()).await;
    until("the obstacle reaches it on start", || has_obstacle(&handle, "default", "box")).await;
    within("shutdown", handle.shutdown()).await.unwrap();

    // Restarted on the same store: the scene is empty at start and gets it again.
    let handle = start_connected(dir.path(), connect).await;
    until("the obstacle reaches it after the restart", || has_obstacle(&handle, "default", "box")).await;
    // What the node deleted is not served any more, and the delete reaches the running server.
    within("delete", perception.delete("box")).await.unwrap();
    until("the delete is applied", || !has_obstacle(&handle, "default", "box")).await;
    within("shutdown", handle.shutdown()).await.unwrap();
    within("close", perception.close()).await.unwrap();
}

/// A server on the Zenoh endpoint `listen` (e.g. the port of the one it replaces).
async fn start_listening(dir: &std::path::Path, listen: Vec<String>) -> ServerHandle {
    let mut c = config(dir);
    c.zenoh.listen = listen;
    within("server start", start(c)).await.expect("server starts")
}

#[tokio::test(flavor = "multi_thread")]
async fn a_node_that_connects_to_the_server_sends_its_obstacles_again_after_a_restart() {
    let dir = tempfile::tempdir().unwrap();
    let handle = start_listening(dir.path(), vec!["tcp/127.0.0.1:0".into()]).await;
    let endpoint = handle.zenoh_locators.clone();
    let mut perception =
        within("perception open", ObstaclePublisher::open("default", &endpoint, &[])).await.unwrap();
    within("queryable", perception.serve_latest()).await.unwrap();
    within("subscriber", perception.wait_for_subscriber(dmp_tests::T)).await.unwrap();
    within("put", perception.put_proto(&ellipse("box", vec![0.5, 0.5], vec![0.1, 0.1]))).await.unwrap();
    until("the put is applied", || has_obstacle(&handle, "default", "box")).await;
    within("shutdown", handle.shutdown()).await.unwrap();

    // Back on the same port and store, with an empty scene: the node reconnects and sends the box again.
    let handle = start_listening(dir.path(), endpoint).await;
    until("the obstacle is sent again after the restart", || has_obstacle(&handle, "default", "box")).await;
    within("shutdown", handle.shutdown()).await.unwrap();
    within("close", perception.close()).await.unwrap();
}

/// The deployment of `deploy/zenohd-obstacles.json5`: the server is a client of the router, the perception node a
/// peer connected to it.
#[tokio::test(flavor = "multi_thread")]
async fn a_server_that_joins_through_a_router_later_gets_the_obstacles() {
    let zenohd = router("tcp/127.0.0.1:0").await;
    let endpoint = locators(&zenohd).await;
    let mut perception =
        within("perception open", ObstaclePublisher::open("default", &endpoint, &[])).await.unwrap();
    within("queryable", perception.serve_latest()).await.unwrap();
    within("put", perception.put_proto(&ellipse("box", vec![0.5, 0.5], vec![0.1, 0.1]))).await.unwrap();

    let dir = tempfile::tempdir().unwrap();
    let mut c = config(dir.path());
    (c.zenoh.connect, c.zenoh.mode) = (endpoint, "client".into());
    let handle = within("server start", start(c)).await.expect("server starts");
    until("the obstacle reaches the late server", || has_obstacle(&handle, "default", "box")).await;
    within("shutdown", handle.shutdown()).await.unwrap();
    within("close", perception.close()).await.unwrap();
    within("router close", std::future::IntoFuture::into_future(zenohd.close())).await.unwrap();
}
