//! End to end, out: two robots on a shared phase (a group run) stream against a server with a ROS 2 domain; a
//! stock Zenoh subscriber (this test's session, as a ROS 2 tool on rmw_zenoh would be) on rmw_zenoh's key of each
//! robot's `/dmp/<robot>/trajectory` receives one `MultiDOFJointTrajectory` per segment, with rmw_zenoh's
//! attachment, and it decodes (with `dmp_ros2`) to the setpoints the gRPC stream got. The cell's markers show each
//! robot's path (the positions sent) while it runs, and delete it when its stream ends.

use std::collections::HashMap;
use std::future::IntoFuture;

use dmp_proto::v1;
use dmp_proto::zenoh_session::{SessionOptions, session_config};
use dmp_ros2::attachment::Attachment;
use dmp_ros2::keys::{MARKER_ARRAY, MULTI_DOF_JOINT_TRAJECTORY, topic_key};
use dmp_ros2::msgs::builtin_interfaces::Time;
use dmp_ros2::msgs::trajectory_msgs::MultiDOFJointTrajectory;
use dmp_ros2::msgs::visualization_msgs::{Marker, MarkerArray};
use dmp_server::ros2::Ros2Counters;
use dmp_server::server::start;
use dmp_tests::{config, within};
use tokio_stream::StreamExt;

use crate::default_limits::exact;
use crate::{line, rows, spec};

/// `msg` is `segment` as the topic is documented: the robot's one joint, the cell's frame and its first point's wall
/// time, a point per setpoint with the position, velocity and acceleration (`z = 0` for 2-D), identity rotations,
/// `dt` apart.
fn assert_same(msg: &MultiDOFJointTrajectory, segment: &v1::Segment) {
    let robot = &segment.robot_id;
    assert_eq!(msg.joint_names, vec![robot.clone()]);
    assert_eq!(msg.header.frame_id, "world");
    assert!(segment.start_unix_s > 0.0);
    assert_eq!(
        msg.header.stamp,
        Time::from_unix_s(segment.start_unix_s),
        "stamped at the first point's wall time"
    );
    let xs = rows(segment, &segment.positions);
    assert_eq!(msg.points.len(), xs.len(), "{robot} segment {}", segment.sequence);
    let (vs, accs) = (rows(segment, &segment.velocities), rows(segment, &segment.accelerations));
    for (k, p) in msg.points.iter().enumerate() {
        let t = &p.transforms[0];
        assert_eq!([t.translation.x, t.translation.y, t.translation.z], [xs[k][0], xs[k][1], 0.0]);
        assert_eq!((t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w), (0.0, 0.0, 0.0, 1.0));
        let (v, a) = (&p.velocities[0].linear, &p.accelerations[0].linear);
        assert_eq!([v.x, v.y, v.z], [vs[k][0], vs[k][1], 0.0]);
        assert_eq!([a.x, a.y, a.z], [accs[k][0], accs[k][1], 0.0]);
        assert!((p.time_from_start.as_s() - k as f64 * segment.dt).abs() < 1e-9);
    }
}

