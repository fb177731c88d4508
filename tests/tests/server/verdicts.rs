//! How a run ended ([`v1::Verdict`]), on a plan and on a stream's last segment, and the runs refused before they
//! start: a start or a goal inside an obstacle's true shape (FAILED_PRECONDITION), a session's new goal inside one (a
//! rejected command).

use dmp_client::DmpClient;
use dmp_proto::v1;
use tokio_stream::StreamExt;

use crate::{ellipse, line, serve, spec};
use dmp_tests::within;

/// A thin wall across the straight line from (0, 0) to (1, 0), at x = 0.5.
fn wall() -> v1::Obstacle {
    v1::Obstacle {
        id: "wall".into(),
        shape: Some(v1::obstacle::Shape::Superquadric(v1::Superquadric {
            semi_axes: vec![0.05, 0.5],
            exponents: vec![4.0, 4.0],
        })),
        center: vec![0.5, 0.0],
        ..Default::default()
    }
}

fn no_avoidance() -> v1::Avoidance {
    v1::Avoidance { method: Some(v1::avoidance::Method::None(v1::avoidance::None {})), ..Default::default() }
}

/// A server with robot `r`'s straight line `line` (tau 1 s) from (0, 0) to (1, 0).
async fn with_line(dir: &std::path::Path) -> (dmp_server::server::ServerHandle, DmpClient) {
    let (handle, client) = serve(dir).await;
    within("put", client.put_primitive("r", "line", &line(vec![0.0, 0.0], vec![1.0, 0.0], 1.0)))
        .await
        .unwrap();
    (handle, client)
}

fn outcome(v: &v1::Verdict) -> v1::Outcome {
    v1::Outcome::try_from(v.outcome).unwrap()
}

async fn all_segments(mut stream: dmp_client::grpc::SegmentStream) -> Vec<v1::Segment> {
    let mut out = Vec::new();
    while let Some(s) = within("segment", stream.next()).await {
        out.push(s.unwrap());
    }
    out
}

/// Without avoidance, at the server's default limits and safety distance, a plan towards a wall brakes before the
/// margin and is held there (BLOCKED, never closer than the margin); with the margin off, it goes through the wall and
/// the verdict is a collision naming it.
#[tokio::test(flavor = "multi_thread")]
async fn a_plan_through_a_wall_without_avoidance_is_blocked_before_it_or_a_collision_without_a_margin() {
    let dir = tempfile::tempdir().unwrap();
    let (handle, client) = with_line(dir.path()).await;
    let mut motion = spec("r", "line");
    motion.ignore_scene = true;
    motion.extra_obstacles = vec![wall()];
    motion.avoidance = Some(no_avoidance());
    let plan = |motion: &v1::MotionSpec| v1::PlanRequest {
        motion: Some(motion.clone()),
        duration: 3.0,
        ..Default::default()
    };
    let r = within("plan", client.plan(plan(&motion))).await.unwrap();
    let v = r.verdict.expect("a plan has a verdict");
    assert_eq!(outcome(&v), v1::Outcome::Blocked, "{v:?}");
    assert!(v.collisions.is_empty() && r.collisions.is_empty(), "{v:?}");
    assert!(v.reason.starts_with("held before an obstacle's safety distance"), "{}", v.reason);
    let margin = r.limits.as_ref().map(|l| l.margin).unwrap_or_default();
    assert!(margin > 0.0, "the server's default margin is in force");
    let clearance = v.min_clearance.expect("a clearance with an obstacle");
    assert!(
        clearance >= margin - 1e-9 && clearance < margin + 0.01,
        "clearance {clearance} m, margin {margin} m"
    );

    // The margin off (the paper's experiments): straight through, a collision naming the wall.
    motion.margin = -1.0;
    let r = within("plan", client.plan(plan(&motion))).await.unwrap();
    let v = r.verdict.expect("a plan has a verdict");
    assert_eq!(outcome(&v), v1::Outcome::Collision, "{v:?}");
    assert_eq!(v.collisions, vec!["wall".to_string()]);
    assert!(v.reason.starts_with("collision with obstacle 'wall' at t = "), "{}", v.reason);
    assert!(v.min_clearance.is_some_and(|c| c < 0.0), "{v:?}");
    assert_eq!(r.collisions, vec!["wall".to_string()]);
    // The trajectory (the plan's only segment) carries the same verdict.
    assert_eq!(r.trajectory.unwrap().verdict.as_ref(), Some(&v));
    within("shutdown", handle.shutdown()).await.unwrap();
}

