//! The Prometheus endpoint (`--metrics-addr`): scraped over HTTP while a robot streams, its values move with what
//! the server did (a learn, a real-time stream, an obstacle over Zenoh, a malformed Zenoh payload, a refused
//! stream).

use dmp_client::zenoh_pub::ObstaclePublisher;
use dmp_proto::v1;
use dmp_server::server::start;
use dmp_tests::scrape::{families, get, scrape, value};
use dmp_tests::{T, config, within};
use tokio_stream::StreamExt;

use crate::{paper_curve, until};

/// Every metric the endpoint serves (by family), with its HELP: README and `deploy/grafana/` use these names.
pub const FAMILIES: &[&str] = &[
    "dmp_streams",
    "dmp_robots",
    "dmp_obstacles",
    "dmp_open_streams",
    "dmp_segments_sent",
    "dmp_segment_lateness_seconds",
    "dmp_obstacle_update_to_segment_seconds",
    "dmp_admissions_refused",
    "dmp_zenoh_malformed_payloads",
    "dmp_robot_states_dropped",
    "dmp_store_operations",
    "dmp_memory_reserved_bytes",
    "dmp_memory_budget_bytes",
    "dmp_compute_work_reserved",
    "dmp_compute_work_budget",
    "dmp_compute_jobs_running",
    "dmp_compute_jobs_abandoned",
    "dmp_compute_jobs_failed",
    "dmp_process_cpu_seconds",
    "dmp_process_resident_memory_bytes",
    "dmp_uptime_seconds",
];

