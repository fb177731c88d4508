//! A plant: three servers, each serving its own cell, clients of one Zenoh router in the test process (router
//! mode, loopback, scouting off). Primitives replicate, a cell resolves to its server, robots of neighbouring cells
//! on two servers avoid each other, a server that starts late or comes back catches up (deletes included), and a
//! server's cell is taken by one survivor while it is away (with its scene) and given back when it returns.

use std::collections::BTreeMap;
use std::path::Path;
use std::time::{Duration, Instant};

use crate::default_limits::exact;
use dmp_client::grpc::DmpClient;
use dmp_client::zenoh_pub::ObstaclePublisher;
use dmp_proto::v1;
use dmp_proto::zenoh_session::locators;
use dmp_server::server::{ServerHandle, start};
use dmp_tests::{config, within};
use tokio_stream::StreamExt;

use crate::stale_scene::router;
use crate::{line, spec, until};

/// A server of the plant: id `id`, serving `cells`, a client of the router at `router`, its store in `dir`.
pub(crate) async fn plant_server(
    dir: &Path,
    router: &[String],
    id: &str,
    cells: &[&str],
    neighbours: &[(&str, &[&str])],
) -> ServerHandle {
    let mut c = config(dir);
    (c.zenoh.mode, c.zenoh.listen, c.zenoh.connect) = ("client".into(), Vec::new(), router.to_vec());
    c.cells = cells.iter().map(|s| s.to_string()).collect();
    c.plant.server_id = Some(id.into());
    c.plant.neighbours = neighbours
        .iter()
        .map(|(cell, others)| (cell.to_string(), others.iter().map(|o| o.to_string()).collect()))
        .collect::<BTreeMap<_, _>>();
    within("server start", start(c)).await.expect("server starts")
}

async fn client_of(h: &ServerHandle) -> DmpClient {
    within("connect", DmpClient::connect(format!("http://{}", h.grpc_addr))).await.expect("connects")
}

/// Waits until every server knows every other (their tokens and announcements went through the router).
pub(crate) async fn until_all_known(servers: &[&ServerHandle]) {
    let n = servers.len();
    until("every server knows the plant", || {
        servers.iter().all(|h| h.cells().directory().server_ids().len() == n)
    })
    .await;
}

/// A router on loopback, its endpoints, and `n` store directories (kept as long as the plant runs).
pub(crate) struct Loopback {
    pub(crate) zenohd: zenoh::Session,
    pub(crate) endpoint: Vec<String>,
    pub(crate) dirs: Vec<tempfile::TempDir>,
}

/// A [`Loopback`] plant with `n` store directories.
pub(crate) async fn loopback(n: usize) -> Loopback {
    let zenohd = router("tcp/127.0.0.1:0").await;
    let endpoint = locators(&zenohd).await;
    let dirs = (0..n).map(|_| tempfile::tempdir().unwrap()).collect();
    Loopback { zenohd, endpoint, dirs }
}

/// Servers s1, s2 and s3 of cells a, b and c, stores in `dirs[0..3]`, once each knows the others.
pub(crate) async fn three_servers(
    endpoint: &[String],
    dirs: &[tempfile::TempDir],
) -> (ServerHandle, ServerHandle, ServerHandle) {
    let s1 = plant_server(dirs[0].path(), endpoint, "s1", &["a"], &[]).await;
    let s2 = plant_server(dirs[1].path(), endpoint, "s2", &["b"], &[]).await;
    let s3 = plant_server(dirs[2].path(), endpoint, "s3", &["c"], &[]).await;
    until_all_known(&[&s1, &s2, &s3]).await;
    (s1, s2, s3)
}

/// Shuts `servers` down, then the router.
pub(crate) async fn shut_down(servers: impl IntoIterator<Item = ServerHandle>, zenohd: zenoh::Session) {
    for h in servers {
        within("shutdown", h.shutdown()).await.unwrap();
    }
    within("router close", std::future::IntoFuture::into_future(zenohd.close())).await.unwrap();
}

/// Whether `h` holds version `version` of `(robot, name)`.
fn holds(h: &ServerHandle, robot: &str, name: &str, version: u64) -> bool {
    h.store().get(robot, name, version).is_ok()
}

