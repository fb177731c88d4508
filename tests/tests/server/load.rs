//! Many streams at once: a hundred concurrent ones, a leaving client, and a small `dmpctl load`.

use dmp_proto::v1;
use tokio_stream::StreamExt;

use crate::default_limits::exact;
use crate::{ellipse, line, serve, spec, until};
use dmp_tests::within;

#[tokio::test(flavor = "multi_thread")]
async fn a_hundred_concurrent_streams_complete_and_a_leaving_client_frees_its_stream() {
    let dir = tempfile::tempdir().unwrap();
    let (handle, client) = serve(dir.path()).await;
    within("put", client.put_primitive("fleet", "hop", &line(vec![0.0, 0.0], vec![0.5, 0.0], 0.5)))
        .await
        .unwrap();
    let mut tasks = Vec::new();
    for i in 0..100 {
        let client = client.clone();
        tasks.push(tokio::spawn(async move {
            // The DMP's own timing: each hop arrives within its 2 s.
            let mut motion = exact(spec("fleet", "hop"));
            motion.ignore_scene = true;
            // A robot executes one stream at a time in a cell: the same robot in a hundred cells, each declared by
            // its scene (far off the line; the motion ignores it anyway).
            motion.cell = format!("bay{i}");
            let bay = client.clone().with_cell(motion.cell.clone());
            within("declare the bay", bay.put_obstacle(ellipse("wall", vec![5.0, 5.0], vec![0.1, 0.1])))
                .await
                .unwrap();
            let request =
                v1::ExecuteRequest { motion: Some(motion), max_duration_s: 2.0, ..Default::default() };
            let mut stream = client.execute(request).await.unwrap();
            let mut last = None;
            while let Some(s) = stream.next().await {
                last = Some(s.unwrap());
            }
            last.unwrap().status
        }));
    }
    for t in tasks {
        let status = within("stream", t).await.unwrap();
        assert_eq!(status, v1::SegmentStatus::GoalReached as i32);
    }
    until("streams released", || handle.open_streams() == 0).await;

    // A real-time stream whose client leaves after one segment is freed.
    let mut motion = spec("fleet", "hop");
    motion.tau = 100.0;
    let request = v1::ExecuteRequest {
        motion: Some(motion),
        pacing: v1::Pacing::Realtime as i32,
        max_duration_s: 300.0,
        ..Default::default()
    };
    let mut stream = within("execute", client.execute(request)).await.unwrap();
    within("segment", stream.next()).await.unwrap().unwrap();
    assert_eq!(handle.open_streams(), 1);
    drop(stream);
    until("stream freed after the client left", || handle.open_streams() == 0).await;
    within("shutdown", handle.shutdown()).await.unwrap();
}

/// A small `dmpctl load` (what CI may run; never the full one): 20 robots in 2 cells at 1 kHz in 10 ms segments
/// for 2 s, with obstacle updates over Zenoh at 5 Hz. Structure and sanity only: no timing target (CI machines
/// are noisy).
#[tokio::test(flavor = "multi_thread")]
async fn a_smoke_load_streams_twenty_robots_in_two_cells() {
    let dir = tempfile::tempdir().unwrap();
    let (handle, _client) = serve(dir.path()).await;
    let out = dir.path().join("load");
    let args = dmp_sim::load::LoadArgs {
        robots: 20,
        rate: 1000.0,
        segment_s: 0.01,
        duration: 2.0,
        scene_updates: 5.0,
        out: Some(out.clone()),
        ..Default::default()
    };
    let url = format!("http://{}", handle.grpc_addr);
    let report = within("the load", dmp_sim::load::run(&args, &url, &handle.zenoh_locators))
        .await
        .expect("the load runs");
    let json = serde_json::to_value(&report).unwrap();
    println!("{}", serde_json::to_string_pretty(&json).unwrap());
    assert_eq!(
        serde_json::from_str::<serde_json::Value>(&std::fs::read_to_string(out.join("load.json")).unwrap())
            .unwrap(),
        json
    );
    for key in [
        "setpoints_expected",
        "setpoints_on_time",
        "late_segments",
        "server_cpu_percent",
        "server_rss_mib",
        "server_rss_mib_max",
    ] {
        assert!(json[key].is_number(), "{key}: {}", json[key]);
    }
    for key in ["p50", "p99", "max"] {
        assert!(json["lateness_ms"][key].is_number(), "lateness_ms.{key}");
    }
    for key in ["p50", "p99"] {
        assert!(json["scene_update_latency_ms"][key].is_number(), "scene_update_latency_ms.{key}");
    }

    assert!(report.errors.is_empty(), "{:#?}", report.errors);
    assert_eq!((report.cells, report.streams_started, report.streams_failed), (2, 20, 0));
    // Each robot streams from its start (spread over the first stagger_s seconds) to the end.
    let ideal = 20.0 * 1000.0 * (args.duration - report.stagger_s * 19.0 / 20.0 / 2.0);
    let expected = report.setpoints_expected as f64;
    assert!((expected - ideal).abs() < 0.05 * ideal, "{expected} setpoints expected, about {ideal} ideal");
    assert!(report.setpoints_on_time > 0 && report.setpoints_on_time <= report.setpoints_expected);
    // Ten setpoints a segment, and more segments where a scene update superseded what was sent.
    assert!(report.segments as f64 > 0.8 * expected / 10.0, "{} segments", report.segments);
    assert!(report.late_segments <= report.segments);
    assert_eq!(report.lateness_ms.count, report.segments);
    // Every late segment is in the series, by the second it arrived in (the stagger, the run and its end).
    assert_eq!(report.late_segments_per_second.iter().sum::<u64>(), report.late_segments);
    assert_eq!(report.late_segments_per_second.len(), (report.stagger_s + args.duration).ceil() as usize + 1);
    assert!(report.scene_updates_sent > 0);
    assert!(report.scene_update_latency_ms.count > 0, "no scene update reached a robot");
    assert!(
        report.scene_update_latency_ms.count + report.scene_updates_unanswered <= report.scene_updates_sent
    );
    assert!(report.server_cpu_percent.unwrap() > 0.0);
    assert!(report.server_rss_mib.unwrap() > 0.0);
    assert!(!report.server_rss_mib_series.is_empty());
    assert_eq!(report.server_open_streams_max, Some(20));
    within("shutdown", handle.shutdown()).await.unwrap();
}