#[tokio::test(flavor = "multi_thread")]
async fn the_metrics_move_with_what_the_server_does() {
    let dir = tempfile::tempdir().unwrap();
    let mut c = config(dir.path());
    c.metrics_addr = Some("127.0.0.1:0".parse().unwrap());
    // One execution at a time: the second is refused, and counted by the limit that refused it.
    c.limits.max_streams = 1;
    let handle = within("server start", start(c)).await.expect("server starts");
    let addr = handle.metrics_addr.expect("the bound metrics address");
    assert_ne!(addr.port(), 0);
    let client = within("connect", dmp_client::DmpClient::connect(format!("http://{}", handle.grpc_addr)))
        .await
        .unwrap();

    let before = scrape(addr).await;
    let names = families(&before);
    for f in FAMILIES {
        assert!(names.contains(*f), "{f} missing from the scrape: {names:?}");
    }
    assert_eq!(names.len(), FAMILIES.len(), "a metric not listed here: {names:?}");
    assert_eq!(value(&before, "dmp_store_operations_total", &[("kind", "put")]), Some(0.0));
    assert_eq!(value(&before, "dmp_segments_sent_total", &[]), Some(0.0));
    assert_eq!(value(&before, "dmp_zenoh_malformed_payloads_total", &[]), Some(0.0));
    assert!(value(&before, "dmp_process_resident_memory_bytes", &[]).unwrap() > 0.0);
    assert!(value(&before, "dmp_process_cpu_seconds_total", &[]).unwrap() > 0.0);

    // A learn, then a real-time stream of it.
    let (t, rows) = paper_curve();
    for robot in ["panda", "panda-2"] {
        within("learn", client.learn(robot, "curve", &t, &rows, Default::default())).await.unwrap();
    }
    let perception =
        within("zenoh open", ObstaclePublisher::open("default", &handle.zenoh_locators, &[])).await.unwrap();
    within("subscriber", perception.wait_for_subscriber(T)).await.unwrap();
    let request = v1::ExecuteRequest {
        motion: Some(v1::MotionSpec {
            robot_id: "panda".into(),
            primitive: "curve".into(),
            ..Default::default()
        }),
        pacing: v1::Pacing::Realtime as i32,
        max_duration_s: 30.0,
        ..Default::default()
    };
    let mut stream = within("execute", client.execute(request.clone())).await.unwrap();
    for _ in 0..4 {
        within("segment", stream.next()).await.unwrap().unwrap();
    }
    // A second execution is refused by limits.max_streams.
    let mut second = request.clone();
    second.motion.as_mut().unwrap().robot_id = "panda-2".into();
    let refused = within("second execute", client.execute(second)).await.err().expect("refused");
    assert!(refused.to_string().contains("limits.max_streams"), "{refused}");

    // An obstacle over Zenoh: the stream sends a segment computed with it.
    let obstacle = serde_json::json!({"center": [0.6, 0.6], "semi_axes": [0.05, 0.05], "exponents": [1, 1]});
    within("put obstacle", perception.put_json("box", &obstacle)).await.unwrap();
    loop {
        let s = within("segment", stream.next()).await.expect("the stream goes on").unwrap();
        if s.scene_version >= 1 {
            break;
        }
    }
    // A malformed payload on an obstacle key.
    let key = dmp_proto::keys::obstacle_key("default", "garbage");
    within("malformed put", async { perception.session().put(key, "not an obstacle").await }).await.unwrap();
    until("malformed payload counted", || handle.malformed_payloads() >= 1).await;

    let during = scrape(addr).await;
    let v = |name: &str, labels: &[(&str, &str)]| {
        value(&during, name, labels).unwrap_or_else(|| panic!("{name} {labels:?} missing"))
    };
    assert_eq!(v("dmp_streams", &[("cell", "default")]), 1.0);
    assert_eq!(v("dmp_obstacles", &[("cell", "default")]), 1.0);
    assert!(v("dmp_robots", &[("cell", "default")]) >= 1.0);
    assert!(v("dmp_open_streams", &[]) >= 1.0);
    assert!(v("dmp_segments_sent_total", &[]) >= 5.0);
    assert!(v("dmp_segment_lateness_seconds_count", &[]) >= 5.0);
    let le_inf = v("dmp_segment_lateness_seconds", &[]);
    assert_eq!(le_inf, v("dmp_segment_lateness_seconds_count", &[]), "+Inf holds every observation");
    assert_eq!(v("dmp_obstacle_update_to_segment_seconds_count", &[]), 1.0);
    let latency = v("dmp_obstacle_update_to_segment_seconds_sum", &[]);
    assert!(latency > 0.0 && latency < 5.0, "obstacle to segment: {latency} s");
    assert_eq!(v("dmp_admissions_refused_total", &[("reason", "limits.max_streams")]), 1.0);
    assert_eq!(v("dmp_admissions_refused_total", &[("reason", "compute.max_job_work")]), 0.0);
    assert_eq!(v("dmp_zenoh_malformed_payloads_total", &[]), handle.malformed_payloads() as f64);
    assert_eq!(v("dmp_store_operations_total", &[("kind", "put")]), 2.0, "the learns");
    assert!(v("dmp_store_operations_total", &[("kind", "get")]) >= 1.0, "the stream read its primitive");
    assert!(v("dmp_memory_reserved_bytes", &[]) > 0.0, "the stream's and the scene's reservations");
    assert!(v("dmp_compute_work_reserved", &[("pool", "realtime")]) > 0.0);
    assert!(v("dmp_uptime_seconds", &[]) > value(&before, "dmp_uptime_seconds", &[]).unwrap());

    // The stream ends: its cell's gauge goes back to 0.
    drop(stream);
    within("stream gone", async {
        while value(&scrape(addr).await, "dmp_streams", &[("cell", "default")]) != Some(0.0) {
            tokio::time::sleep(std::time::Duration::from_millis(20)).await;
        }
    })
    .await;

    // Only GET /metrics.
    assert_eq!(get(addr, "/").await.status, 404);
    within("shutdown", handle.shutdown()).await.unwrap();
}

#[tokio::test(flavor = "multi_thread")]
async fn the_metrics_are_off_by_default() {
    let dir = tempfile::tempdir().unwrap();
    let handle = within("server start", start(config(dir.path()))).await.expect("server starts");
    assert_eq!(handle.metrics_addr, None);
    within("shutdown", handle.shutdown()).await.unwrap();
}
