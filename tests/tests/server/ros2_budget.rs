//! A MoveIt collision object applies whole or not at all within the cell's obstacle budget: one of 10,000 boxes,
//! published over rmw_zenoh's key to the real server, is refused whole (nothing added, counted), a REMOVE takes
//! away every obstacle an object added, and the cell then takes obstacles over gRPC as before.

use std::future::IntoFuture;
use std::sync::atomic::Ordering;

use dmp_proto::zenoh_session::{SessionOptions, session_config};
use dmp_ros2::msgs::geometry_msgs::{Point, Pose, Quaternion};
use dmp_ros2::msgs::moveit_msgs::CollisionObject;
use dmp_ros2::msgs::shape_msgs::SolidPrimitive;
use dmp_server::server::start;
use dmp_tests::{config, within};
use zenoh::Wait;

use super::{ellipse, until};

fn at(x: f64) -> Pose {
    Pose { position: Point { x, y: 0.0, z: 0.0 }, orientation: Quaternion { w: 1.0, ..Default::default() } }
}

fn boxes(id: &str, operation: u8, n: usize) -> Vec<u8> {
    let b = SolidPrimitive { r#type: SolidPrimitive::BOX, dimensions: vec![0.01; 3], ..Default::default() };
    let mut msg = CollisionObject {
        id: id.into(),
        operation,
        pose: at(0.0),
        primitives: vec![b; n],
        primitive_poses: (0..n).map(|k| at(k as f64 * 1e-3)).collect(),
        ..Default::default()
    };
    msg.header.frame_id = "world".into();
    dmp_ros2::encode(&msg).unwrap()
}

#[tokio::test(flavor = "multi_thread")]
async fn a_collision_object_over_the_budget_is_refused_whole_and_remove_leaves_no_orphans() {
    let data = tempfile::tempdir().unwrap();
    let mut c = config(data.path());
    c.ros2.domain = Some(7);
    let max = c.limits.max_obstacles;
    let h = within("server start", start(c)).await.expect("server starts");
    let cell = h.cells().get("").unwrap();
    let counters = h.ros2_counters().expect("the ROS 2 bridge runs");
    let node = session_config(&SessionOptions::loopback_peer(h.zenoh_locators.clone())).unwrap();
    let node = within("node open", zenoh::open(node).into_future()).await.unwrap();
    let key = "7/collision_object/moveit_msgs::msg::dds_::CollisionObject_/RIHS01_test";
    let publisher = within("publisher", node.declare_publisher(key).into_future()).await.unwrap();
    until("the server's subscriber is known", || {
        publisher.matching_status().wait().map(|s| s.matching()).unwrap_or(false)
    })
    .await;
    let put = |bytes: Vec<u8>| within("put", publisher.put(bytes).into_future());

    let t0 = std::time::Instant::now();
    put(boxes("big", CollisionObject::ADD, 10 * max)).await.unwrap();
    until("the big object is refused", || counters.refused.load(Ordering::Relaxed) == 1).await;
    eprintln!("{} boxes refused in {:?}", 10 * max, t0.elapsed());
    assert_eq!(cell.snapshot().obstacles.len(), 0, "nothing of it was added");

    // One that fits, then one that takes the rest of the budget but for one obstacle: both apply.
    put(boxes("small", CollisionObject::ADD, 2)).await.unwrap();
    put(boxes("most", CollisionObject::ADD, max - 3)).await.unwrap();
    until("both objects in the scene", || cell.snapshot().obstacles.len() == max - 1).await;
    // An append over the budget changes nothing.
    put(boxes("small", CollisionObject::APPEND, 2)).await.unwrap();
    until("the append is refused", || counters.refused.load(Ordering::Relaxed) == 2).await;
    assert_eq!(cell.snapshot().obstacles.len(), max - 1);

    // REMOVE by id, then REMOVE all: nothing is left.
    put(boxes("small", CollisionObject::REMOVE, 0)).await.unwrap();
    until("`small` removed", || cell.snapshot().obstacles.len() == max - 3).await;
    put(boxes("", CollisionObject::REMOVE, 0)).await.unwrap();
    until("every object removed", || cell.snapshot().obstacles.is_empty()).await;
    assert_eq!(counters.refused.load(Ordering::Relaxed), 2);

    // The cell takes obstacles over gRPC again.
    let client = within("connect", dmp_client::grpc::DmpClient::connect(format!("http://{}", h.grpc_addr)))
        .await
        .unwrap();
    within("put obstacle", client.put_obstacle(ellipse("o", vec![0.5, 0.5], vec![0.1, 0.1]))).await.unwrap();
    within("close", node.close().into_future()).await.unwrap();
}
