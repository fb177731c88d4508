//! Obstacles published over Zenoh: they change a running stream, and clearing them is seen too.

use dmp::Isopotential;
use dmp_client::zenoh_pub::ObstaclePublisher;
use dmp_proto::v1;
use tokio_stream::StreamExt;

use crate::default_limits::exact;
use crate::{dynamic_volumetric, line, serve, spec};
use dmp_tests::{T, within};

#[tokio::test(flavor = "multi_thread")]
async fn an_obstacle_published_over_zenoh_changes_the_stream_and_is_cleared() {
    let dir = tempfile::tempdir().unwrap();
    let (handle, client) = serve(dir.path()).await;
    within("put", client.put_primitive("youbot", "corridor", &line(vec![0.0, 0.0], vec![1.0, 0.0], 1.0)))
        .await
        .unwrap();
    let perception =
        within("zenoh open", ObstaclePublisher::open("default", &handle.zenoh_locators, &[])).await.unwrap();
    within("subscriber", perception.wait_for_subscriber(T)).await.unwrap();

    // A real-time robot: segments arrive 50 ms ahead of the wall clock. Without limits: the DMP swerves round
    // the obstacle and arrives in time, as the paper's potential has it.
    let mut motion = exact(spec("youbot", "corridor"));
    motion.avoidance = Some(dynamic_volumetric(10.0, 2.0, 0.5));
    let request = v1::ExecuteRequest {
        motion: Some(motion),
        pacing: v1::Pacing::Realtime as i32,
        max_duration_s: 4.0,
        ..Default::default()
    };
    let mut stream = within("execute", client.execute(request)).await.unwrap();
    let mut segments = Vec::new();
    // Wall clock (Unix seconds) at which each segment arrived.
    let mut arrivals = Vec::new();
    let now = || std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap().as_secs_f64();
    while segments.len() < 8 {
        segments.push(within("segment", stream.next()).await.unwrap().unwrap());
        arrivals.push(now());
    }
    assert!(segments.iter().all(|s| s.scene_version == 0));
    let obstacle = serde_json::json!({"center": [0.6, 0.03], "semi_axes": [0.1, 0.1], "exponents": [1, 1]});
    let put_at = segments.last().unwrap().start_time;
    within("put obstacle", perception.put_json("box", &obstacle)).await.unwrap();
    while let Some(s) = within("segment", stream.next()).await {
        segments.push(s.unwrap());
        arrivals.push(now());
    }
    let last = segments.last().unwrap();
    assert_eq!(last.status, v1::SegmentStatus::GoalReached as i32, "ended with {:?}", last.status);
    let first_new =
        segments.iter().position(|s| s.scene_version >= 1).expect("a segment accounts for the obstacle");
    // It supersedes what was sent ahead: it starts before the last segment sent with the old scene ended.
    let old_end = segments[first_new - 1].start_time + 0.01;
    assert!(
        segments[first_new].start_time < old_end,
        "no supersession: {} >= {old_end}",
        segments[first_new].start_time
    );
    assert!(
        segments[first_new].start_time < put_at + 0.2,
        "applied late: {}",
        segments[first_new].start_time
    );
    // From the robot's current time (plus the 10 ms rollback margin), not from the end of what was kept for
    // rollbacks: the stream runs up to 90 ms ahead, and all of it can be superseded.
    // The run time at which it arrived (negative before the first point is due).
    let seg = &segments[first_new];
    let arrived_at = arrivals[first_new] - (seg.start_unix_s - seg.start_time);
    let ahead = seg.start_time - arrived_at.max(0.0);
    assert!(
        ahead <= 0.015,
        "the superseding segment starts {ahead} s after it arrived (run time {arrived_at})"
    );
    // The current setpoints (later segments supersede earlier ones) clear the true shape and bend around it.
    let mut setpoints = dmp_client::setpoints::Setpoints::new();
    for s in &segments {
        setpoints.push(s).unwrap();
    }
    let traj = setpoints.into_trajectory();
    let shape = dmp::Superquadric::ellipsoid(vec![0.1, 0.1]).unwrap();
    let mut max_y: f64 = 0.0;
    for k in 0..traj.len() {
        let p = traj.position(k);
        assert!(shape.value(&[p[0] - 0.6, p[1] - 0.03]) > 0.0, "inside the obstacle at {p:?}");
        max_y = max_y.max(p[1].abs());
    }
    assert!(max_y > 0.02, "the path did not bend around the obstacle (max |y| = {max_y})");
    let end = traj.position(traj.len() - 1);
    assert!((end[0] - 1.0).abs() < 1e-2 && end[1].abs() < 1e-2, "ended at {end:?}");
    within("shutdown", handle.shutdown()).await.unwrap();
}
