//! The client library's calls against the real server (gRPC only): primitives, execution streams, sessions.

use dmp_client::grpc::{collect_setpoints, record_primitive};
use dmp_client::setpoints::segments_to_trajectory;
use dmp_client::{ClientError, DmpClient, Setpoints};
use dmp_proto::v1;
use dmp_tests::{TestServer, within};
use tokio_stream::StreamExt;

/// Points per segment of the server's streams by default: segments of 10 ms at dt = 1 ms.
const SEGMENT_POINTS: usize = 10;

fn demo() -> (Vec<f64>, Vec<Vec<f64>>) {
    let t: Vec<f64> = (0..=200).map(|k| k as f64 / 200.0).collect();
    let x = t.iter().map(|t| vec![t * t, (3.0 * t).sin()]).collect();
    (t, x)
}

#[tokio::test(flavor = "multi_thread")]
async fn primitives_learn_get_list_put_delete() {
    let server = TestServer::grpc_only().await;
    // A bare HOST:PORT means http://.
    let c = within("connect", DmpClient::connect(server.handle().grpc_addr.to_string())).await.unwrap();
    let (t, x) = demo();
    let params = v1::LearnParameters { n_basis: 20, ..Default::default() };
    let r = within("learn", c.learn("r1", "wave", &t, &x, params)).await.unwrap();
    assert_eq!((r.version, r.robot_id.as_str(), r.name.as_str()), (1, "r1", "wave"));
    let p = record_primitive(&r).unwrap();
    assert_eq!((p.dim, p.n_basis), (2, 20));
    let again = within("put", c.put_primitive("r1", "wave", &p)).await.unwrap();
    assert_eq!(again.version, 2);
    assert_eq!(record_primitive(&within("get", c.get("r1", "wave", 1)).await.unwrap()).unwrap(), p);
    let other = within("put other", c.put_primitive("r2", "other", &p)).await.unwrap();
    assert_eq!((other.robot_id.as_str(), other.version), ("r2", 1));
    let listed = within("list", c.list("r1")).await.unwrap();
    assert_eq!(listed.iter().map(|r| (r.name.as_str(), r.version)).collect::<Vec<_>>(), [("wave", 2)]);
    assert_eq!(within("delete", c.delete("r1", "wave")).await.unwrap(), 2);
    assert!(within("list after delete", c.list("r1")).await.unwrap().is_empty());

    let e = within("get deleted", c.get("r1", "wave", 0)).await.unwrap_err();
    assert_eq!(e.code(), Some(tonic::Code::NotFound));
    assert!(e.is_bad_input() && e.to_string().contains("wave"), "{e}");
    let e = within("learn one sample", c.learn("r1", "one", &t[..1], &x[..1], Default::default()))
        .await
        .unwrap_err();
    assert_eq!(e.code(), Some(tonic::Code::InvalidArgument), "{e}");
    assert!(e.is_bad_input());
    let mut ragged = x.clone();
    ragged[3].push(1.0);
    let e = within("learn ragged", c.learn("r1", "bad", &t, &ragged, Default::default())).await.unwrap_err();
    assert!(e.to_string().contains("demonstration.x[3]"), "{e}");
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread")]
async fn execute_streams_reassemble_into_the_plan() {
    let server = TestServer::grpc_only().await;
    let c = server.client().await;
    let (t, x) = demo();
    within("learn", c.learn("r", "p", &t, &x, Default::default())).await.unwrap();
    let motion = v1::MotionSpec { robot_id: "r".into(), primitive: "p".into(), ..Default::default() };
    let plan =
        within("plan", c.plan(v1::PlanRequest { motion: Some(motion.clone()), dt: 0.002, duration: 0.5 }))
            .await
            .unwrap();
    let planned = segments_to_trajectory(plan.trajectory.as_ref()).unwrap();
    assert_eq!(planned.len(), 251);
    let request =
        v1::ExecuteRequest { motion: Some(motion), dt: 0.002, max_duration_s: 0.5, ..Default::default() };
    let stream = within("execute", c.execute(request)).await.unwrap();
    let mut seen = 0;
    let s = within("read the stream", collect_setpoints(stream, |_| seen += 1)).await.unwrap();
    // The default 10 ms segment is 5 points at dt = 2 ms: 50 segments, then the point at exactly 0.5 s.
    assert_eq!(seen, 51);
    // The goal is not reached by 0.5 s: the run ends at its maximum duration.
    assert_eq!(s.last_status(), Some(v1::SegmentStatus::Stopped));
    let streamed = s.into_trajectory();
    assert_eq!((streamed.x.clone(), streamed.xd.clone()), (planned.x.clone(), planned.xd.clone()));
    assert!(streamed.t.iter().zip(&planned.t).all(|(a, b)| (a - b).abs() < 1e-12));
    server.stop().await;
}

/// The row of `traj` at time `t` (a multiple of `dt`).
fn row(traj: &dmp::Trajectory, t: f64, dt: f64) -> usize {
    let k = (t / dt).round() as usize;
    assert!((traj.t[k] - t).abs() < 1e-9 * dt.max(1.0), "row {k} is at {}, not {t}", traj.t[k]);
    k
}

#[tokio::test(flavor = "multi_thread")]
async fn a_session_sends_commands_and_receives_superseding_segments() {
    let server = TestServer::grpc_only().await;
    let c = server.client().await;
    let (t, x) = demo();
    within("learn", c.learn("r", "p", &t, &x, Default::default())).await.unwrap();
    // Real time, computed a second ahead of the wall clock: the first second is sent at once and a command
    // supersedes most of it. tau = 4 (four times slower than the demonstration): the new goal is seconds away,
    // so the run cannot reach it before it is stopped.
    let motion = v1::MotionSpec {
        robot_id: "r".into(),
        primitive: "p".into(),
        tau: 4.0,
        ignore_scene: true,
        // The DMP's own run, which the plan and the stream compare bit for bit.
        limits: Some(dmp_proto::limits::NO_LIMITS),
        margin: -1.0,
        ..Default::default()
    };
    // Where the run goes without commands.
    let plan = v1::PlanRequest { motion: Some(motion.clone()), dt: 0.001, duration: 2.0 };
    let plan = within("plan", c.plan(plan)).await.unwrap();
    let planned = segments_to_trajectory(plan.trajectory.as_ref()).unwrap();
    let start = v1::ExecuteRequest {
        motion: Some(motion),
        pacing: v1::Pacing::Realtime as i32,
        lookahead_s: 1.0,
        ..Default::default()
    };
    let mut session = within("session", c.session(start)).await.unwrap();
    let mut s = Setpoints::new();
    let first = within("segment 0", session.next_segment()).await.unwrap().unwrap();
    assert_eq!((first.sequence, first.start_time, first.dt), (0, 0.0, 0.001));
    s.push(&first).unwrap();
    assert_eq!(s.trajectory().unwrap().len(), SEGMENT_POINTS);
    let sender = session.sender();
    let goal = [9.0, 8.0];
    within("set goal", sender.set_goal(goal.to_vec())).await.unwrap();

    // Segments sent before the goal arrived come first; the first one computed after it starts at the robot's
    // current time, before the end of what was sent: it supersedes the rest.
    let mut sequence = 0;
    let (seg, before) = loop {
        let seg = within("segment", session.next_segment()).await.expect("the run goes on").unwrap();
        sequence += 1;
        assert_eq!(seg.sequence, sequence);
        assert_eq!(seg.status(), v1::SegmentStatus::Running);
        let before = s.trajectory().unwrap().clone();
        s.push(&seg).unwrap();
        if seg.start_time < before.t[before.len() - 1] + 0.5 * seg.dt {
            break (seg, before);
        }
    };
    assert!(seg.start_time > 0.0, "applied from the current state, not from the start");
    // Until then, the setpoints sent were the plan's.
    assert_eq!(before.x, planned.x[..before.x.len()]);
    let k = row(&before, seg.start_time, seg.dt);
    let traj = s.trajectory().unwrap();
    assert_eq!(traj.len(), k + SEGMENT_POINTS, "rows from {} s on are superseded", seg.start_time);
    // Continuous: it starts from the state already sent for that time; only the acceleration changes.
    assert_eq!((traj.position(k), traj.velocity(k)), (before.position(k), before.velocity(k)));
    assert!(traj.acceleration(k) != before.acceleration(k));
    // Half a second later, the run is well on its way to the new goal, far from the plan.
    let later = seg.start_time + 0.5;
    while s.trajectory().unwrap().t.last().unwrap() + 0.5 * seg.dt < later {
        let seg = within("segment", session.next_segment()).await.expect("the run goes on").unwrap();
        assert_eq!(seg.status(), v1::SegmentStatus::Running);
        s.push(&seg).unwrap();
    }
    let traj = s.trajectory().unwrap();
    let was = planned.position(row(&planned, later, seg.dt));
    let now = traj.position(row(traj, later, seg.dt));
    for i in 0..2 {
        assert!(now[i] > was[i] + 0.5, "not heading for the new goal: {now:?} (was {was:?})");
    }

    // Stop: superseding again, the robot decelerates to rest and the stream ends with STOPPED.
    within("stop", session.stop()).await.unwrap();
    let (_, mut rest) = session.into_parts();
    let mut superseded = false;
    let mut last = None;
    while let Some(seg) = within("segment", rest.next()).await {
        let seg = seg.unwrap();
        superseded |= seg.start_time + 0.5 * seg.dt < *s.trajectory().unwrap().t.last().unwrap();
        s.push(&seg).unwrap();
        last = Some(seg);
    }
    assert!(superseded, "the stop did not supersede what was sent ahead");
    assert_eq!(last.expect("segments after the stop").status(), v1::SegmentStatus::Stopped);
    let traj = s.trajectory().unwrap();
    let v = traj.velocity(traj.len() - 1);
    assert!(v.iter().map(|v| v * v).sum::<f64>().sqrt() < 2e-3, "not at rest: {v:?}");
    // The session is over: once the server has dropped the call, commands fail.
    drop(rest);
    let e = within("a command after the end", async {
        loop {
            if let Err(e) = sender.pause().await {
                break e;
            }
        }
    })
    .await;
    assert!(matches!(e, ClientError::Closed(_)), "{e}");
    drop(sender);
    server.stop().await;
}