#[tokio::test(flavor = "multi_thread")]
async fn primitives_replicate_and_a_cell_resolves_to_its_server() {
    let Loopback { zenohd, endpoint, dirs } = loopback(3).await;
    let (s1, s2, s3) = three_servers(&endpoint, &dirs).await;
    let (c1, c2) = (client_of(&s1).await, client_of(&s2).await);

    // Put on s1: readable on s2 and s3 within a second, the same version, bit for bit.
    let p = line(vec![0.0, 0.0], vec![1.0, 0.5], 1.0);
    let put = within("put", c1.put_primitive("r1", "reach", &p)).await.unwrap();
    let stored = Instant::now();
    until("replicated to s2 and s3", || {
        holds(&s2, "r1", "reach", put.version) && holds(&s3, "r1", "reach", put.version)
    })
    .await;
    let took = stored.elapsed();
    assert!(took < Duration::from_secs(1), "replication took {took:?}");
    let got = within("get on s2", c2.get("r1", "reach", 0)).await.unwrap();
    assert_eq!(got.version, put.version);
    assert_eq!(got.primitive, put.primitive);
    assert_eq!(got.origin_server, "s1");

    // The same (robot, name) learned on two servers at once: both versions everywhere, one latest everywhere.
    let (q1, q2) = (line(vec![0.0], vec![1.0], 1.0), line(vec![0.0], vec![2.0], 1.0));
    let (v1, v2) = tokio::join!(c1.put_primitive("r1", "dup", &q1), c2.put_primitive("r1", "dup", &q2));
    let (v1, v2) = (v1.unwrap().version, v2.unwrap().version);
    assert_ne!(v1, v2);
    let servers = [&s1, &s2, &s3];
    until("both versions on every server", || {
        servers.iter().all(|h| holds(h, "r1", "dup", v1) && holds(h, "r1", "dup", v2))
    })
    .await;
    let latest: Vec<u64> = servers.iter().map(|h| h.store().get("r1", "dup", 0).unwrap().version).collect();
    assert_eq!(latest, vec![v1.max(v2); 3], "every server agrees on the latest");

    // A cell resolves to its server, over Zenoh, from a client of the router.
    let found = within(
        "resolve b",
        dmp_client::discovery::resolve_cell_via(&endpoint, None, "b", Duration::from_secs(5)),
    )
    .await
    .unwrap();
    assert_eq!((found.server_id.as_str(), found.grpc_address), ("s2", format!("http://{}", s2.grpc_addr)));
    let none =
        dmp_client::discovery::resolve_cell_via(&endpoint, None, "nowhere", Duration::from_millis(500));
    let e = within("resolve nowhere", none).await.unwrap_err();
    assert!(e.to_string().contains("cell `nowhere`"), "{e}");
    // dmpctl without --server finds it too.
    let cli = <dmpctl::cli::Cli as clap::Parser>::try_parse_from([
        "dmpctl",
        "--cell",
        "b",
        "--zenoh-connect",
        &endpoint[0],
        "info",
    ])
    .unwrap();
    let out = within("dmpctl info", dmpctl::cli::run_async(cli)).await.unwrap();
    let info: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(info["cell"], "b", "{out}");

    // A request for a cell s1 does not serve names the server that does.
    let e = within("scene of b on s1", c1.clone().with_cell("b").list_obstacles()).await.unwrap_err();
    assert_eq!(e.code(), Some(tonic::Code::FailedPrecondition), "{e}");
    let said = e.to_string();
    assert!(
        said.contains("cell `b`") && said.contains("`s2`") && said.contains(&s2.grpc_addr.to_string()),
        "{said}"
    );

    shut_down([s1, s2, s3], zenohd).await;
}

