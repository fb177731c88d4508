//! "At the goal and at rest" per request: a stream ends in the segment where its tolerance is first met for good,
//! and says since when.

use dmp_proto::v1;
use tokio_stream::StreamExt;

use crate::{paper_curve, rows, serve, spec};
use dmp_tests::within;

/// Every segment of an as-fast-as-read stream of the paper's curve (tau 1 s), with `tolerance`.
async fn segments(client: &dmp_client::DmpClient, tolerance: Option<v1::GoalTolerance>) -> Vec<v1::Segment> {
    let mut motion = spec("r", "curve");
    motion.ignore_scene = true;
    motion.goal_tolerance = tolerance;
    let request = v1::ExecuteRequest { motion: Some(motion), max_duration_s: 10.0, ..Default::default() };
    let mut stream = within("execute", client.execute(request)).await.unwrap();
    let mut out = Vec::new();
    while let Some(s) = within("segment", stream.next()).await {
        out.push(s.unwrap());
    }
    out
}

/// The time of the first point of the last unbroken run of points within `tol` of `goal`, counted here.
fn first_met(segments: &[v1::Segment], goal: &[f64], tol: (f64, f64)) -> Option<f64> {
    let mut since = None;
    for s in segments {
        for (k, (x, v)) in rows(s, &s.positions).iter().zip(rows(s, &s.velocities)).enumerate() {
            let dist = x.iter().zip(goal).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt();
            let speed = v.iter().map(|a| a * a).sum::<f64>().sqrt();
            if dist <= tol.0 && speed <= tol.1 {
                since = since.or(Some(s.start_time + k as f64 * s.dt));
            } else {
                since = None;
            }
        }
    }
    since
}

#[tokio::test(flavor = "multi_thread")]
async fn a_stream_reports_when_its_goal_tolerance_was_first_met() {
    let dir = tempfile::tempdir().unwrap();
    let (handle, client) = serve(dir.path()).await;
    let (t, x) = paper_curve();
    let record = within("learn", client.learn("r", "curve", &t, &x, Default::default())).await.unwrap();
    let goal = record.primitive.unwrap().goal;
    let mut ends = Vec::new();
    for (tolerance, tol) in [
        (None, (1e-3, 1e-3)),
        (Some(v1::GoalTolerance { position: 0.0, speed: 1e-2, ..Default::default() }), (1e-3, 1e-2)),
        (Some(v1::GoalTolerance { position: 1e-2, speed: 0.1, ..Default::default() }), (1e-2, 0.1)),
    ] {
        let segs = segments(&client, tolerance).await;
        let last = segs.last().unwrap();
        assert_eq!(last.status, v1::SegmentStatus::GoalReached as i32, "{tol:?}");
        assert!(segs[..segs.len() - 1].iter().all(|s| s.goal_reached_time == 0.0), "{tol:?}");
        let counted = first_met(&segs, &goal, tol).unwrap();
        assert!(
            (last.goal_reached_time - counted).abs() < 1e-9,
            "{tol:?}: {} against {counted}",
            last.goal_reached_time
        );
        let end = last.start_time + last.dt * (rows(last, &last.positions).len() - 1) as f64;
        assert!(last.goal_reached_time <= end + 1e-9, "{tol:?}");
        ends.push(end);
    }
    // A looser tolerance ends the run no later.
    assert!(ends.windows(2).all(|w| w[1] <= w[0]), "{ends:?}");
    assert!(ends[2] < ends[0], "{ends:?}");
    // A tolerance that cannot be met is refused, naming its field.
    let mut motion = spec("r", "curve");
    motion.goal_tolerance = Some(v1::GoalTolerance { position: 1e-3, speed: -1.0, ..Default::default() });
    let e =
        within("execute", client.execute(v1::ExecuteRequest { motion: Some(motion), ..Default::default() }))
            .await
            .map(|_| ())
            .unwrap_err();
    assert_eq!(e.code(), Some(tonic::Code::InvalidArgument), "{e}");
    assert!(e.to_string().contains("motion.goal_tolerance.speed"), "{e}");
    within("shutdown", handle.shutdown()).await.unwrap();
}