#[tokio::test(flavor = "multi_thread")]
async fn a_plan_too_short_for_its_goal_is_out_of_time_with_the_distance_left() {
    let dir = tempfile::tempdir().unwrap();
    let (handle, client) = with_line(dir.path()).await;
    let mut motion = spec("r", "line");
    motion.ignore_scene = true;
    let short = v1::PlanRequest { motion: Some(motion.clone()), duration: 0.3, ..Default::default() };
    let r = within("plan", client.plan(short)).await.unwrap();
    let v = r.verdict.unwrap();
    assert_eq!(outcome(&v), v1::Outcome::OutOfTime, "{v:?}");
    assert!(!v.goal_reached);
    let seg = r.trajectory.unwrap();
    let last = &seg.positions[seg.positions.len() - 2..];
    let left = ((last[0] - 1.0).powi(2) + last[1].powi(2)).sqrt();
    assert!(left > 0.05 && (v.goal_distance - left).abs() < 1e-9, "{} against {left}", v.goal_distance);
    assert!(
        v.reason.contains(&format!("ended {left:.3} m short of the goal"))
            && v.reason.contains("out of time"),
        "{}",
        v.reason
    );
    assert!(v.collisions.is_empty() && v.min_clearance.is_none(), "{v:?}");
    // Long enough, the same plan reaches its goal.
    let long = v1::PlanRequest { motion: Some(motion), duration: 4.0, ..Default::default() };
    let v = within("plan", client.plan(long)).await.unwrap().verdict.unwrap();
    assert_eq!(outcome(&v), v1::Outcome::GoalReached, "{v:?}");
    assert!(v.goal_reached && v.goal_distance < 1e-3, "{v:?}");
    within("shutdown", handle.shutdown()).await.unwrap();
}

#[tokio::test(flavor = "multi_thread")]
async fn a_stream_that_reaches_its_goal_says_so_on_its_last_segment_only() {
    let dir = tempfile::tempdir().unwrap();
    let (handle, client) = with_line(dir.path()).await;
    let mut motion = spec("r", "line");
    motion.ignore_scene = true;
    let request = v1::ExecuteRequest { motion: Some(motion), max_duration_s: 10.0, ..Default::default() };
    let segs = all_segments(within("execute", client.execute(request)).await.unwrap()).await;
    let (last, before) = segs.split_last().unwrap();
    assert!(before.iter().all(|s| s.verdict.is_none()), "a verdict before the last segment");
    let v = last.verdict.as_ref().expect("the last segment has a verdict");
    assert_eq!(last.status, v1::SegmentStatus::GoalReached as i32);
    assert_eq!(outcome(v), v1::Outcome::GoalReached, "{v:?}");
    assert!(v.goal_reached && v.goal_distance <= 1e-3 && v.collisions.is_empty(), "{v:?}");
    assert!(v.reason.contains("reached the goal"), "{}", v.reason);
    // Cut short by max_duration_s, the run is out of time and says where.
    let mut motion = spec("r", "line");
    motion.ignore_scene = true;
    let request = v1::ExecuteRequest { motion: Some(motion), max_duration_s: 0.4, ..Default::default() };
    let segs = all_segments(within("execute", client.execute(request)).await.unwrap()).await;
    let v = segs.last().unwrap().verdict.clone().unwrap();
    assert_eq!(outcome(&v), v1::Outcome::OutOfTime, "{v:?}");
    assert!(v.reason.contains("at max_duration_s"), "{}", v.reason);
    within("shutdown", handle.shutdown()).await.unwrap();
}

#[tokio::test(flavor = "multi_thread")]
async fn a_stopped_session_ends_stopped() {
    let dir = tempfile::tempdir().unwrap();
    let (handle, client) = with_line(dir.path()).await;
    let mut motion = spec("r", "line");
    motion.ignore_scene = true;
    let start = v1::ExecuteRequest { motion: Some(motion), max_duration_s: 10.0, ..Default::default() };
    let mut session = within("session", client.session(start)).await.unwrap();
    let first = within("segment", session.next_segment()).await.unwrap().unwrap();
    assert!(first.verdict.is_none());
    within("stop", session.stop()).await.unwrap();
    let mut last = first;
    while let Some(s) = within("segment", session.next_segment()).await {
        let s = s.unwrap();
        if s.verdict.is_some() {
            last = s;
            break;
        }
        last = s;
    }
    let v = last.verdict.expect("the last segment has a verdict");
    assert_eq!(outcome(&v), v1::Outcome::Stopped, "{v:?}");
    assert!(!v.goal_reached && v.goal_distance > 0.1, "{v:?}");
    assert!(v.reason.starts_with("stopped on request"), "{}", v.reason);
    within("shutdown", handle.shutdown()).await.unwrap();
}