/// A small `dmpctl load --pose`: pose robots at the Panda profile stream with their orientations (a segment
/// without them would end its robot with an error), turning a quarter at every goal change.
#[tokio::test(flavor = "multi_thread")]
async fn a_pose_load_streams_orientations_within_the_panda_profile() {
    let dir = tempfile::tempdir().unwrap();
    let (handle, client) = serve(dir.path()).await;
    let args = dmp_sim::load::LoadArgs {
        robots: 10,
        rate: 500.0,
        segment_s: 0.02,
        duration: 2.0,
        tau: 0.5,
        pose: true,
        keep: true,
        ..Default::default()
    };
    let url = format!("http://{}", handle.grpc_addr);
    let report = within("the pose load", dmp_sim::load::run(&args, &url, &handle.zenoh_locators))
        .await
        .expect("the pose load runs");
    assert!(report.errors.is_empty(), "{:#?}", report.errors);
    assert!(report.pose);
    assert_eq!((report.streams_started, report.streams_failed), (10, 0));
    assert!(report.setpoints_on_time > 0 && report.retargets >= 10, "{report:?}");
    // What the robots streamed: a pose primitive, and a plan of it keeps the Panda's angular speed.
    let stored = within("get", client.get("load.c0.r3", "load", 0)).await.unwrap();
    assert_eq!(stored.primitive.unwrap().orientation_reference.len(), 4);
    let mut start = dmp_sim::load::setup::start_request(
        &args.validate().unwrap(),
        &dmp_sim::load::layout::robots(10, 10, 3, "load")[3],
        "load-0",
    );
    let motion = start.motion.take().unwrap();
    let plan = v1::PlanRequest { motion: Some(motion), dt: 0.002, duration: 1.0 };
    let t = within("plan", client.plan(plan)).await.unwrap().trajectory.unwrap();
    assert_eq!(t.orientations.len(), 4 * t.positions.len() / 3);
    let fastest = t.angular_velocities.chunks(3).map(|w| w.iter().map(|v| v * v).sum::<f64>().sqrt());
    let fastest = fastest.fold(0.0, f64::max);
    assert!(fastest > 0.5 && fastest <= dmp::Limits::PANDA.max_angular_speed * 1.001, "{fastest} rad/s");
    within("shutdown", handle.shutdown()).await.unwrap();
}

/// The load against a secured server: each robot streams with its own token (`--tokens`), set-up and monitoring
/// with the admin's; a robot holding another robot's token is refused.
#[tokio::test(flavor = "multi_thread")]
async fn a_load_against_a_secured_server_streams_each_robot_as_itself() {
    use dmp_client::connect::ConnectOptions;
    use dmp_server::access::init::{InitOptions, init};
    use dmp_sim::load::layout;

    let set = tempfile::tempdir().unwrap();
    let args = dmp_sim::load::LoadArgs {
        robots: 6,
        cell_size: 3,
        rate: 1000.0,
        segment_s: 0.01,
        duration: 1.0,
        tokens: Some(set.path().to_path_buf()),
        ..Default::default()
    };
    let robots = layout::robots(args.robots, args.cell_size, args.dim, &args.prefix);
    let cells = (0..2).map(|c| layout::cell_name(&args.prefix, c)).collect();
    let options =
        InitOptions { cells, robots: robots.iter().map(|r| r.id.clone()).collect(), ..Default::default() };
    init(set.path(), &options).unwrap();
    let access = set.path().join("access.toml");
    let server = dmp_tests::TestServer::start_with(|c| {
        c.zenoh.disabled = true;
        c.security.access = Some(access);
    })
    .await;
    let admin = std::fs::read_to_string(set.path().join("admin.token")).unwrap();
    let options = ConnectOptions { token: Some(admin.trim().to_owned()), ..Default::default() };
    let url = server.url();
    let load = || dmp_sim::load::run_with(&args, &url, &[], &options);
    let report = within("the load", load()).await.expect("the load runs");
    assert!(report.errors.is_empty(), "{:#?}", report.errors);
    assert_eq!((report.streams_started, report.streams_failed), (6, 0));
    assert!(report.setpoints_on_time > 0);
    // The load's robots are its own (`load.c<cell>.r<k>`), and their primitives are gone once it ended.
    let admin_client = dmp_client::DmpClient::connect_with(&url, &options).await.unwrap();
    for r in &robots {
        assert!(r.id.starts_with("load.c"), "{}", r.id);
        assert!(within("list", admin_client.list(&r.id)).await.unwrap().is_empty(), "{} is left", r.id);
    }

    // Two robots swap their tokens: each is refused as the other.
    let (a, b) = (
        set.path().join(format!("{}.token", robots[0].id)),
        set.path().join(format!("{}.token", robots[1].id)),
    );
    let (ta, tb) = (std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    std::fs::write(&a, tb).unwrap();
    std::fs::write(&b, ta).unwrap();
    let report = within("the load", load()).await.expect("the load runs");
    assert_eq!(report.streams_failed, 2, "{:#?}", report.errors);
    assert!(report.errors.iter().any(|e| e.message.contains("may not execute")), "{:#?}", report.errors);
    server.stop().await;
}
