//! Golden payloads: CDR written by rosbags (an independent implementation, `tests/python/ros2_payloads.py`) decodes
//! in `dmp_ros2` to the values rosbags reads back, `dmp_ros2` writes the same bytes again, and its bytes decode in
//! rosbags to the same values; so do the messages the server writes itself (a segment's trajectory, a cell's
//! markers with every kind: true shapes, isopotentials, paths, DELETE and DELETEALL). Also: the `.msg` files of `ros2/msg/` are rosbags' Humble and Jazzy definitions,
//! and the type hashes the server publishes with are rosbags'.

use std::io::Write;
use std::process::{Command, Stdio};

use dmp_ros2::msgs::moveit_msgs::CollisionObject;
use dmp_ros2::msgs::nav2_dynamic_msgs::ObstacleArray;
use dmp_ros2::msgs::trajectory_msgs::MultiDOFJointTrajectory;
use dmp_ros2::msgs::visualization_msgs::MarkerArray;
use serde::Serialize;
use serde::de::DeserializeOwned;
use serde_json::{Value, json};

use super::python_clients::{python, workspace};

fn payloads(mode: &str, stdin: &str) -> Vec<String> {
    let mut args = mode.split(' ');
    let mut child = Command::new(python())
        .arg(workspace().join("tests/python/ros2_payloads.py"))
        .arg(workspace().join("ros2/msg"))
        .args(&mut args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .expect("python starts");
    child.stdin.take().unwrap().write_all(stdin.as_bytes()).unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success(), "ros2_payloads.py {mode} failed");
    String::from_utf8(out.stdout).unwrap().lines().map(str::to_owned).collect()
}

/// Decodes rosbags' payload as `T`: the same values; encodes them again: the same bytes. Returns the JSON line
/// that asks rosbags to decode our payload, and our value.
fn check<T: DeserializeOwned + Serialize>(case: &Value) -> (String, Value) {
    let name = case["name"].as_str().unwrap();
    let bytes = hex::decode(case["cdr"].as_str().unwrap()).unwrap();
    let msg: T = dmp_ros2::decode(&bytes).unwrap_or_else(|e| panic!("{name}: {e}"));
    let value = serde_json::to_value(&msg).unwrap();
    assert_eq!(value, case["value"], "{name}: our values differ from rosbags'");
    let ours = dmp_ros2::encode(&msg).unwrap();
    assert_eq!(hex::encode(&ours), case["cdr"].as_str().unwrap(), "{name}: our bytes differ from rosbags'");
    let line = json!({"name": name, "type": case["type"], "cdr": hex::encode(&ours)}).to_string();
    (line, value)
}

#[test]
fn rosbags_payloads_decode_to_the_same_values_both_ways() {
    let cases: Vec<Value> = payloads("encode", "").iter().map(|l| serde_json::from_str(l).unwrap()).collect();
    let mut seen_types = std::collections::BTreeSet::new();
    let mut back = String::new();
    let mut expected = Vec::new();
    for case in &cases {
        let ty = case["type"].as_str().unwrap();
        seen_types.insert(ty.to_owned());
        let (line, value) = match ty {
            "moveit_msgs/msg/CollisionObject" => check::<CollisionObject>(case),
            "nav2_dynamic_msgs/msg/ObstacleArray" => check::<ObstacleArray>(case),
            "trajectory_msgs/msg/MultiDOFJointTrajectory" => check::<MultiDOFJointTrajectory>(case),
            "visualization_msgs/msg/MarkerArray" => check::<MarkerArray>(case),
            other => panic!("no Rust type for {other}"),
        };
        back.push_str(&line);
        back.push('\n');
        expected.push(value);
    }
    assert_eq!(seen_types.len(), 4, "{seen_types:?}");
    // Every primitive type and every operation is covered.
    let co: Vec<&Value> = cases.iter().filter(|c| c["type"] == "moveit_msgs/msg/CollisionObject").collect();
    let ops: std::collections::BTreeSet<u64> =
        co.iter().map(|c| c["value"]["operation"].as_u64().unwrap()).collect();
    assert_eq!(ops.into_iter().collect::<Vec<_>>(), vec![0, 1, 2, 3]);
    let kinds: std::collections::BTreeSet<u64> = co
        .iter()
        .flat_map(|c| c["value"]["primitives"].as_array().unwrap())
        .map(|p| p["type"].as_u64().unwrap())
        .collect();
    assert_eq!(kinds.into_iter().collect::<Vec<_>>(), vec![1, 2, 3, 4, 5]);

    let decoded = payloads("decode", &back);
    assert_eq!(decoded.len(), expected.len());
    for (line, want) in decoded.iter().zip(&expected) {
        let got: Value = serde_json::from_str(line).unwrap();
        assert_eq!(&got["value"], want, "{}: rosbags reads our payload differently", got["name"]);
    }
}

