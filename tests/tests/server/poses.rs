//! Poses over the wire: a primitive learned from positions and orientations streams unit quaternions with their
//! angular velocities and accelerations, reaches a new goal orientation (also one changed mid-session), and a
//! position primitive keeps working unchanged and refuses orientations with the field at fault.

use dmp_proto::v1;
use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use tokio_stream::StreamExt;

use crate::{rows, serve, spec};
use dmp_tests::within;

const DT: f64 = 1e-3;

fn min_jerk(u: f64) -> f64 {
    let u = u.clamp(0.0, 1.0);
    u * u * u * (10.0 + u * (-15.0 + 6.0 * u))
}

fn xyzw(q: &UnitQuaternion<f64>) -> [f64; 4] {
    [q.i, q.j, q.k, q.w]
}

fn quaternion(v: &[f64]) -> UnitQuaternion<f64> {
    UnitQuaternion::new_unchecked(Quaternion::new(v[3], v[0], v[1], v[2]))
}

/// A 2 s reach of 0.3 m that turns 90° about a tilted axis (minimum jerk, 1 kHz): times, positions, orientations.
fn pose_demo() -> (Vec<f64>, Vec<Vec<f64>>, Vec<[f64; 4]>) {
    let t: Vec<f64> = (0..=2000).map(|k| k as f64 * DT).collect();
    let axis = Vector3::new(0.3, -0.5, 0.8).normalize();
    let x = t.iter().map(|&t| vec![0.3 * min_jerk(t / 2.0), 0.1, 0.2]).collect();
    let q = t
        .iter()
        .map(|&t| {
            xyzw(&UnitQuaternion::from_scaled_axis(axis * (std::f64::consts::FRAC_PI_2 * min_jerk(t / 2.0))))
        })
        .collect();
    (t, x, q)
}

async fn collect(mut stream: dmp_client::grpc::SegmentStream) -> Vec<v1::Segment> {
    let mut out = Vec::new();
    while let Some(s) = within("segment", stream.next()).await {
        out.push(s.unwrap());
    }
    out
}

/// Every segment's orientations are unit quaternions, one per point, with 3 angular values per point.
fn check_orientations(segments: &[v1::Segment]) -> Vec<UnitQuaternion<f64>> {
    let mut all = Vec::new();
    for s in segments {
        let n = rows(s, &s.positions).len();
        assert_eq!(s.dim, 3, "positions only in `positions`");
        assert_eq!(s.orientations.len(), 4 * n);
        assert_eq!(s.angular_velocities.len(), 3 * n);
        assert_eq!(s.angular_accelerations.len(), 3 * n);
        for q in s.orientations.chunks_exact(4) {
            let norm = q.iter().map(|v| v * v).sum::<f64>().sqrt();
            assert!((norm - 1.0).abs() <= 1e-12, "norm {norm}");
            all.push(quaternion(q));
        }
    }
    all
}

#[tokio::test(flavor = "multi_thread")]
async fn a_pose_primitive_streams_unit_quaternions_to_a_new_goal_orientation() {
    let dir = tempfile::tempdir().unwrap();
    let (handle, client) = serve(dir.path()).await;
    let (t, x, q) = pose_demo();
    let record =
        within("learn", client.learn_pose("arm", "turn", &t, &x, &q, Default::default())).await.unwrap();
    let p = record.primitive.unwrap();
    assert_eq!(p.dim, 6, "3 positions and the 3 coordinates of the orientation");
    assert_eq!(p.orientation_reference.len(), 4);

    let goal = UnitQuaternion::from_scaled_axis(Vector3::new(0.2, 0.9, -0.3));
    let mut motion = spec("arm", "turn");
    motion.ignore_scene = true;
    motion.goal_orientation = xyzw(&goal).to_vec();
    let request =
        v1::ExecuteRequest { motion: Some(motion.clone()), max_duration_s: 8.0, ..Default::default() };
    let segments = collect(within("execute", client.execute(request)).await.unwrap()).await;
    let last = segments.last().unwrap();
    assert_eq!(last.status, v1::SegmentStatus::GoalReached as i32);
    let qs = check_orientations(&segments);
    assert!(qs[0].angle_to(&quaternion(&q[0])) < 1e-9, "starts at the primitive's start");
    let error = qs.last().unwrap().angle_to(&goal).to_degrees();
    assert!(error <= 0.1, "ends {error}° from the goal");
    let end = rows(last, &last.positions).pop().unwrap();
    assert!((end[0] - 0.3).abs() < 1e-3, "the position part reaches its goal too: {end:?}");

    // The plan of the same request carries the same orientations.
    let plan = within("plan", client.plan(v1::PlanRequest { motion: Some(motion), dt: DT, duration: 3.0 }))
        .await
        .unwrap();
    let planned = plan.trajectory.unwrap();
    let planned_q = check_orientations(std::slice::from_ref(&planned));
    for (a, b) in planned_q.iter().zip(&qs) {
        assert!(a.angle_to(b) < 1e-9);
    }
    within("shutdown", handle.shutdown()).await.unwrap();
}