#[tokio::test(flavor = "multi_thread")]
async fn a_start_or_goal_inside_an_obstacle_is_refused_before_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let (handle, client) = with_line(dir.path()).await;
    within("obstacle", client.put_obstacle(wall())).await.unwrap();
    let mut inside = spec("r", "line");
    inside.goal = vec![0.5, 0.1];
    let e =
        within("plan", client.plan(v1::PlanRequest { motion: Some(inside.clone()), ..Default::default() }))
            .await
            .unwrap_err();
    let text = e.to_string();
    assert_eq!(e.code(), Some(tonic::Code::FailedPrecondition), "{e}");
    assert!(
        text.contains("motion.goal") && text.contains("GOAL_IN_COLLISION") && text.contains("`wall`"),
        "{e}"
    );
    let request = v1::ExecuteRequest { motion: Some(inside.clone()), ..Default::default() };
    let e = within("execute", client.execute(request)).await.map(|_| ()).unwrap_err();
    assert_eq!(e.code(), Some(tonic::Code::FailedPrecondition), "{e}");
    assert!(e.to_string().contains("`wall`"), "{e}");
    let start = v1::ExecuteRequest { motion: Some(inside.clone()), ..Default::default() };
    let e = match within("session", client.session(start)).await {
        Ok(mut s) => within("segment", s.next_segment()).await.unwrap().unwrap_err(),
        Err(e) => e,
    };
    assert_eq!(e.code(), Some(tonic::Code::FailedPrecondition), "{e}");
    assert!(e.to_string().contains("start.motion.goal"), "{e}");
    // A start inside: named as the start.
    let mut from_inside = spec("r", "line");
    from_inside.start = vec![0.5, -0.2];
    let e = within("plan", client.plan(v1::PlanRequest { motion: Some(from_inside), ..Default::default() }))
        .await
        .unwrap_err();
    assert_eq!(e.code(), Some(tonic::Code::FailedPrecondition), "{e}");
    assert!(
        e.to_string().contains("motion.start") && e.to_string().contains("START_STATE_IN_COLLISION"),
        "{e}"
    );
    // The scene ignored, the wall is not known to the run: the plan goes.
    inside.ignore_scene = true;
    within("plan", client.plan(v1::PlanRequest { motion: Some(inside.clone()), ..Default::default() }))
        .await
        .unwrap();
    // A run's own obstacle counts too.
    inside.extra_obstacles = vec![ellipse("ball", vec![0.5, 0.1], vec![0.05, 0.05])];
    let e = within("plan", client.plan(v1::PlanRequest { motion: Some(inside), ..Default::default() }))
        .await
        .unwrap_err();
    assert!(e.to_string().contains("`ball`"), "{e}");
    within("shutdown", handle.shutdown()).await.unwrap();
}

#[tokio::test(flavor = "multi_thread")]
async fn a_sessions_new_goal_inside_an_obstacle_is_a_rejected_command() {
    let dir = tempfile::tempdir().unwrap();
    let (handle, client) = with_line(dir.path()).await;
    within("obstacle", client.put_obstacle(wall())).await.unwrap();
    let mut motion = spec("r", "line");
    motion.goal = vec![0.3, 0.0];
    let start = v1::ExecuteRequest { motion: Some(motion), max_duration_s: 10.0, ..Default::default() };
    let mut session = within("session", client.session(start)).await.unwrap();
    within("segment", session.next_segment()).await.unwrap().unwrap();
    within("set goal", session.set_goal(vec![0.5, 0.0])).await.unwrap();
    let mut warning = None;
    let mut last = None;
    while let Some(s) = within("segment", session.next_segment()).await {
        let s = s.unwrap();
        if let Some(w) = s.warnings.iter().find(|w| w.kind == v1::warning::Kind::CommandRejected as i32) {
            warning.get_or_insert(w.clone());
        }
        last = Some(s);
    }
    let w = warning.expect("the goal inside the wall is rejected with a warning");
    assert_eq!(w.field, "set_goal.goal");
    assert!(w.reason.contains("GOAL_IN_COLLISION") && w.reason.contains("`wall`"), "{}", w.reason);
    // The run went on to its former goal.
    let v = last.unwrap().verdict.unwrap();
    assert_eq!(outcome(&v), v1::Outcome::GoalReached, "{v:?}");
    within("shutdown", handle.shutdown()).await.unwrap();
}

#[tokio::test(flavor = "multi_thread")]
async fn every_member_of_a_group_gets_the_verdict_on_the_last_segment() {
    let dir = tempfile::tempdir().unwrap();
    let (handle, client) = serve(dir.path()).await;
    let mut members = Vec::new();
    for (id, y) in [("a", 0.0), ("b", 1.0)] {
        let p = line(vec![0.0, y], vec![1.0, y], 1.0);
        within("put", client.put_primitive(id, "line", &p)).await.unwrap();
        let mut motion = spec(id, "line");
        motion.ignore_scene = true;
        motion.footprint = Some(v1::Superquadric { semi_axes: vec![0.1, 0.1], exponents: vec![] });
        members.push(v1::GroupMember { motion: Some(motion) });
    }
    let request = v1::ExecuteGroupRequest { members, max_duration_s: 10.0, ..Default::default() };
    let mut stream = within("group", client.execute_group(request)).await.unwrap();
    let mut groups = Vec::new();
    while let Some(g) = within("group segment", stream.next()).await {
        groups.push(g.unwrap());
    }
    let (last, before) = groups.split_last().unwrap();
    assert!(before.iter().flat_map(|g| &g.segments).all(|s| s.verdict.is_none()));
    assert_eq!(last.segments.len(), 2);
    for s in &last.segments {
        let v = s.verdict.as_ref().expect("each member's last segment has the verdict");
        assert_eq!(outcome(v), v1::Outcome::GoalReached, "{}: {v:?}", s.robot_id);
        assert!(v.goal_reached && v.goal_distance <= 1e-3, "{v:?}");
    }
    within("shutdown", handle.shutdown()).await.unwrap();
}