/// The server's own messages, as the publishers build them.
fn server_messages() -> Vec<(&'static str, &'static str, Vec<u8>, Value)> {
    use dmp_proto::v1;
    use dmp_server::ros2::marker_shapes::{isopotential, path, true_shape};
    use dmp_server::ros2::markers::{Shown, marker_array};
    use dmp_server::ros2::paths::Path;
    use dmp_server::ros2::trajectory::trajectory_message;

    let pose_run = v1::Segment {
        robot_id: "arm-1".into(),
        start_time: 0.5,
        dt: 0.004,
        dim: 3,
        positions: vec![0.1, 0.2, 0.3, 0.11, 0.19, 0.31, 0.125, 0.18, 0.32],
        velocities: vec![2.5, -2.5, 2.5, 3.0, -2.0, 2.0, 3.5, -1.5, 1.5],
        accelerations: vec![10.0, 0.0, -7.5, 12.0, 1.0, -6.0, 0.0, 0.0, 0.0],
        orientations: vec![
            0.0,
            0.0,
            0.6,
            0.8,
            0.0,
            0.1,
            0.6,
            0.7937253933193772,
            0.0,
            0.2,
            0.6,
            0.7745966692414834,
        ],
        angular_velocities: vec![0.0, 25.0, 0.0, 0.0, 24.0, 0.5, 0.0, 23.0, 1.0],
        angular_accelerations: vec![0.0, -250.0, 0.0, 0.0, -240.0, 5.0, 0.0, -230.0, 10.0],
        start_unix_s: 1_764_100_000.5,
        ..Default::default()
    };
    let flat_run = v1::Segment {
        robot_id: "amr".into(),
        dt: 0.01,
        dim: 2,
        positions: vec![1.0, 2.0, 1.01, 2.02],
        velocities: vec![1.0, 2.0, 1.0, 2.0],
        accelerations: vec![0.0, 0.0, -0.5, 0.25],
        ..Default::default()
    };
    let boxed = v1::Obstacle {
        id: "crate".into(),
        shape: Some(v1::obstacle::Shape::Solid(v1::SolidPrimitive {
            r#type: 1,
            dimensions: vec![0.2, 0.1, 0.3],
        })),
        center: vec![1.0, 2.0, 0.5],
        rotation: vec![0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0],
        margin: 0.05,
        ..Default::default()
    };
    let disc = v1::Obstacle {
        id: "post".into(),
        shape: Some(v1::obstacle::Shape::Superquadric(v1::Superquadric {
            semi_axes: vec![0.1, 0.2],
            exponents: vec![2.0, 2.0],
        })),
        center: vec![0.5, -0.5],
        ..Default::default()
    };
    let engine = |o: &v1::Obstacle| dmp_proto::obstacle::obstacle_to_engine(o).unwrap();
    let robot_path =
        Path { times: vec![0.0, 0.1, 0.2], points: vec![[0.0, 0.0, 0.0], [0.1, 0.05, 0.0], [0.2, 0.1, 0.0]] };
    let mut wanted = vec![true_shape(&boxed).unwrap(), isopotential(&engine(&boxed)).unwrap()];
    wanted.extend([
        true_shape(&disc).unwrap(),
        isopotential(&engine(&disc)).unwrap(),
        path("arm-1", &robot_path).unwrap(),
    ]);
    let mut shown = Shown::default();
    let first = marker_array("world", 1_764_100_001.25, shown.update(wanted.clone(), false));
    // The disc (its true shape and its isopotential) and the robot go: three DELETEs.
    let next = marker_array("world", 1_764_100_002.0, shown.update(wanted[..2].to_vec(), true));
    assert_eq!(next.markers.iter().filter(|m| m.action == 2).count(), 3);

    let traj = "trajectory_msgs/msg/MultiDOFJointTrajectory";
    let markers = "visualization_msgs/msg/MarkerArray";
    let encoded = |name, ty, v: Vec<u8>, value: Value| (name, ty, v, value);
    let t1 = trajectory_message(&pose_run, "world", pose_run.start_unix_s);
    let t2 = trajectory_message(&flat_run, "world", 1_764_100_003.0);
    vec![
        encoded(
            "server-pose-trajectory",
            traj,
            dmp_ros2::encode(&t1).unwrap(),
            serde_json::to_value(&t1).unwrap(),
        ),
        encoded(
            "server-flat-trajectory",
            traj,
            dmp_ros2::encode(&t2).unwrap(),
            serde_json::to_value(&t2).unwrap(),
        ),
        encoded(
            "server-markers",
            markers,
            dmp_ros2::encode(&first).unwrap(),
            serde_json::to_value(&first).unwrap(),
        ),
        encoded(
            "server-marker-deletes",
            markers,
            dmp_ros2::encode(&next).unwrap(),
            serde_json::to_value(&next).unwrap(),
        ),
    ]
}

