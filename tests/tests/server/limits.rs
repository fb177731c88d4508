//! Resource limits: each one refuses clearly (RESOURCE_EXHAUSTED or INVALID_ARGUMENT naming the limit) and the
//! server keeps serving everything else.

use std::time::Duration;

use dmp::Stepping;
use dmp_client::DmpClient;
use dmp_client::zenoh_pub::ObstaclePublisher;
use dmp_proto::v1;
use dmp_server::runs::pacing::StreamConfig;
use dmp_server::runs::stream_memory::StreamBytes;
use dmp_tests::{T, TestServer, within};
use tokio_stream::StreamExt;
use tonic::Code;

use crate::{ellipse, line, spec, until};

/// A 2-D line, stored for `robot`, with a long time scale: its streams run until their client leaves.
async fn slow_line(client: &DmpClient, robot: &str) {
    within("put", client.put_primitive(robot, "line", &line(vec![0.0; 2], vec![1.0, 0.0], 50.0)))
        .await
        .unwrap();
}

fn long_execute(robot: &str) -> v1::ExecuteRequest {
    v1::ExecuteRequest { motion: Some(spec(robot, "line")), max_duration_s: 100.0, ..Default::default() }
}

fn code<T>(r: Result<T, dmp_client::ClientError>) -> (Option<Code>, String) {
    match r {
        Ok(_) => (None, "accepted".into()),
        Err(e) => (e.code(), e.to_string()),
    }
}

/// The server's estimate of a default as-fast-as-read 2-D stream (10 ms segments of 1 ms points).
fn default_stream_bytes(buffer: usize) -> usize {
    let cfg = StreamConfig {
        stepping: Stepping::rk4(1e-3),
        segment_points: 10,
        realtime: false,
        lookahead: Duration::from_millis(50),
        max_duration: 100.0,
        urgency: None,
    };
    StreamBytes::estimate(&cfg, 2, buffer).total
}

