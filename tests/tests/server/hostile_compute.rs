//! Costly work is admitted by its cost and stops when its client goes: plans past their deadline, learns whose
//! client left, requests beyond the compute budgets.

use std::sync::atomic::Ordering;
use std::time::Duration;

use dmp_proto::v1;
use dmp_proto::v1::motion_service_client::MotionServiceClient;
use dmp_proto::v1::primitive_service_client::PrimitiveServiceClient;
use dmp_tests::{TestServer, within};
use tokio_stream::StreamExt;

use crate::default_limits::exact;
use crate::{line, spec, until};

/// `n` spheres 50 m away.
fn far_obstacles(n: usize) -> Vec<v1::Obstacle> {
    (0..n)
        .map(|i| {
            crate::ellipse(
                &format!("far-{i}"),
                vec![50.0 + (i % 100) as f64, 50.0 + (i / 100) as f64],
                vec![0.1, 0.1],
            )
        })
        .collect()
}

async fn channel(server: &TestServer) -> tonic::transport::Channel {
    let endpoint = tonic::transport::Channel::from_shared(server.url()).unwrap();
    within("connect", endpoint.connect()).await.unwrap()
}

fn idle(server: &TestServer) -> bool {
    let c = &server.handle().compute();
    c.batch.counters().running.load(Ordering::Acquire) == 0 && c.admission.batch_in_use() == 0
}

