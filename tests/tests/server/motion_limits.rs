//! A robot's limits and the goal filter per request (`MotionSpec.limits`, `MotionSpec.goal_filter_alpha`): every
//! setpoint the robot keeps stays within its limits, measured as finite differences of the positions at the output
//! rate over the segments with supersession applied; a motion far beyond them is tracked within them, never backing
//! up for a run-up, to its goal; bad limits are refused naming the field.

use dmp::Limits;
use dmp_proto::limits::limits_to_proto;
use dmp_proto::v1;
use tokio_stream::StreamExt;

use crate::{line, rows, serve, spec};
use dmp_tests::within;

/// Every segment of an as-fast-as-read Execute of `motion` (30 s at most).
pub(crate) async fn executed(client: &dmp_client::DmpClient, motion: v1::MotionSpec) -> Vec<v1::Segment> {
    let request = v1::ExecuteRequest { motion: Some(motion), max_duration_s: 30.0, ..Default::default() };
    let mut stream = within("execute", client.execute(request)).await.unwrap();
    let mut segments = Vec::new();
    while let Some(s) = within("segment", stream.next()).await {
        segments.push(s.unwrap());
    }
    segments
}

/// The points a robot keeps: each segment supersedes the earlier ones from its start time on.
pub(crate) fn kept(segments: &[v1::Segment]) -> Vec<Vec<f64>> {
    let mut out: Vec<Vec<f64>> = Vec::new();
    for s in segments {
        let first = (s.start_time / s.dt).round() as usize;
        out.truncate(first);
        out.extend(rows(s, &s.positions));
    }
    out
}

/// Peak speed, acceleration and jerk of `x` as backward differences at `dt`, at rest before the first point.
pub(crate) fn peaks(x: &[Vec<f64>], dt: f64) -> [f64; 3] {
    let p = |k: isize| &x[k.max(0) as usize];
    let norm = |f: &dyn Fn(usize) -> f64| (0..x[0].len()).map(|i| f(i).powi(2)).sum::<f64>().sqrt();
    let mut peak = [0.0f64; 3];
    for k in 0..x.len() as isize {
        let (a, b, c, d) = (p(k), p(k - 1), p(k - 2), p(k - 3));
        let v = norm(&|i| (a[i] - b[i]) / dt);
        let acc = norm(&|i| (a[i] - 2.0 * b[i] + c[i]) / (dt * dt));
        let j = norm(&|i| (a[i] - 3.0 * b[i] + 3.0 * c[i] - d[i]) / (dt * dt * dt));
        for (m, q) in peak.iter_mut().zip([v, acc, j]) {
            *m = m.max(q);
        }
    }
    peak
}

fn within_limits(p: [f64; 3], l: &Limits) -> bool {
    p[0] <= l.max_speed && p[1] <= l.max_acceleration && p[2] <= l.max_jerk
}

#[tokio::test(flavor = "multi_thread")]
async fn a_goal_change_keeps_the_panda_profile_and_reaches_the_new_goal() {
    let dir = tempfile::tempdir().unwrap();
    let (handle, client) = serve(dir.path()).await;
    let reach = line(vec![0.3, 0.0, 0.4], vec![0.6, 0.2, 0.5], 2.0);
    within("put", client.put_primitive("panda", "reach", &reach)).await.unwrap();
    for alpha in [0.0, -1.0] {
        let mut motion = spec("panda", "reach");
        motion.ignore_scene = true;
        motion.limits = Some(limits_to_proto(&Limits::PANDA));
        motion.goal_filter_alpha = alpha;
        let start = v1::ExecuteRequest { motion: Some(motion), max_duration_s: 20.0, ..Default::default() };
        let mut session = within("session", client.session(start)).await.unwrap();
        let mut segments = Vec::new();
        for _ in 0..40 {
            segments.push(within("segment", session.next_segment()).await.unwrap().unwrap());
        }
        let new_goal = vec![0.6, 0.5, 0.5];
        within("set goal", session.set_goal(new_goal.clone())).await.unwrap();
        while let Some(s) = within("segment", session.next_segment()).await {
            segments.push(s.unwrap());
        }
        let last = segments.last().unwrap();
        assert_eq!(last.status, v1::SegmentStatus::GoalReached as i32, "alpha {alpha}");
        let x = kept(&segments);
        let end = x.last().unwrap();
        let err = end.iter().zip(&new_goal).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt();
        assert!(err <= 1e-3, "alpha {alpha}: ended {err} from the new goal");
        let p = peaks(&x, last.dt);
        assert!(within_limits(p, &Limits::PANDA), "alpha {alpha}: peaks {p:?}");
    }
    within("shutdown", handle.shutdown()).await.unwrap();
}

#[tokio::test(flavor = "multi_thread")]
async fn a_motion_far_beyond_the_limits_is_tracked_within_them_to_its_goal() {
    let dir = tempfile::tempdir().unwrap();
    let (handle, client) = serve(dir.path()).await;
    within("put", client.put_primitive("base", "dash", &line(vec![0.0; 2], vec![1.0, 0.0], 0.5)))
        .await
        .unwrap();
    let slow = Limits { max_speed: 0.8, max_acceleration: 1.0, max_jerk: 10.0, ..Limits::NONE };
    let mut motion = spec("base", "dash");
    motion.ignore_scene = true;
    motion.limits = Some(limits_to_proto(&slow));
    let segments = executed(&client, motion.clone()).await;
    let last = segments.last().unwrap();
    assert_eq!(last.status, v1::SegmentStatus::GoalReached as i32, "{:?}", last.verdict);
    let x = kept(&segments);
    let p = peaks(&x, segments[0].dt);
    assert!(within_limits(p, &slow), "peaks {p:?}");
    // The DMP runs at 2 m/s on average, the robot at 0.8 m/s at most: it follows from behind, never backing up
    // to gain speed towards a target just ahead.
    let back = x.windows(2).map(|w| w[0][0] - w[1][0]).fold(0.0, f64::max);
    assert!(back <= 1e-12, "backed up by {back} m in one step");
    // Bad limits are refused, naming the field (a negative one is none, explicitly: not bad).
    motion.limits = Some(v1::Limits { max_jerk: f64::NAN, ..limits_to_proto(&slow) });
    let e =
        within("execute", client.execute(v1::ExecuteRequest { motion: Some(motion), ..Default::default() }))
            .await
            .map(|_| ())
            .unwrap_err();
    assert_eq!(e.code(), Some(tonic::Code::InvalidArgument), "{e}");
    assert!(e.to_string().contains("motion.limits.max_jerk"), "{e}");
    within("shutdown", handle.shutdown()).await.unwrap();
}