#[tokio::test(flavor = "multi_thread")]
async fn streams_are_bounded_in_memory_and_a_cancelled_unread_one_gives_it_back() {
    let one = default_stream_bytes(4);
    let server = TestServer::start_with(|c| {
        c.zenoh.disabled = true;
        c.limits.max_segment_bytes = 100_000;
        c.limits.max_stream_bytes = 300_000;
        c.limits.max_server_bytes = 2 * one + one / 2;
    })
    .await;
    let client = server.client().await;
    // One robot per stream: a robot executes in one stream at a time.
    for robot in ["r", "a", "b", "c"] {
        slow_line(&client, robot).await;
    }
    let memory = &server.handle().memory();

    // 10 s segments: one segment alone is over its limit.
    let request = v1::ExecuteRequest { segment_s: 10.0, ..long_execute("r") };
    let (c, msg) = code(within("10 s segments", client.execute(request)).await);
    assert_eq!(c, Some(Code::ResourceExhausted), "{msg}");
    assert!(msg.contains("max_segment_bytes = 100000") && msg.contains("480512"), "{msg}");
    // 1 s segments: each within its limit, but the stream's buffered ones are not.
    let request = v1::ExecuteRequest { segment_s: 1.0, ..long_execute("r") };
    let (c, msg) = code(within("1 s segments", client.execute(request)).await);
    assert_eq!(c, Some(Code::ResourceExhausted), "{msg}");
    assert!(msg.contains("max_stream_bytes = 300000"), "{msg}");
    assert_eq!(memory.used(), 0, "refusals reserve nothing");

    // Two streams that are never read fill the server's budget; a third is refused, naming it.
    let unread_a = within("execute a", client.execute(long_execute("a"))).await.unwrap();
    let unread_b = within("execute b", client.execute(long_execute("b"))).await.unwrap();
    assert_eq!(memory.used(), 2 * one);
    let (c, msg) = code(within("execute c", client.execute(long_execute("c"))).await);
    assert_eq!(c, Some(Code::ResourceExhausted), "{msg}");
    assert!(msg.contains("max_server_bytes") && msg.contains(&format!("about {one} bytes")), "{msg}");
    // Everything else is served meanwhile.
    within("plan", client.plan(v1::PlanRequest { motion: Some(spec("r", "line")), dt: 0.01, duration: 1.0 }))
        .await
        .unwrap();

    // The client cancels a stream it never read: its producer ends and its memory comes back.
    drop(unread_a);
    until("the cancelled stream's memory is back", || memory.used() == one).await;
    let mut stream = within("execute again", client.execute(long_execute("c"))).await.unwrap();
    within("segment", stream.next()).await.unwrap().unwrap();
    drop((stream, unread_b));
    until("every stream's memory is back", || memory.used() == 0 && server.handle().open_streams() == 0)
        .await;
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread")]
async fn scenes_are_bounded_per_cell_and_across_cells() {
    let obstacle = |id: &str| ellipse(id, vec![5.0, 5.0], vec![0.1, 0.1]);
    let one = dmp_server::cells::cell::obstacle_bytes(&obstacle("o00"));
    let server = TestServer::start_with(|c| {
        c.zenoh.disabled = true;
        c.limits.max_scene_bytes = 3 * one;
        c.limits.max_server_bytes = 5 * one;
    })
    .await;
    let client = server.client().await;
    let a = client.clone().with_cell("a");
    let b = client.clone().with_cell("b");
    for i in 0..3 {
        within("put in a", a.put_obstacle(obstacle(&format!("o{i:02}")))).await.unwrap();
    }
    let (c, msg) = code(within("a 4th in a", a.put_obstacle(obstacle("o03"))).await);
    assert_eq!(c, Some(Code::ResourceExhausted), "{msg}");
    assert!(msg.contains(&format!("max_scene_bytes = {}", 3 * one)) && msg.contains("cell `a`"), "{msg}");
    // A replacement of an obstacle is not an addition.
    within("replace in a", a.put_obstacle(obstacle("o00"))).await.unwrap();
    for i in 0..2 {
        within("put in b", b.put_obstacle(obstacle(&format!("o{i:02}")))).await.unwrap();
    }
    let (c, msg) = code(within("a 3rd in b", b.put_obstacle(obstacle("o02"))).await);
    assert_eq!(c, Some(Code::ResourceExhausted), "{msg}");
    assert!(msg.contains(&format!("max_server_bytes = {}", 5 * one)), "{msg}");

    // Both scenes go on being served: listed, planned through.
    slow_line(&client, "r").await;
    assert_eq!(within("list a", a.list_obstacles()).await.unwrap().obstacles.len(), 3);
    assert_eq!(within("list b", b.list_obstacles()).await.unwrap().obstacles.len(), 2);
    let mut motion = spec("r", "line");
    motion.cell = "b".into();
    within("plan in b", client.plan(v1::PlanRequest { motion: Some(motion), dt: 0.01, duration: 1.0 }))
        .await
        .unwrap();
    // A delete in one cell makes room in the other.
    assert!(within("delete in a", a.delete_obstacle("o01")).await.unwrap().changed);
    within("the 3rd in b", b.put_obstacle(obstacle("o02"))).await.unwrap();
    assert_eq!(server.handle().memory().used(), 5 * one);
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread")]
async fn ids_of_more_than_128_characters_are_refused_everywhere() {
    let server = TestServer::start().await;
    let handle = server.handle();
    let client = server.client().await;
    let long = "x".repeat(129);
    let longest = "y".repeat(128);
    let invalid = |r: (Option<Code>, String), field: &str| {
        assert_eq!(r.0, Some(Code::InvalidArgument), "{}", r.1);
        assert!(r.1.contains(field) && r.1.contains("1 to 128 characters"), "{field}: {}", r.1);
    };
    invalid(
        code(within("obstacle", client.put_obstacle(ellipse(&long, vec![0.0; 2], vec![0.1; 2]))).await),
        "obstacle.id",
    );
    invalid(code(within("delete", client.delete_obstacle(&long)).await), "id");
    invalid(code(within("cell", client.clone().with_cell(&long).list_obstacles()).await), "cell");
    invalid(
        code(
            within("primitive", client.put_primitive(&long, "p", &line(vec![0.0; 2], vec![1.0, 0.0], 1.0)))
                .await,
        ),
        "robot_id",
    );
    invalid(
        code(
            within("name", client.put_primitive("r", &long, &line(vec![0.0; 2], vec![1.0, 0.0], 1.0))).await,
        ),
        "name",
    );
    slow_line(&client, "r").await;
    let mut motion = spec("r", "line");
    motion.extra_obstacles = vec![ellipse(&long, vec![5.0; 2], vec![0.1; 2])];
    invalid(
        code(
            within(
                "extra obstacle",
                client.plan(v1::PlanRequest { motion: Some(motion), ..Default::default() }),
            )
            .await,
        ),
        "motion.extra_obstacles[0].id",
    );
    invalid(code(within("list", client.list(&long)).await), "robot_id");

    // Over Zenoh: a key with a long obstacle id, or a long robot id, is refused (counted) and creates nothing.
    let perception =
        within("zenoh open", ObstaclePublisher::open("default", &handle.zenoh_locators, &[])).await.unwrap();
    within("subscriber", perception.wait_for_subscriber(T)).await.unwrap();
    let json = format!(r#"{{"center": [5, 5], "semi_axes": [0.1, 0.1], "id": "{long}"}}"#);
    let session = perception.session();
    within("zenoh long id", async {
        session.put(format!("dmp/default/obstacles/{long}"), json).await.unwrap()
    })
    .await;
    within("zenoh long robot", async {
        session.put(format!("dmp/default/robots/{long}/state"), vec![0u8; 4]).await.unwrap()
    })
    .await;
    until("both refused", || handle.malformed_payloads() >= 2).await;

    // 128 characters are fine, and the cell goes on serving lists and plans.
    within("longest id", client.put_obstacle(ellipse(&longest, vec![5.0; 2], vec![0.1; 2]))).await.unwrap();
    let snapshot = within("list obstacles", client.list_obstacles()).await.unwrap();
    assert_eq!(snapshot.obstacles.iter().map(|o| o.id.as_str()).collect::<Vec<_>>(), [longest.as_str()]);
    within("plan", client.plan(v1::PlanRequest { motion: Some(spec("r", "line")), dt: 0.01, duration: 1.0 }))
        .await
        .unwrap();
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread")]
async fn old_versions_are_pruned_and_lists_come_in_pages() {
    let server = TestServer::start_with(|c| {
        c.zenoh.disabled = true;
        c.limits.max_versions = 3;
        c.limits.list_page_size = 2;
        c.limits.max_list_page_size = 3;
    })
    .await;
    let client = server.client().await;
    let p = line(vec![0.0; 2], vec![1.0, 0.0], 1.0);
    for v in 1..=5 {
        assert_eq!(within("put a", client.put_primitive("r", "a", &p)).await.unwrap().version, v);
    }
    for v in 1..=2 {
        let (c, msg) = code(within("pruned", client.get("r", "a", v)).await);
        assert_eq!(c, Some(Code::NotFound), "version {v}: {msg}");
    }
    assert_eq!(within("kept", client.get("r", "a", 3)).await.unwrap().version, 3);
    for name in ["b", "c", "d", "e"] {
        within("put", client.put_primitive("r", name, &p)).await.unwrap();
    }
    let first = within("first page", client.list_page("r", 0, "")).await.unwrap();
    assert_eq!(first.records.iter().map(|r| r.name.as_str()).collect::<Vec<_>>(), ["a", "b"]);
    assert_eq!(first.next_page_token, "b");
    let big = within("a page too large", client.list_page("r", 1000, &first.next_page_token)).await.unwrap();
    assert_eq!(big.records.iter().map(|r| r.name.as_str()).collect::<Vec<_>>(), ["c", "d", "e"]);
    assert!(big.next_page_token.is_empty(), "the last page");
    // The client library follows the pages.
    let all = within("list", client.list("r")).await.unwrap();
    assert_eq!(
        all.iter().map(|r| (r.name.as_str(), r.version)).collect::<Vec<_>>(),
        [("a", 5), ("b", 1), ("c", 1), ("d", 1), ("e", 1)]
    );
    let (c, msg) = code(within("bad token", client.list_page("r", 0, "a/b")).await);
    assert_eq!(c, Some(Code::InvalidArgument), "{msg}");
    assert!(msg.contains("page_token"), "{msg}");
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread")]
async fn watches_never_starve_executions_and_streams_are_bounded_per_connection_and_client() {
    let server = TestServer::start_with(|c| {
        c.zenoh.disabled = true;
        c.limits.max_watches = 3;
        c.limits.max_streams_per_connection = 4;
        c.limits.max_streams_per_client = 6;
    })
    .await;
    // One connection per client value (each `client()` connects anew); all from 127.0.0.1.
    let watcher = server.client().await;
    let robot = server.client().await;
    // One robot per stream: a robot executes in one stream at a time.
    for r in ["r", "w1", "w2", "x1", "x2", "x3", "x4"] {
        slow_line(&robot, r).await;
    }
    let mut watches = Vec::new();
    for _ in 0..3 {
        watches.push(within("watch", watcher.watch_scene()).await.unwrap());
    }
    let (c, msg) = code(within("a 4th watch", watcher.watch_scene()).await);
    assert_eq!(c, Some(Code::ResourceExhausted), "{msg}");
    assert!(msg.contains("limits.max_watches = 3"), "{msg}");
    // The watches at their limit take nothing from the robots: an execution runs to its end.
    let quick =
        v1::ExecuteRequest { motion: Some(spec("r", "line")), max_duration_s: 0.05, ..Default::default() };
    let mut stream = within("execute while watched", robot.execute(quick)).await.unwrap();
    let mut segments = 0;
    while let Some(s) = within("segment", stream.next()).await {
        s.unwrap();
        segments += 1;
    }
    assert!(segments >= 5, "50 ms in 10 ms segments, to the end: {segments}");
    let executions = || server.handle().open_executions();
    until("the execution's permit is back", || executions() == 0).await;

    // Per connection: the watcher's connection holds 3 watches; one execution more and it is full.
    let on_watcher =
        within("execute on the watcher's connection", watcher.execute(long_execute("w1"))).await.unwrap();
    let (c, msg) = code(within("a 5th on one connection", watcher.execute(long_execute("w2"))).await);
    assert_eq!(c, Some(Code::ResourceExhausted), "{msg}");
    assert!(msg.contains("max_streams_per_connection = 4"), "{msg}");
    // Per client: another connection of the same address has room for 2 more, then the client is full.
    let r1 = within("execute 1", robot.execute(long_execute("x1"))).await.unwrap();
    let r2 = within("execute 2", robot.execute(long_execute("x2"))).await.unwrap();
    let (c, msg) = code(within("a 7th of one client", robot.execute(long_execute("x3"))).await);
    assert_eq!(c, Some(Code::ResourceExhausted), "{msg}");
    assert!(msg.contains("client 127.0.0.1") && msg.contains("max_streams_per_client = 6"), "{msg}");
    // Streams that end give their places back.
    drop(watches);
    until("the watches are gone", || server.handle().open_watches() == 0).await;
    let r3 = within("execute after the watches left", robot.execute(long_execute("x4"))).await.unwrap();
    drop((on_watcher, r1, r2, r3));
    until("every stream is gone", || server.handle().open_streams() == 0).await;
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread")]
async fn empty_cells_are_reclaimed_and_deletes_never_create_one() {
    let server = TestServer::start_with(|c| c.limits.max_cells = 3).await;
    let handle = server.handle();
    let cells = &handle.cells();
    let client = server.client().await;

    // Deletes of junk cells over Zenoh and gRPC create nothing.
    let perception =
        within("zenoh open", ObstaclePublisher::open("default", &handle.zenoh_locators, &[])).await.unwrap();
    within("subscriber", perception.wait_for_subscriber(T)).await.unwrap();
    let session = perception.session();
    for i in 0..20 {
        within("zenoh delete", async { session.delete(format!("dmp/junk{i}/obstacles/o")).await.unwrap() })
            .await;
    }
    // Samples of one session arrive in order: once the marker is in, the deletes were handled.
    within("marker", perception.put_proto(&ellipse("marker", vec![5.0, 5.0], vec![0.1, 0.1]))).await.unwrap();
    until("the marker arrived", || !cells.get("").unwrap().snapshot().obstacles.is_empty()).await;
    assert_eq!(cells.len(), 1, "no cell was created by a delete");
    let change = within("grpc delete", client.clone().with_cell("junk").delete_obstacle("o")).await.unwrap();
    assert!(!change.changed);
    let empty = within("grpc list", client.clone().with_cell("junk2").list_obstacles()).await.unwrap();
    assert!(empty.obstacles.is_empty());
    assert_eq!(cells.len(), 1, "no cell was created by a delete or a list");

    // Cells in use fill the limit; a new one is refused, naming it.
    let x = client.clone().with_cell("x");
    let y = client.clone().with_cell("y");
    within("put x", x.put_obstacle(ellipse("o", vec![5.0, 5.0], vec![0.1, 0.1]))).await.unwrap();
    within("put y", y.put_obstacle(ellipse("o", vec![5.0, 5.0], vec![0.1, 0.1]))).await.unwrap();
    let z = client.clone().with_cell("z");
    let (c, msg) = code(within("put z", z.put_obstacle(ellipse("o", vec![5.0, 5.0], vec![0.1, 0.1]))).await);
    assert_eq!(c, Some(Code::ResourceExhausted), "{msg}");
    assert!(msg.contains("max_cells"), "{msg}");
    // Emptied, a cell is reclaimed (by the reaper, or when a new cell needs its place) and z is served.
    within("delete x", x.delete_obstacle("o")).await.unwrap();
    within("put z", z.put_obstacle(ellipse("o", vec![5.0, 5.0], vec![0.1, 0.1]))).await.unwrap();
    within("delete y", y.delete_obstacle("o")).await.unwrap();
    until("y is reclaimed", || cells.len() == 2).await;
    assert!(cells.find("y").unwrap().is_none() && cells.find("z").unwrap().is_some());
    // A watched cell is in use even when empty: it keeps its place.
    let _watch = within("watch y", y.watch_scene()).await.unwrap();
    let w = client.clone().with_cell("w");
    let (c, msg) = code(within("put w", w.put_obstacle(ellipse("o", vec![5.0, 5.0], vec![0.1, 0.1]))).await);
    assert_eq!(c, Some(Code::ResourceExhausted), "{msg}");
    assert_eq!(cells.len(), 3);
    assert!(cells.find("y").unwrap().is_some());
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread")]
async fn idle_connections_are_closed_and_busy_ones_kept() {
    use tokio::io::AsyncReadExt;
    let server = TestServer::start_with(|c| {
        c.zenoh.disabled = true;
        c.limits.idle_timeout_s = 0.5;
        // Pings answered by the client are not activity.
        c.limits.http2_keepalive_interval_s = 0.1;
    })
    .await;
    // A connection that says nothing is closed.
    let mut idle =
        within("connect", tokio::net::TcpStream::connect(server.handle().grpc_addr)).await.unwrap();
    let started = std::time::Instant::now();
    let mut buf = [0u8; 1024];
    loop {
        match within("the idle connection is closed", idle.read(&mut buf)).await {
            Ok(0) | Err(_) => break,
            Ok(_) => continue, // the server's settings frame
        }
    }
    assert!(started.elapsed() >= Duration::from_millis(400), "closed after {:?}", started.elapsed());

    // A connection with an open stream is kept past the timeout, and its stream goes on.
    let watcher = server.client().await;
    let mut watch = within("watch", watcher.watch_scene()).await.unwrap();
    within("first snapshot", watch.next()).await.unwrap().unwrap();
    let deadline = tokio::time::Instant::now() + Duration::from_millis(1500);
    tokio::time::sleep_until(deadline).await;
    let other = server.client().await;
    within("put", other.put_obstacle(ellipse("o", vec![5.0, 5.0], vec![0.1, 0.1]))).await.unwrap();
    let snapshot = within("change", watch.next()).await.unwrap().unwrap();
    assert_eq!(snapshot.obstacles.len(), 1);
    // A client whose connection was closed while idle connects again for its next request.
    tokio::time::sleep(Duration::from_secs(1)).await;
    within("stats after idling", other.stats()).await.unwrap();
    server.stop().await;
}
