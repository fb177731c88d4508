//! Values that used to stop every robot of a cell (issue 15, "One obstacle kills every stream in its cell"): numbers
//! outside the ranges that keep every term finite are refused with the field and the range, and an obstacle that
//! still cannot be used (a dimension other than the robot's, or a term that is not finite where the robot is) is
//! dropped for that robot and reported, while its stream goes on to the goal.

use dmp_client::grpc::DmpClient;
use dmp_proto::v1;
use tokio_stream::StreamExt;

use crate::default_limits::exact;
use crate::{dynamic_volumetric, ellipse, line, paper_curve, spec};
use dmp_tests::{TestServer, within};

/// The half-width of the workspace of these tests: far wider than the reach within which the ranges are proven to
/// keep every term finite ([`dmp::ranges::REACH_M`]), so that an obstacle can pass validation and still overflow.
const WIDE_WORKSPACE_M: f64 = 1e8;

async fn wide_server() -> (TestServer, DmpClient) {
    let server = TestServer::start_with(|c| c.limits.workspace_m = WIDE_WORKSPACE_M).await;
    let client = server.client().await;
    (server, client)
}

fn superquadric(id: &str, center: Vec<f64>, semi_axes: Vec<f64>, exponents: Vec<f64>) -> v1::Obstacle {
    v1::Obstacle {
        id: id.into(),
        shape: Some(v1::obstacle::Shape::Superquadric(v1::Superquadric { semi_axes, exponents })),
        center,
        ..Default::default()
    }
}

/// Accepted, but 1e8 m away (ahead of the robot, so that its dynamic term is active) with 1 mm semi-axes and
/// exponents 8: `|grad C|^2` overflows where the robot is.
fn far_and_sharp(id: &str) -> v1::Obstacle {
    superquadric(id, vec![WIDE_WORKSPACE_M, WIDE_WORKSPACE_M], vec![1e-3; 2], vec![8.0; 2])
}

/// The robot `r`'s line, avoiding obstacles with the dynamic volumetric potential.
/// The DMP's own run (no limits): it reaches its goal within the default 3 tau.
fn avoiding() -> v1::MotionSpec {
    v1::MotionSpec { avoidance: Some(dynamic_volumetric(10.0, 2.0, 0.5)), ..exact(spec("r", "line")) }
}

fn realtime(motion: v1::MotionSpec) -> v1::ExecuteRequest {
    v1::ExecuteRequest {
        motion: Some(motion),
        pacing: v1::Pacing::Realtime as i32,
        max_duration_s: 4.0,
        ..Default::default()
    }
}

/// Asserts an InvalidArgument naming `field` and `range`.
fn refused<T: std::fmt::Debug>(what: &str, r: Result<T, dmp_client::ClientError>, field: &str, range: &str) {
    let e = r.expect_err(what);
    assert_eq!(e.code(), Some(tonic::Code::InvalidArgument), "{what}: {e}");
    let text = e.to_string();
    assert!(
        text.contains(field) && text.contains(range),
        "{what}: `{text}` names not `{field}` and `{range}`"
    );
}

fn ignored_ids(warnings: &[v1::Warning]) -> Vec<&str> {
    warnings
        .iter()
        .filter(|w| w.kind() == v1::warning::Kind::ObstacleIgnored)
        .map(|w| w.obstacle_id.as_str())
        .collect()
}

/// Every segment until the stream ends, checked finite.
async fn drain(
    stream: &mut dmp_client::grpc::SegmentStream,
    mut segments: Vec<v1::Segment>,
) -> Vec<v1::Segment> {
    while let Some(s) = within("segment", stream.next()).await {
        segments.push(s.expect("the stream goes on"));
    }
    for s in &segments {
        assert!(s.positions.iter().chain(&s.velocities).all(|v| v.is_finite()));
    }
    segments
}