#[tokio::test(flavor = "multi_thread")]
async fn a_server_that_starts_late_or_comes_back_catches_up() {
    let zenohd = router("tcp/127.0.0.1:0").await;
    let endpoint = locators(&zenohd).await;
    let (d1, d2) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let s1 = plant_server(d1.path(), &endpoint, "s1", &["a"], &[]).await;
    let c1 = client_of(&s1).await;
    let early =
        within("put early", c1.put_primitive("r", "early", &line(vec![0.0], vec![1.0], 1.0))).await.unwrap();

    // Started after the put: it asks s1 for what it lacks.
    let s2 = plant_server(d2.path(), &endpoint, "s2", &["b"], &[]).await;
    until("the late server gets the early primitive", || holds(&s2, "r", "early", early.version)).await;
    within("s2 down", s2.shutdown()).await.unwrap();

    // Learned while s2 was down: it gets it when it comes back on its store.
    let missed = within("put missed", c1.put_primitive("r", "missed", &line(vec![0.0], vec![2.0], 1.0)))
        .await
        .unwrap();
    let s2 = plant_server(d2.path(), &endpoint, "s2", &["b"], &[]).await;
    until("the restarted server gets what it missed", || holds(&s2, "r", "missed", missed.version)).await;
    assert!(holds(&s2, "r", "early", early.version), "kept in its store");
    assert_eq!(s2.store().get("r", "missed", 0).unwrap().primitive, missed.primitive);

    shut_down([s1, s2], zenohd).await;
}

#[tokio::test(flavor = "multi_thread")]
async fn a_delete_reaches_a_server_that_was_down_and_a_newer_relearn_wins_everywhere() {
    let Loopback { zenohd, endpoint, dirs } = loopback(3).await;
    let (s1, s2, s3) = three_servers(&endpoint, &dirs).await;
    let (c1, c3) = (client_of(&s1).await, client_of(&s3).await);
    let gone =
        within("put gone", c1.put_primitive("r", "gone", &line(vec![0.0], vec![1.0], 1.0))).await.unwrap();
    let kept =
        within("put kept", c1.put_primitive("r", "kept", &line(vec![0.0], vec![2.0], 1.0))).await.unwrap();
    until("s2 holds both", || holds(&s2, "r", "gone", gone.version) && holds(&s2, "r", "kept", kept.version))
        .await;

    // s2 goes down; `gone` is deleted on s1 meanwhile; s2 comes back on its store and deletes it too.
    within("s2 down", s2.shutdown()).await.unwrap();
    within("delete on s1", c1.delete("r", "gone")).await.unwrap();
    until("s3 applies the delete", || !holds(&s3, "r", "gone", gone.version)).await;
    let s2 = plant_server(dirs[1].path(), &endpoint, "s2", &["b"], &[]).await;
    until("the restarted server applies the delete it missed", || !holds(&s2, "r", "gone", gone.version))
        .await;
    assert!(holds(&s2, "r", "kept", kept.version), "the other primitive stays");
    assert!(s2.store().tombstone("r", "gone").unwrap().is_some_and(|n| n >= gone.version));
    // s2 came back holding `gone` and the others asked it for its versions: the tombstone keeps it deleted.
    for h in [&s1, &s2, &s3] {
        assert!(h.store().get("r", "gone", 0).is_err(), "deleted everywhere");
    }

    // Deleted on s1, learned again on s3 after the delete: the new version is kept everywhere and is the latest.
    within("delete kept", c1.delete("r", "kept")).await.unwrap();
    until("s3 applies the second delete", || !holds(&s3, "r", "kept", kept.version)).await;
    let again = within("relearn on s3", c3.put_primitive("r", "kept", &line(vec![0.0], vec![3.0], 1.0)))
        .await
        .unwrap();
    assert!(again.version > kept.version);
    let servers = [&s1, &s2, &s3];
    until("the re-learned version everywhere", || {
        servers.iter().all(|h| holds(h, "r", "kept", again.version))
    })
    .await;
    for h in servers {
        let latest = h.store().get("r", "kept", 0).unwrap();
        assert_eq!((latest.version, &latest.primitive), (again.version, &again.primitive));
        assert!(!holds(h, "r", "kept", kept.version));
    }

    shut_down([s1, s2, s3], zenohd).await;
}