#[tokio::test(flavor = "multi_thread")]
async fn a_plan_past_its_deadline_stops_computing() {
    let server = TestServer::grpc_only().await;
    let client = server.client().await;
    within("put", client.put_primitive("r", "line", &line(vec![0.0, 0.0], vec![1.0, 0.0], 1.0)))
        .await
        .unwrap();
    let mut motion = spec("r", "line");
    motion.extra_obstacles = far_obstacles(1000);
    // Admitted (within `max_request_work`), and many seconds of work.
    let mut request = tonic::Request::new(v1::PlanRequest { motion: Some(motion), duration: 30.0, dt: 1e-3 });
    request.set_timeout(Duration::from_millis(300));
    let mut motion_client = MotionServiceClient::new(channel(&server).await);
    let t0 = std::time::Instant::now();
    let err = within("plan", motion_client.plan(request)).await.unwrap_err();
    assert!(matches!(err.code(), tonic::Code::DeadlineExceeded | tonic::Code::Cancelled), "{err:?}");
    // It stops at its next chunk, not at its end.
    until("the plan stopped", || idle(&server)).await;
    let stopped_after = t0.elapsed();
    let stats = within("stats", client.stats()).await.unwrap();
    assert_eq!(stats.batch_jobs_running, 0);
    assert!(stopped_after < Duration::from_secs(10), "stopped after {stopped_after:?}");
    // The server goes on serving plans.
    let plan = within(
        "plan",
        client.plan(v1::PlanRequest { motion: Some(spec("r", "line")), ..Default::default() }),
    )
    .await
    .unwrap();
    assert!(!plan.trajectory.unwrap().positions.is_empty());
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread")]
async fn a_learn_whose_client_left_is_not_stored() {
    let server = TestServer::start_with(|c| {
        c.zenoh.disabled = true;
        c.compute.batch_threads = 1;
        // Room for a plan far longer than the learns' deadline, however fast this machine steps.
        c.compute.max_request_work = 1e12;
        c.compute.batch_queue_work = 1e13;
        c.limits.max_obstacles = 5000;
    })
    .await;
    let client = server.client().await;
    // The one batch thread is busy with a long plan (its client leaves once the learns are done with).
    within("put", client.put_primitive("busy", "line", &line(vec![0.0, 0.0], vec![1.0, 0.0], 1.0)))
        .await
        .unwrap();
    let mut motion = spec("busy", "line");
    motion.extra_obstacles = far_obstacles(5000);
    let plan = v1::PlanRequest { motion: Some(motion), duration: 30.0, dt: 1e-3 };
    let mut motion_client = MotionServiceClient::new(channel(&server).await);
    let busy = tokio::spawn(async move { motion_client.plan(plan).await });
    let batch = server.handle().compute().batch.clone();
    until("the plan runs", || batch.counters().running.load(Ordering::Acquire) == 1).await;
    let samples = 5_000;
    let t: Vec<f64> = (0..samples).map(|i| i as f64 * 1e-3).collect();
    let demonstration = v1::Demonstration {
        positions: t.iter().flat_map(|t| [t.sin(), t.cos()]).collect(),
        t,
        dim: 2,
        ..Default::default()
    };
    let learn = |name: &str| v1::LearnRequest {
        robot_id: "r".into(),
        name: name.into(),
        demonstration: Some(demonstration.clone()),
        parameters: Some(v1::LearnParameters { n_basis: 50, ..Default::default() }),
    };
    let mut primitives = PrimitiveServiceClient::new(channel(&server).await);
    let mut other = primitives.clone();
    // One learn with a deadline, one whose client goes away: both wait in the queue behind the plan.
    let mut timed = tonic::Request::new(learn("timed"));
    timed.set_timeout(Duration::from_secs(3));
    let timed = tokio::spawn(async move { primitives.learn(timed).await });
    let left_request = learn("left");
    let left = tokio::spawn(async move { other.learn(left_request).await });
    until("both learns are queued", || batch.queued() == 2).await;
    left.abort();
    assert!(left.await.unwrap_err().is_cancelled());
    let err = within("the timed learn", timed).await.unwrap().unwrap_err();
    assert!(matches!(err.code(), tonic::Code::DeadlineExceeded | tonic::Code::Cancelled), "{err:?}");
    // The plan still holds the one batch thread (else the learns could have run): its client leaves too, the plan
    // stops at its next chunk and the queued learns are skipped, never run.
    assert_eq!(
        batch.counters().running.load(Ordering::Acquire),
        1,
        "the plan ended before the learns' deadline"
    );
    busy.abort();
    let _ = busy.await;
    until("the plan and the learns stopped", || idle(&server) && batch.queued() == 0).await;
    let listed = within("list", client.list("r")).await.unwrap();
    assert!(listed.is_empty(), "stored after the client left: {listed:?}");
    let stats = within("stats", client.stats()).await.unwrap();
    assert!(stats.jobs_abandoned >= 2, "{stats:?}");
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread")]
async fn a_learn_cancelled_while_it_runs_is_not_stored() {
    let server = TestServer::start_with(|c| c.zenoh.disabled = true).await;
    let client = server.client().await;
    // Least squares of 30,000 samples x 301 Gaussians (within the learn limits): long enough to be cancelled
    // while it runs.
    let samples = 30_000;
    let t: Vec<f64> = (0..samples).map(|i| i as f64 * 1e-3).collect();
    let demonstration = v1::Demonstration {
        positions: t.iter().flat_map(|t| [t.sin(), t.cos()]).collect(),
        t,
        dim: 2,
        ..Default::default()
    };
    let request = v1::LearnRequest {
        robot_id: "r".into(),
        name: "cancelled".into(),
        demonstration: Some(demonstration),
        parameters: Some(v1::LearnParameters { n_basis: 300, ..Default::default() }),
    };
    let mut primitives = PrimitiveServiceClient::new(channel(&server).await);
    let learn = tokio::spawn(async move { primitives.learn(request).await });
    let running = || server.handle().compute().batch.counters().running.load(Ordering::Acquire);
    until("the learn runs", || running() == 1).await;
    // The client goes away mid-computation (its request future is dropped: HTTP/2 resets the stream).
    learn.abort();
    assert!(learn.await.unwrap_err().is_cancelled());
    until("the learn finished computing", || idle(&server)).await;
    let listed = within("list", client.list("r")).await.unwrap();
    assert!(listed.is_empty(), "stored after the client left: {listed:?}");
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread")]
async fn requests_beyond_the_budgets_are_refused_with_their_cost_and_others_go_on() {
    let server = TestServer::start_with(|c| {
        c.zenoh.disabled = true;
        c.compute.realtime_threads = 1;
        c.compute.realtime_work_per_thread_s = 5e7;
        c.compute.max_request_work = 5e8;
    })
    .await;
    let client = server.client().await;
    for robot in ["r", "r2"] {
        within("put", client.put_primitive(robot, "line", &line(vec![0.0, 0.0], vec![1.0, 0.0], 1.0)))
            .await
            .unwrap();
    }
    let realtime = |robot: &str, obstacles: usize| {
        // The DMP's own timing: the robot's stream reaches its goal within the default 3 tau.
        let mut motion = exact(spec(robot, "line"));
        motion.extra_obstacles = far_obstacles(obstacles);
        v1::ExecuteRequest { motion: Some(motion), pacing: v1::Pacing::Realtime as i32, ..Default::default() }
    };
    // A robot streams within the budget.
    let mut running = within("execute", client.execute(realtime("r", 0))).await.unwrap();
    within("first segment", running.next()).await.unwrap().unwrap();
    // A real-time run beyond what is left of the budget.
    let Err(e) = within("execute", client.execute(realtime("r2", 300))).await else { panic!("admitted") };
    assert_eq!(e.code(), Some(tonic::Code::ResourceExhausted), "{e}");
    assert!(e.to_string().contains("work units per second"), "{e}");
    assert!(e.to_string().contains("realtime_work_per_thread_s"), "{e}");
    // One segment too costly for one computation.
    let mut long = realtime("r2", 20);
    long.segment_s = 10.0;
    let Err(e) = within("execute", client.execute(long)).await else { panic!("admitted") };
    assert!(e.to_string().contains("max_job_work"), "{e}");
    // A plan beyond the limit of one request.
    let mut motion = spec("r", "line");
    motion.extra_obstacles = far_obstacles(100);
    let plan = v1::PlanRequest { motion: Some(motion), duration: 30.0, ..Default::default() };
    let e = within("plan", client.plan(plan)).await.unwrap_err();
    assert_eq!(e.code(), Some(tonic::Code::ResourceExhausted), "{e}");
    assert!(e.to_string().contains("max_request_work"), "{e}");
    // The robot's stream went on and reaches its goal.
    let mut last = None;
    while let Some(s) = within("segment", running.next()).await {
        last = Some(s.unwrap());
    }
    assert_eq!(last.unwrap().status, v1::SegmentStatus::GoalReached as i32);
    // Its reservation came back.
    until("budget returned", || server.handle().compute().admission.realtime_in_use() == 0).await;
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread")]
async fn a_scene_that_grows_under_a_running_stream_is_counted_against_new_ones() {
    let server = TestServer::start_with(|c| {
        c.zenoh.disabled = true;
        c.compute.realtime_threads = 1;
        c.compute.realtime_work_per_thread_s = 5e7;
    })
    .await;
    let client = server.client().await;
    let admission = || &server.handle().compute().admission;
    within("put", client.put_primitive("r", "line", &line(vec![0.0, 0.0], vec![1.0, 0.0], 10.0)))
        .await
        .unwrap();
    within("put", client.put_primitive("r2", "line", &line(vec![0.0, 0.0], vec![1.0, 0.0], 1.0)))
        .await
        .unwrap();
    let realtime = |robot: &str, ignore_scene: bool| {
        let motion = v1::MotionSpec { ignore_scene, ..spec(robot, "line") };
        v1::ExecuteRequest { motion: Some(motion), pacing: v1::Pacing::Realtime as i32, ..Default::default() }
    };
    let mut running = within("execute", client.execute(realtime("r", false))).await.unwrap();
    within("first segment", running.next()).await.unwrap().unwrap();
    let admitted = admission().realtime_in_use();
    assert!(admitted > 0);
    // Perception adds 300 obstacles to the robot's cell: far more than the budget it was admitted with.
    for o in far_obstacles(300) {
        within("put obstacle", client.put_obstacle(o)).await.unwrap();
    }
    // The robot is told, goes on avoiding them, and its reservation counts them.
    within("the over-budget warning", async {
        loop {
            let segment = running.next().await.expect("the stream goes on").unwrap();
            let over = v1::warning::Kind::ComputeOverBudget as i32;
            if let Some(w) = segment.warnings.iter().find(|w| w.kind == over) {
                assert!(w.reason.contains("obstacles after this run was admitted"), "{w:?}");
                break;
            }
        }
    })
    .await;
    assert!(admission().realtime_in_use() as f64 > admission().realtime_budget());
    // A new real-time run is refused, even one that avoids no obstacle: the budget is taken.
    let Err(e) = within("execute", client.execute(realtime("r2", true))).await else { panic!("admitted") };
    assert_eq!(e.code(), Some(tonic::Code::ResourceExhausted), "{e}");
    // The obstacles go: the reservation shrinks back, and the new run is admitted.
    for o in far_obstacles(300) {
        within("delete obstacle", client.delete_obstacle(&o.id)).await.unwrap();
    }
    until("the reservation shrank", || admission().realtime_in_use() == admitted).await;
    let mut second = within("execute", client.execute(realtime("r2", true))).await.unwrap();
    within("first segment", second.next()).await.unwrap().unwrap();
    let segment = within("segment", running.next()).await.unwrap().unwrap();
    assert_eq!(segment.status, v1::SegmentStatus::Running as i32);
    drop((running, second));
    until("budget returned", || admission().realtime_in_use() == 0).await;
    server.stop().await;
}