#[tokio::test(flavor = "multi_thread")]
async fn hostile_values_are_refused_and_a_running_stream_is_unaffected() {
    let (server, client) = wide_server().await;
    within("put", client.put_primitive("bystander", "line", &line(vec![0.0, 0.0], vec![1.0, 0.0], 1.0)))
        .await
        .unwrap();
    within("put", client.put_primitive("r", "line", &line(vec![0.0, 0.0], vec![1.0, 0.0], 1.0)))
        .await
        .unwrap();
    // A robot of the cell, running in real time while the rest is refused.
    let mut stream = within("execute", client.execute(realtime(spec("bystander", "line")))).await.unwrap();
    let first = within("first segment", stream.next()).await.unwrap().unwrap();

    let put = |o: v1::Obstacle| client.put_obstacle(o);
    let ball = || ellipse("o", vec![0.5, 0.5], vec![0.1, 0.1]);
    refused(
        "exponents 1e6",
        within("put", put(superquadric("o", vec![0.5, 0.5], vec![0.1; 2], vec![1e6, 1.0]))).await,
        "obstacle.superquadric.exponents[0]",
        "between 1 and 8",
    );
    refused(
        "semi-axes 1e-300",
        within("put", put(ellipse("o", vec![0.5, 0.5], vec![1e-300, 0.1]))).await,
        "obstacle.superquadric.semi_axes[0]",
        "between 0.001 and 10000 m",
    );
    refused(
        "centre out of the workspace",
        within("put", put(ellipse("o", vec![0.5, -2e8], vec![0.1, 0.1]))).await,
        "obstacle.center[1]",
        "within the workspace",
    );
    refused(
        "velocity 1e300",
        within("put", put(v1::Obstacle { velocity: vec![1e300, 0.0], ..ball() })).await,
        "obstacle.velocity",
        "between 0 and 20 m/s",
    );
    let nested = v1::Obstacle {
        shape: Some(v1::obstacle::Shape::Nested(v1::NestedSuperquadric {
            semi_axes: vec![0.1; 3],
            n: 1e6,
            m: 1.0,
        })),
        center: vec![0.0; 3],
        ..ball()
    };
    refused("nested n 1e6", within("put", put(nested)).await, "obstacle.nested.n", "between 1 and 8");
    let mut tiny_alpha = line(vec![0.0, 0.0], vec![1.0, 0.0], 1.0);
    tiny_alpha.alpha = 1e-300;
    refused(
        "alpha 1e-300",
        within("put", client.put_primitive("r", "tiny", &tiny_alpha)).await,
        "primitive.alpha",
        "between 0.01 and 100",
    );
    let mut tiny_tau = line(vec![0.0, 0.0], vec![1.0, 0.0], 1.0);
    tiny_tau.tau = 1e-300;
    refused(
        "primitive tau 1e-300",
        within("put", client.put_primitive("r", "tiny", &tiny_tau)).await,
        "primitive.tau",
        "between 1e-3 and 1e4",
    );
    let (t, x) = paper_curve();
    let parameters = v1::LearnParameters { alpha: 1e-300, ..Default::default() };
    refused(
        "learn alpha 1e-300",
        within("learn", client.learn("r", "tiny", &t, &x, parameters)).await,
        "parameters.alpha",
        "between 0.01 and 100",
    );
    let mut motion = spec("r", "line");
    motion.tau = 1e-300;
    refused(
        "execute tau 1e-300",
        within("execute", client.execute(realtime(motion))).await.map(|_| ()),
        "motion.tau",
        "between 1e-3 and 1e4",
    );
    let mut motion = spec("r", "line");
    motion.goal = vec![1e300, 0.0];
    let plan = v1::PlanRequest { motion: Some(motion), ..Default::default() };
    refused(
        "plan goal 1e300",
        within("plan", client.plan(plan)).await,
        "motion.goal[0]",
        "within the workspace",
    );
    let mut motion = spec("r", "line");
    motion.extra_obstacles = vec![ellipse("x", vec![0.5, 0.5], vec![0.1, 1e-300])];
    refused(
        "extra obstacle semi-axes 1e-300",
        within("execute", client.execute(realtime(motion))).await.map(|_| ()),
        "motion.extra_obstacles[0].superquadric.semi_axes[1]",
        "between 0.001 and 10000 m",
    );
    let mut motion = spec("r", "line");
    motion.avoidance = Some(v1::Avoidance {
        method: Some(v1::avoidance::Method::DynamicVolumetric(v1::avoidance::DynamicVolumetric {
            lambda: 1e300,
            beta: 2.0,
            eta: 0.5,
        })),
        ..Default::default()
    });
    refused(
        "lambda 1e300",
        within("execute", client.execute(realtime(motion))).await.map(|_| ()),
        "motion.avoidance.lambda",
        "between 1e-9 and 1e9",
    );
    let mut motion = spec("r", "line");
    motion.footprint = Some(v1::Superquadric { semi_axes: vec![0.1, 0.1], exponents: vec![1e6, 1.0] });
    refused(
        "footprint exponents 1e6",
        within("execute", client.execute(realtime(motion))).await.map(|_| ()),
        "motion.footprint.exponents[0]",
        "between 1 and 8",
    );

    // Nothing refused reached the scene, and the bystander went on to its goal as if nothing happened.
    let segments = drain(&mut stream, vec![first]).await;
    let last = segments.last().unwrap();
    assert_eq!(last.status, v1::SegmentStatus::GoalReached as i32, "ended with {:?}", last.status);
    assert!(segments.iter().all(|s| s.scene_version == 0 && s.warnings.is_empty()));
    assert!(within("list", client.list_obstacles()).await.unwrap().obstacles.is_empty());
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread")]
async fn an_obstacle_the_robot_cannot_use_is_reported_and_the_stream_reaches_its_goal() {
    let (server, client) = wide_server().await;
    within("put", client.put_primitive("r", "line", &line(vec![0.0, 0.0], vec![1.0, 0.0], 1.0)))
        .await
        .unwrap();
    let mut stream = within("execute", client.execute(realtime(avoiding()))).await.unwrap();
    let mut segments = Vec::new();
    while segments.len() < 5 {
        segments.push(within("segment", stream.next()).await.unwrap().unwrap());
    }
    // Both pass validation: one overflows where the robot is, the other is a 3-D ball in a 2-D robot's cell.
    within("put sharp", client.put_obstacle(far_and_sharp("sharp"))).await.unwrap();
    within("put ball", client.put_obstacle(ellipse("ball", vec![0.5, 0.0, 0.0], vec![0.1; 3])))
        .await
        .unwrap();
    let segments = drain(&mut stream, segments).await;
    let last = segments.last().unwrap();
    assert_eq!(last.status, v1::SegmentStatus::GoalReached as i32, "ended with {:?}", last.status);
    assert!(segments.iter().any(|s| s.scene_version >= 2), "the scene with both reached the stream");
    let warnings: Vec<v1::Warning> = segments.iter().flat_map(|s| s.warnings.clone()).collect();
    let mut ids = ignored_ids(&warnings);
    ids.sort_unstable();
    assert_eq!(ids, ["ball", "sharp"], "each reported once: {warnings:?}");
    for w in &warnings {
        let why = if w.obstacle_id == "ball" { "3 dimensions" } else { "not finite" };
        assert!(w.reason.contains(why), "{w:?}");
    }

    // A plan in the same scene reports the same.
    let plan = v1::PlanRequest { motion: Some(avoiding()), duration: 3.0, ..Default::default() };
    let reply = within("plan", client.plan(plan)).await.unwrap();
    let mut ids = ignored_ids(&reply.warnings);
    ids.sort_unstable();
    assert_eq!(ids, ["ball", "sharp"], "{:?}", reply.warnings);
    let trajectory = reply.trajectory.unwrap();
    assert_eq!(trajectory.status, v1::SegmentStatus::GoalReached as i32);
    assert!(trajectory.positions.iter().all(|v| v.is_finite()));
    server.stop().await;
}
