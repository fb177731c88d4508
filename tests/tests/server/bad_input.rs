//! Bad input gets a clear status, and the server keeps serving.

use dmp_client::zenoh_pub::ObstaclePublisher;
use dmp_proto::v1;

use crate::default_limits::exact;
use crate::{dynamic_volumetric, ellipse, line, paper_curve, serve, spec, until};
use dmp_tests::{T, within};

#[tokio::test(flavor = "multi_thread")]
async fn bad_input_gets_a_clear_status_and_the_server_keeps_serving() {
    let dir = tempfile::tempdir().unwrap();
    let (handle, client) = serve(dir.path()).await;
    let (t, mut x) = paper_curve();
    x[3][1] = f64::NAN;
    let e = within("learn NaN", client.learn("r", "bad", &t, &x, Default::default())).await.unwrap_err();
    assert_eq!(e.code(), Some(tonic::Code::InvalidArgument), "{e}");
    assert!(e.to_string().contains("demonstration.positions[3][1]"), "{e}");
    let e = within("learn bad id", client.learn("a/b", "x", &t[..3], &x[..3], Default::default()))
        .await
        .unwrap_err();
    assert!(e.to_string().contains("robot_id"), "{e}");
    let e = within("get missing", client.get("r", "nothing", 0)).await.unwrap_err();
    assert_eq!(e.code(), Some(tonic::Code::NotFound), "{e}");
    within("put", client.put_primitive("r", "line", &line(vec![0.0, 0.0], vec![1.0, 0.0], 1.0)))
        .await
        .unwrap();
    let mut motion = spec("r", "line");
    motion.goal = vec![1.0, 2.0, 3.0];
    let e =
        within("plan bad goal", client.plan(v1::PlanRequest { motion: Some(motion), ..Default::default() }))
            .await
            .unwrap_err();
    assert!(e.to_string().contains("motion.goal"), "{e}");
    // A start velocity (a resumed session's) of the wrong length, not finite, or faster than a robot state may be.
    for (v, field) in [
        (vec![0.1], "motion.start_velocity"),
        (vec![0.1, f64::NAN], "motion.start_velocity[1]"),
        (vec![0.0, 11.0], "motion.start_velocity[1]"),
    ] {
        let mut motion = spec("r", "line");
        motion.start_velocity = v.clone();
        let e = within(
            "plan bad start velocity",
            client.plan(v1::PlanRequest { motion: Some(motion), ..Default::default() }),
        )
        .await
        .unwrap_err();
        assert_eq!(e.code(), Some(tonic::Code::InvalidArgument), "{v:?}: {e}");
        assert!(e.to_string().contains(field), "{v:?}: {e}");
    }
    // A good one starts the run moving: its first point has it.
    let mut motion = exact(spec("r", "line"));
    motion.start_velocity = vec![0.2, -0.1];
    let plan =
        within("plan moving", client.plan(v1::PlanRequest { motion: Some(motion), ..Default::default() }))
            .await
            .unwrap();
    assert_eq!(plan.trajectory.unwrap().velocities[..2], [0.2, -0.1]);
    let request = v1::ExecuteRequest { motion: Some(spec("r", "line")), dt: -1.0, ..Default::default() };
    let e = within("execute bad dt", client.execute(request)).await.err().expect("refused");
    assert!(e.to_string().contains("dt"), "{e}");
    for tol in [-1e-6, f64::NAN, 0.5] {
        let request = v1::ExecuteRequest {
            motion: Some(spec("r", "line")),
            integration_tolerance: tol,
            ..Default::default()
        };
        let e = within("execute bad tolerance", client.execute(request)).await.err().expect("refused");
        assert_eq!(e.code(), Some(tonic::Code::InvalidArgument), "{e}");
        assert!(e.to_string().contains("integration_tolerance"), "{tol}: {e}");
    }
    // An unstable step is refused before anything is computed, and so is a method that cannot work.
    let e = within(
        "plan unstable",
        client.plan(v1::PlanRequest { motion: Some(spec("r", "line")), dt: 0.1, duration: 1.0 }),
    )
    .await
    .unwrap_err();
    assert!(e.to_string().contains("unstable"), "{e}");
    let mut motion = spec("r", "line");
    motion.avoidance = Some(dynamic_volumetric(10.0, 0.5, 0.5));
    let request = v1::ExecuteRequest { motion: Some(motion), ..Default::default() };
    let e = within("execute bad beta", client.execute(request)).await.err().expect("refused");
    assert!(e.to_string().contains("motion.avoidance.beta"), "{e}");
    let mut bad = ellipse("neg", vec![0.0, 0.0], vec![-0.3, 0.2]);
    let e = within("put bad obstacle", client.put_obstacle(bad.clone())).await.unwrap_err();
    assert!(e.to_string().contains("semi_axes[0]"), "{e}");
    bad.shape = None;
    assert!(within("put shapeless", client.put_obstacle(bad)).await.is_err());

    // Malformed Zenoh payloads are counted and change nothing.
    let perception =
        within("zenoh open", ObstaclePublisher::open("default", &handle.zenoh_locators, &[])).await.unwrap();
    within("subscriber", perception.wait_for_subscriber(T)).await.unwrap();
    let session = perception.session();
    within("garbage", async {
        session.put("dmp/default/obstacles/junk", vec![0xff, 0x00, 0x13]).await.unwrap()
    })
    .await;
    within("bad json", async {
        session.put("dmp/default/obstacles/neg", r#"{"center": [0, 0], "semi_axes": [-1, 1]}"#).await.unwrap()
    })
    .await;
    until("malformed payloads counted", || handle.malformed_payloads() >= 2).await;
    let snap = within("list obstacles", client.list_obstacles()).await.unwrap();
    assert!(snap.obstacles.is_empty(), "{:?}", snap.obstacles);
    within("list", client.list("r")).await.unwrap();
    let channel = tonic::transport::Channel::from_shared(format!("http://{}", handle.grpc_addr))
        .unwrap()
        .connect()
        .await
        .unwrap();
    let mut health = tonic_health::pb::health_client::HealthClient::new(channel);
    let status =
        within("health", health.check(tonic_health::pb::HealthCheckRequest { service: String::new() }))
            .await
            .unwrap()
            .into_inner()
            .status;
    assert_eq!(status, tonic_health::pb::health_check_response::ServingStatus::Serving as i32);
    // A client that stops reading does not hold the shutdown.
    let mut motion = spec("r", "line");
    motion.tau = 50.0;
    let request = v1::ExecuteRequest { motion: Some(motion), max_duration_s: 100.0, ..Default::default() };
    let _unread = within("execute", client.execute(request)).await.unwrap();
    until("the stream is open", || handle.open_streams() == 1).await;
    within("shutdown with an unread stream", handle.shutdown()).await.unwrap();
}