#[test]
fn the_servers_trajectories_and_markers_decode_in_rosbags_to_the_same_values() {
    let messages = server_messages();
    let mut lines = String::new();
    for (name, ty, cdr, _) in &messages {
        lines.push_str(&json!({"name": name, "type": ty, "cdr": hex::encode(cdr)}).to_string());
        lines.push('\n');
    }
    let decoded = payloads("decode", &lines);
    assert_eq!(decoded.len(), messages.len());
    for (line, (name, _, _, want)) in decoded.iter().zip(&messages) {
        let got: Value = serde_json::from_str(line).unwrap();
        assert_eq!(&got["name"], name);
        assert_eq!(&got["value"], want, "{name}: rosbags reads the server's payload differently");
    }
}

#[test]
fn the_msg_files_are_rosbags_humble_and_jazzy_definitions() {
    let lines = payloads("defs", "");
    assert!(lines.len() >= 40, "{lines:?}");
    let bad: Vec<&String> = lines.iter().filter(|l| !l.starts_with("ok ")).collect();
    assert!(bad.is_empty(), "{bad:?}");
}

#[test]
fn the_attachment_is_zenoh_ext_serialization() {
    let a = dmp_ros2::attachment::Attachment {
        sequence_number: 42,
        source_timestamp: -1_764_100_000_123_456_789,
        source_gid: std::array::from_fn(|i| i as u8),
    };
    let lines = payloads("attachment 42 -1764100000123456789", "");
    assert_eq!(lines, vec![hex::encode(a.encode())]);
}

#[test]
fn published_type_hashes_are_rosbags() {
    use dmp_ros2::keys::{MARKER_ARRAY, MULTI_DOF_JOINT_TRAJECTORY};
    let lines = payloads("hashes", "");
    for ty in [MULTI_DOF_JOINT_TRAJECTORY, MARKER_ARRAY] {
        assert!(lines.contains(&format!("{} {}", ty.name, ty.hash)), "{ty:?} not in {lines:?}");
    }
}