#[tokio::test(flavor = "multi_thread")]
async fn a_goal_orientation_changed_mid_session_is_reached() {
    let dir = tempfile::tempdir().unwrap();
    let (handle, client) = serve(dir.path()).await;
    let (t, x, q) = pose_demo();
    within("learn", client.learn_pose("arm", "turn", &t, &x, &q, Default::default())).await.unwrap();
    let mut motion = spec("arm", "turn");
    motion.ignore_scene = true;
    motion.tau = 20.0;
    let start = v1::ExecuteRequest { motion: Some(motion), max_duration_s: 40.0, ..Default::default() };
    let mut session = within("session", client.session(start)).await.unwrap();
    for _ in 0..5 {
        within("segment", session.next_segment()).await.unwrap().unwrap();
    }
    let goal = UnitQuaternion::from_scaled_axis(Vector3::new(-0.6, 0.1, 0.4));
    within("set goal", session.set_pose_goal(vec![], Some(xyzw(&goal)))).await.unwrap();
    // Faster, so that the test ends soon.
    within("set tau", session.set_tau(1.0)).await.unwrap();
    let mut segments = Vec::new();
    while let Some(s) = within("segment", session.next_segment()).await {
        let s = s.unwrap();
        let done = s.status == v1::SegmentStatus::GoalReached as i32;
        segments.push(s);
        if done {
            break;
        }
    }
    let qs = check_orientations(&segments);
    assert!(qs.last().unwrap().angle_to(&goal).to_degrees() <= 0.1);
    within("shutdown", handle.shutdown()).await.unwrap();
}

#[tokio::test(flavor = "multi_thread")]
async fn orientations_are_refused_where_they_cannot_apply() {
    let dir = tempfile::tempdir().unwrap();
    let (handle, client) = serve(dir.path()).await;
    let (t, x, q) = pose_demo();
    within("learn", client.learn("plain", "reach", &t, &x, Default::default())).await.unwrap();
    let mut motion = spec("plain", "reach");
    motion.goal_orientation = vec![0.0, 0.0, 0.0, 1.0];
    let e = within("plan", client.plan(v1::PlanRequest { motion: Some(motion), dt: DT, duration: 1.0 }))
        .await
        .unwrap_err();
    assert_eq!(e.code(), Some(tonic::Code::InvalidArgument), "{e}");
    assert!(e.to_string().contains("motion.goal_orientation"), "{e}");

    within("learn", client.learn_pose("arm", "turn", &t, &x, &q, Default::default())).await.unwrap();
    let mut motion = spec("arm", "turn");
    motion.goal_orientation = vec![0.0, 0.0, 0.0, 2.0];
    let e = within("plan", client.plan(v1::PlanRequest { motion: Some(motion), dt: DT, duration: 1.0 }))
        .await
        .unwrap_err();
    assert!(e.to_string().contains("motion.goal_orientation"), "{e}");
    assert!(e.to_string().contains("unit quaternion"), "{e}");

    // A tool costs a field evaluation per control point and step: a huge one is refused before any work.
    let mut motion = spec("arm", "turn");
    motion.tool = Some(v1::Tool {
        shape: Some(v1::Superquadric { semi_axes: vec![0.3, 0.01, 0.01], exponents: vec![] }),
        control_points: 100_000,
        ..Default::default()
    });
    let e =
        within("plan", client.plan(v1::PlanRequest { motion: Some(motion.clone()), dt: DT, duration: 1.0 }))
            .await
            .unwrap_err();
    assert_eq!(e.code(), Some(tonic::Code::InvalidArgument), "{e}");
    assert!(e.to_string().contains("motion.tool.control_points"), "{e}");
    // A tool of a sane size is taken.
    motion.tool.as_mut().unwrap().control_points = 0;
    motion.ignore_scene = true;
    let plan = within("plan", client.plan(v1::PlanRequest { motion: Some(motion), dt: DT, duration: 1.0 }))
        .await
        .unwrap();
    assert!(plan.trajectory.is_some_and(|t| t.orientations.len() == 4 * 1001));

    let mut bad = q.clone();
    bad[7] = [0.0, 0.0, 0.0, 0.5];
    let e =
        within("learn", client.learn_pose("arm", "bad", &t, &x, &bad, Default::default())).await.unwrap_err();
    assert!(e.to_string().contains("demonstration.orientations[7]"), "{e}");
    within("shutdown", handle.shutdown()).await.unwrap();
}