#[tokio::test(flavor = "multi_thread")]
async fn a_load_via_zenoh_discovery_spreads_its_robots_over_the_plant() {
    let Loopback { zenohd, endpoint, dirs } = loopback(3).await;
    let s1 = plant_server(dirs[0].path(), &endpoint, "s1", &["a", "d"], &[]).await;
    let s2 = plant_server(dirs[1].path(), &endpoint, "s2", &["b"], &[]).await;
    let s3 = plant_server(dirs[2].path(), &endpoint, "s3", &["c"], &[]).await;
    until_all_known(&[&s1, &s2, &s3]).await;
    let cells = |names: &[&str]| names.iter().map(|c| c.to_string()).collect::<Vec<_>>();
    // 8 robots in cells of 2: cells a, b, c, d; the server given is never asked.
    let args = dmp_sim::load::LoadArgs {
        robots: 8,
        cell_size: 2,
        rate: 100.0,
        segment_s: 0.05,
        duration: 1.5,
        dim: 2,
        cell_names: cells(&["a", "b", "c", "d"]),
        via_zenoh_discovery: true,
        ..Default::default()
    };
    let report = within("the load", dmp_sim::load::run(&args, "http://127.0.0.1:1", &endpoint))
        .await
        .expect("the load runs through the plant");
    assert!(report.errors.is_empty(), "{:#?}", report.errors);
    assert_eq!((report.cells, report.streams_started, report.streams_failed), (4, 8, 0));
    let parts: Vec<(&str, String, Vec<String>, usize)> = report
        .servers
        .iter()
        .map(|p| (p.server_id.as_str(), p.grpc_address.clone(), p.cells.clone(), p.robots))
        .collect();
    let url = |h: &ServerHandle| format!("http://{}", h.grpc_addr);
    assert_eq!(
        parts,
        [
            ("s1", url(&s1), cells(&["a", "d"]), 4),
            ("s2", url(&s2), cells(&["b"]), 2),
            ("s3", url(&s3), cells(&["c"]), 2)
        ]
    );
    for p in &report.servers {
        assert!(p.setpoints_expected > 0 && p.setpoints_on_time <= p.setpoints_expected, "{p:?}");
        assert!(p.lateness_ms.count > 0 && p.segments_sent.is_some_and(|n| n > 0), "{p:?}");
        assert!(p.rss_mib_max.is_some_and(|m| m > 0.0), "{p:?}");
    }
    let sum = |f: fn(&dmp_sim::load::report::ServerPart) -> u64| report.servers.iter().map(f).sum::<u64>();
    assert_eq!(sum(|p| p.setpoints_expected), report.setpoints_expected);
    assert_eq!(sum(|p| p.setpoints_on_time), report.setpoints_on_time);
    assert_eq!(sum(|p| p.lateness_ms.count), report.lateness_ms.count);
    // Each server streamed (its part's segments are its own count), and the clean-up removed the primitives
    // everywhere.
    for h in [&s1, &s2, &s3] {
        assert!(h.segments_sent() > 0);
    }
    until("the load's primitives deleted on every server", || {
        [&s1, &s2, &s3].iter().all(|h| h.store().list("load.c0.r0").unwrap().is_empty())
    })
    .await;
    // A cell no server serves is refused, naming it.
    let lost = dmp_sim::load::LoadArgs { robots: 1, cell_names: cells(&["nowhere"]), ..args };
    let e =
        within("no server", dmp_sim::load::run(&lost, "http://127.0.0.1:1", &endpoint)).await.unwrap_err();
    assert!(e.to_string().contains("cell `nowhere`"), "{e}");

    shut_down([s1, s2, s3], zenohd).await;
}

/// The closest that a planned path of `seg` (2-D) comes to `point`.
fn closest(seg: &v1::Segment, point: [f64; 2]) -> f64 {
    seg.positions.chunks(2).map(|p| (p[0] - point[0]).hypot(p[1] - point[1])).fold(f64::INFINITY, f64::min)
}