#[tokio::test(flavor = "multi_thread")]
async fn a_group_runs_trajectories_arrive_on_rmw_zenoh_keys_as_the_robots_got_them() {
    let data = tempfile::tempdir().unwrap();
    let mut c = config(data.path());
    c.ros2.domain = Some(5);
    let h = within("server start", start(c)).await.expect("server starts");
    let client = within("connect", dmp_client::grpc::DmpClient::connect(format!("http://{}", h.grpc_addr)))
        .await
        .unwrap();
    let tool = session_config(&SessionOptions::loopback_peer(h.zenoh_locators.clone())).unwrap();
    let tool = within("tool open", zenoh::open(tool).into_future()).await.unwrap();
    let robots = ["amr-1", "amr-2"];
    let mut subscribers = Vec::new();
    for (robot, token) in robots.iter().zip(["amr_1", "amr_2"]) {
        let key = topic_key(5, &format!("/dmp/{token}/trajectory"), &MULTI_DOF_JOINT_TRAJECTORY);
        subscribers.push(within("subscribe", tool.declare_subscriber(&key).into_future()).await.unwrap());
        let start = if *robot == "amr-1" { [0.0, 0.0] } else { [0.0, 2.0] };
        let goal = [start[0] + 1.0, start[1]];
        within("put", client.put_primitive(robot, "go", &line(start.to_vec(), goal.to_vec(), 1.0)))
            .await
            .unwrap();
    }
    // Declared after the trajectories' subscribers on the same session: once the markers arrive (a put obstacle
    // changes the scene), the server has the subscriptions before it publishes a trajectory.
    let markers_key = topic_key(5, "/dmp/default/markers", &MARKER_ARRAY);
    let markers = within("subscribe", tool.declare_subscriber(&markers_key).into_future()).await.unwrap();
    let far = crate::ellipse("far", vec![10.0, 10.0], vec![0.2, 0.2]);
    within("put obstacle", client.put_obstacle(far)).await.unwrap();
    loop {
        let sample = within("markers", markers.recv_async()).await.unwrap();
        let array: MarkerArray = dmp_ros2::decode(&sample.payload().to_bytes()).unwrap();
        if array.markers.iter().any(|m| m.text == "far" && m.ns == "isopotentials") {
            break;
        }
    }

    let members = robots
        .iter()
        .map(|r| {
            // The DMP's own timing: the run lasts its second or so, and its segments fit the subscribers' queues
            // until they are read (the default profile would stretch it to several seconds).
            let mut motion = exact(spec(r, "go"));
            motion.ignore_scene = true;
            motion.footprint = Some(v1::Superquadric { semi_axes: vec![0.2, 0.2], exponents: vec![] });
            v1::GroupMember { motion: Some(motion) }
        })
        .collect();
    // Real time: the run lasts its second or so, over several periods of the markers.
    let request = v1::ExecuteGroupRequest {
        members,
        max_duration_s: 10.0,
        pacing: v1::Pacing::Realtime as i32,
        ..Default::default()
    };
    let mut stream = within("group", client.execute_group(request)).await.unwrap();
    let mut got: HashMap<String, Vec<v1::Segment>> = HashMap::new();
    while let Some(g) = within("group segment", stream.next()).await {
        for s in g.unwrap().segments {
            got.entry(s.robot_id.clone()).or_default().push(s);
        }
    }
    let counters = h.ros2_counters().unwrap();
    assert_eq!(Ros2Counters::get(&counters.trajectories_dropped), 0);
    for (robot, sub) in robots.iter().zip(&subscribers) {
        let segments = &got[*robot];
        assert!(segments.len() >= 2, "{robot}: {} segments", segments.len());
        let mut last_sequence = 0;
        for segment in segments {
            let sample = within("trajectory", sub.recv_async()).await.unwrap();
            let msg: MultiDOFJointTrajectory = dmp_ros2::decode(&sample.payload().to_bytes()).unwrap();
            assert_same(&msg, segment);
            let a = Attachment::decode(&sample.attachment().expect("an attachment").to_bytes()).unwrap();
            assert_eq!(a.sequence_number, last_sequence + 1, "{robot}: one sample per segment, in order");
            last_sequence = a.sequence_number;
        }
        assert!(sub.try_recv().unwrap().is_none(), "{robot}: more trajectories than segments");
    }
    assert_eq!(
        Ros2Counters::get(&counters.trajectories_published),
        got.values().map(Vec::len).sum::<usize>() as u64
    );

    // The markers: each robot's path (the positions sent) while it ran, then its DELETE.
    let mut paths: HashMap<String, (i32, Vec<[f64; 3]>)> = HashMap::new();
    let mut deleted = Vec::new();
    while deleted.len() < robots.len() {
        let sample = within("markers", markers.recv_async()).await.unwrap();
        let array: MarkerArray = dmp_ros2::decode(&sample.payload().to_bytes()).unwrap();
        for m in array.markers.into_iter().filter(|m| m.ns == "paths") {
            match m.action {
                Marker::ADD => {
                    paths.insert(m.text.clone(), (m.id, m.points.iter().map(|p| [p.x, p.y, p.z]).collect()));
                }
                Marker::DELETE => deleted.push(m.id),
                other => panic!("action {other}"),
            }
        }
    }
    for robot in robots {
        let (id, points) = &paths[robot];
        assert!(deleted.contains(id), "{robot}'s path not deleted");
        let sent: Vec<[f64; 3]> =
            got[robot].iter().flat_map(|s| rows(s, &s.positions)).map(|x| [x[0], x[1], 0.0]).collect();
        // The last path drawn before the DELETE: the positions sent so far (the end may have come within the same
        // period as the last segments).
        assert!(points.len() >= 2 && sent.starts_with(points), "{robot}: the path is not the positions sent");
    }
    within("tool close", tool.close().into_future()).await.unwrap();
    within("shutdown", h.shutdown()).await.unwrap();
}