#[tokio::test(flavor = "multi_thread")]
async fn robots_of_neighbouring_cells_on_two_servers_avoid_each_other() {
    let Loopback { zenohd, endpoint, dirs } = loopback(3).await;
    let s1 = plant_server(dirs[0].path(), &endpoint, "s1", &["a"], &[("a", &["b"])]).await;
    let s2 = plant_server(dirs[1].path(), &endpoint, "s2", &["b"], &[("b", &["a"])]).await;
    let s3 = plant_server(dirs[2].path(), &endpoint, "s3", &["c"], &[]).await;
    until_all_known(&[&s1, &s2, &s3]).await;
    let footprint = v1::Superquadric { semi_axes: vec![0.1, 0.1], exponents: vec![] };

    // r1 in cell a on s1, creeping across (0.5, 0) in real time for a long while.
    let c1 = client_of(&s1).await.with_cell("a");
    within("put r1", c1.put_primitive("r1", "creep", &line(vec![0.5, -0.01], vec![0.5, 0.01], 60.0)))
        .await
        .unwrap();
    let mut motion = spec("r1", "creep");
    motion.footprint = Some(footprint.clone());
    let request = v1::ExecuteRequest {
        motion: Some(motion),
        pacing: v1::Pacing::Realtime as i32,
        ..Default::default()
    };
    let mut r1 = within("execute r1", c1.execute(request)).await.unwrap();
    let reader = tokio::spawn(async move { while let Some(Ok(_)) = r1.next().await {} });
    let sees_r1 = |h: &ServerHandle, cell: &str| {
        h.cells().find(cell).unwrap().is_some_and(|c| {
            c.other_robots("", dmp_server::clock::system_unix_s(), 0.5)
                .iter()
                .any(|r| r.state.robot_id == "r1")
        })
    };
    until("s2's cell b sees r1 of cell a", || sees_r1(&s2, "b")).await;

    // r2 crosses r1's place: in cell b (a neighbour, on s2) it goes round r1; in cell c (no neighbour, on s3) it
    // goes straight through.
    let plan = |h: &ServerHandle, cell: &'static str| {
        let url = format!("http://{}", h.grpc_addr);
        let footprint = footprint.clone();
        async move {
            let c = within("connect", DmpClient::connect(url)).await.unwrap().with_cell(cell);
            within("put r2", c.put_primitive("r2", "cross", &line(vec![0.0, 0.0], vec![1.0, 0.0], 6.0)))
                .await
                .unwrap();
            // The DMP's avoidance as the paper has it: no limits holding the swerve back.
            let mut motion = exact(spec("r2", "cross"));
            motion.footprint = Some(footprint);
            let request = v1::PlanRequest { motion: Some(motion), dt: 0.001, duration: 8.0 };
            within("plan r2", c.plan(request)).await.unwrap().trajectory.unwrap()
        }
    };
    let neighbour = plan(&s2, "b").await;
    // Where s2 saw r1 (it creeps 0.33 mm/s: a plan's time moves it by less than a millimetre).
    let seen =
        s2.cells().find("b").unwrap().unwrap().other_robots("", dmp_server::clock::system_unix_s(), 0.5);
    let r1_at =
        seen.iter().find(|r| r.state.robot_id == "r1").expect("r1 still executing").state.position.clone();
    let stranger = plan(&s3, "c").await;
    let (near, far) = (closest(&neighbour, [r1_at[0], r1_at[1]]), closest(&stranger, [r1_at[0], r1_at[1]]));
    assert!(far < 0.02, "without the neighbour r2 goes through r1's place ({far})");
    assert!(near > 0.1 - 2e-3, "r2 keeps out of r1's footprint (radius 0.1): {near}");
    assert!(!sees_r1(&s3, "c"), "cell c does not take cell a's robots");

    reader.abort();
    shut_down([s1, s2, s3], zenohd).await;
}

/// Whether `h` holds obstacle `id` in `cell` (never creating the cell).
/// Reads `stream` to its end: the status it ends with (an end without one fails the test).
async fn last_status<T>(
    stream: &mut (impl tokio_stream::Stream<Item = Result<T, dmp_client::ClientError>> + Unpin),
) -> dmp_client::ClientError {
    loop {
        match stream.next().await {
            Some(Ok(_)) => continue,
            Some(Err(e)) => return e,
            None => panic!("the stream ended without a status"),
        }
    }
}

fn sees_obstacle(h: &ServerHandle, cell: &str, id: &str) -> bool {
    h.cells().find(cell).ok().flatten().is_some_and(|c| c.snapshot().obstacles.contains_key(id))
}

#[tokio::test(flavor = "multi_thread")]
async fn a_cell_is_taken_while_its_server_is_away_and_given_back_when_it_returns() {
    use dmp_server::cells::rendezvous::rendezvous;
    let Loopback { zenohd, endpoint, dirs } = loopback(3).await;
    let (s1, s2, s3) = three_servers(&endpoint, &dirs).await;
    // A perception node keeping cell a's latest obstacle: what a taker asks for the cell's scene.
    let mut perception =
        within("perception open", ObstaclePublisher::open("a", &endpoint, &[])).await.unwrap();
    within("queryable", perception.serve_latest()).await.unwrap();
    within("subscriber", perception.wait_for_subscriber(dmp_tests::T)).await.unwrap();
    within("put", perception.put_proto(&crate::ellipse("box", vec![3.0, 3.0], vec![0.1, 0.1])))
        .await
        .unwrap();
    until("s1 has cell a's obstacle", || sees_obstacle(&s1, "a", "box")).await;

    // s1 leaves: one survivor, rendezvous' pick, takes cell a with its scene; the other does not.
    within("s1 down", s1.shutdown()).await.unwrap();
    let (taker, other) = match rendezvous("a", ["s2", "s3"]).unwrap() {
        "s2" => (&s2, &s3),
        _ => (&s3, &s2),
    };
    until("the taker serves cell a", || taker.cells().serves("a")).await;
    until("with cell a's scene", || sees_obstacle(taker, "a", "box")).await;
    assert!(!other.cells().serves("a"), "one server takes the cell");
    let found = within(
        "resolve a",
        dmp_client::discovery::resolve_cell_via(&endpoint, None, "a", Duration::from_secs(5)),
    )
    .await
    .unwrap();
    assert_eq!(found.grpc_address, format!("http://{}", taker.grpc_addr));
    // The other survivor refuses cell a, naming the taker.
    let refused = within("the other refuses", client_of(other).await.with_cell("a").list_obstacles())
        .await
        .unwrap_err()
        .to_string();
    assert!(
        refused.contains("its server `s1` is gone")
            && refused.contains("serves it meanwhile")
            && refused.contains(&taker.grpc_addr.to_string()),
        "{refused}"
    );

    // A robot of cell a streams on the taker.
    let c = client_of(taker).await.with_cell("a");
    within("put r1", c.put_primitive("r1", "creep", &line(vec![0.0, 0.0], vec![0.1, 0.0], 60.0)))
        .await
        .unwrap();
    let request = v1::ExecuteRequest {
        motion: Some(spec("r1", "creep")),
        pacing: v1::Pacing::Realtime as i32,
        ..Default::default()
    };
    let mut stream = within("execute", c.execute(request)).await.unwrap();
    within("a segment", stream.next()).await.unwrap().unwrap();
    // And an observer watches cell a's scene there.
    let mut watch = within("watch", c.watch_scene()).await.unwrap();
    within("the scene", watch.next()).await.unwrap().unwrap();

    // s1 comes back: the taker gives cell a back, and its stream and watch end naming s1.
    let s1 = plant_server(dirs[0].path(), &endpoint, "s1", &["a"], &[]).await;
    let ended = within("the stream ends", last_status(&mut stream)).await;
    assert_eq!(ended.code(), Some(tonic::Code::Unavailable), "{ended}");
    let said = ended.to_string();
    assert!(said.contains("`s1`") && said.contains(&s1.grpc_addr.to_string()), "{said}");
    let watch_ended = within("the watch ends", last_status(&mut watch)).await;
    assert_eq!(watch_ended.code(), Some(tonic::Code::Unavailable), "{watch_ended}");
    assert!(watch_ended.to_string().contains("`s1`"), "{watch_ended}");
    assert!(!taker.cells().serves("a") && !sees_obstacle(taker, "a", "box"), "the taker let it go");

    within("perception close", perception.close()).await.unwrap();
    shut_down([s1, s2, s3], zenohd).await;
}
