//! Fail-over of a plant with real processes: three `dmp-server` binaries (cells a, b, c), clients of a Zenoh router
//! in the test process (router mode, loopback, scouting off, the lease of `deploy/zenoh-lease.json5`). A robot of
//! cell a streams through the client library's resumable session; its server is killed (SIGKILL): the robot
//! resumes on the one survivor that rendezvous hashing picks, with continuous setpoints; the killed server restarts
//! on its store, catches up with a primitive put meanwhile, and takes its cell back, the robot following it.
//!
//! The binary is only reachable from this package's tests (`CARGO_BIN_EXE_dmp-server`), hence the test lives here
//! rather than in `tests/tests/server/plant.rs`, whose in-process servers cannot be killed.
#![cfg(target_os = "linux")]

use std::collections::BTreeSet;
use std::future::{Future, IntoFuture};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use dmp_client::grpc::DmpClient;
use dmp_client::resume::{ResumableSession, ResumeOptions};
use dmp_client::setpoints::Setpoints;
use dmp_proto::keys::{cell_server_key, server_key};
use dmp_proto::zenoh_session::{SessionOptions, locators, session_config};
use dmp_proto::{codec, v1};
use dmp_server::cells::rendezvous::rendezvous;
use dmp_server::config::Config;

/// The longest any single await may take.
const T: Duration = Duration::from_secs(60);

async fn within<F: Future>(what: &str, f: F) -> F::Output {
    tokio::time::timeout(T, f).await.unwrap_or_else(|_| panic!("timed out: {what}"))
}

/// Polls `cond` (async) until it holds, at most [`T`].
async fn until<F: Future<Output = bool>>(what: &str, mut cond: impl FnMut() -> F) {
    within(what, async {
        while !cond().await {
            tokio::time::sleep(Duration::from_millis(10)).await;
        }
    })
    .await
}

/// One server of the plant: its process (killed when dropped), its id, cell and directory (store, log).
struct Server {
    id: String,
    cell: String,
    dir: PathBuf,
    child: Option<Child>,
}

impl Server {
    fn start(dir: &Path, router: &str, id: &str, cell: &str) -> Self {
        std::fs::create_dir_all(dir).unwrap();
        let mut c = Config { grpc_addr: "127.0.0.1:0".parse().unwrap(), ..Default::default() };
        c.data_dir = dir.join("data");
        c.cells = vec![cell.into()];
        c.plant.server_id = Some(id.into());
        c.zenoh.mode = "client".into();
        c.zenoh.listen = Vec::new();
        c.zenoh.connect = vec![router.into()];
        c.zenoh.multicast_scouting = false;
        c.zenoh.config_file = Some(lease_file());
        let config = dir.join("server.toml");
        std::fs::write(&config, toml::to_string(&c).unwrap()).unwrap();
        let mut s = Self { id: id.into(), cell: cell.into(), dir: dir.to_path_buf(), child: None };
        s.spawn();
        s
    }

    fn spawn(&mut self) {
        let log = std::fs::OpenOptions::new().create(true).append(true).open(self.dir.join("log")).unwrap();
        let child = Command::new(env!("CARGO_BIN_EXE_dmp-server"))
            .arg("--config")
            .arg(self.dir.join("server.toml"))
            .env("RUST_LOG", "warn,dmp_server::plant=info")
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(log)
            .spawn()
            .expect("dmp-server runs");
        self.child = Some(child);
    }

    /// SIGSTOP: the process freezes, its connections stay open (a host that hangs, or is cut off).
    fn freeze(&self) {
        let pid = self.child.as_ref().expect("running").id().to_string();
        let stopped = Command::new("kill").args(["-STOP", &pid]).status().unwrap();
        assert!(stopped.success());
    }

    /// SIGKILL, and reaped.
    fn kill(&mut self) {
        if let Some(mut c) = self.child.take() {
            c.kill().unwrap();
            c.wait().unwrap();
        }
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        self.kill();
    }
}

/// The recommended short lease (`deploy/zenoh-lease.json5`).
fn lease_file() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../deploy/zenoh-lease.json5")
}

/// A plant: the router, its three servers, and a Zenoh client of the router for the test's questions.
struct Plant {
    _dir: tempfile::TempDir,
    router: zenoh::Session,
    zenoh: zenoh::Session,
    servers: Vec<Server>,
}

impl Plant {
    async fn start() -> Self {
        let mut c = zenoh::Config::from_file(lease_file()).unwrap();
        c.insert_json5("mode", "\"router\"").unwrap();
        c.insert_json5("listen/endpoints", "[\"tcp/127.0.0.1:0\"]").unwrap();
        c.insert_json5("scouting/multicast/enabled", "false").unwrap();
        c.insert_json5("scouting/gossip/enabled", "false").unwrap();
        let router = within("router open", zenoh::open(c).into_future()).await.unwrap();
        let endpoint = locators(&router).await.remove(0);
        let options = SessionOptions {
            mode: "client".into(),
            listen: Some(Vec::new()),
            connect: vec![endpoint.clone()],
            multicast_scouting: false,
            config_file: None,
            tls: None,
            access_control: None,
        };
        let zenoh = within("client open", zenoh::open(session_config(&options).unwrap()).into_future())
            .await
            .unwrap();
        let dir = tempfile::tempdir().unwrap();
        let servers = [("s1", "a"), ("s2", "b"), ("s3", "c")]
            .iter()
            .map(|(id, cell)| Server::start(&dir.path().join(id), &endpoint, id, cell))
            .collect();
        let plant = Self { _dir: dir, router, zenoh, servers };
        for s in &plant.servers {
            plant.until_knows_the_others(s).await;
        }
        plant
    }

    /// The announcement of server `id`, once it answers.
    async fn announcement(&self, id: &str) -> v1::PlantServer {
        within(&format!("server {id} answers"), async {
            loop {
                if let Some(s) = self.ask(id).await {
                    return s;
                }
                tokio::time::sleep(Duration::from_millis(10)).await;
            }
        })
        .await
    }

    async fn ask(&self, id: &str) -> Option<v1::PlantServer> {
        let replies = self.zenoh.get(server_key(id)).timeout(Duration::from_millis(500)).await.ok()?;
        let reply = replies.recv_async().await.ok()?;
        codec::decode::<v1::PlantServer>(&reply.result().ok()?.payload().to_bytes()).ok()
    }

    async fn client(&self, id: &str) -> DmpClient {
        let s = self.announcement(id).await;
        within("connect", DmpClient::connect(s.grpc_address)).await.unwrap()
    }

    /// Waits until `s` names the server of every other cell (its directory holds them all): only then would it
    /// take their cells.
    async fn until_knows_the_others(&self, s: &Server) {
        let client = self.client(&s.id).await;
        for other in self.servers.iter().filter(|o| o.id != s.id) {
            let c = client.clone().with_cell(other.cell.clone());
            let (id, cell) = (other.id.clone(), other.cell.clone());
            until(&format!("{} knows {id}", s.id), || {
                let c = c.clone();
                let want = (format!("`{id}`"), format!("cell `{cell}`"));
                async move {
                    matches!(c.list_obstacles().await, Err(e) if e.to_string().contains(&want.0)
                        && e.to_string().contains(&want.1))
                }
            })
            .await;
        }
    }

    /// The servers answering for `cell` on `dmp/@cells/<cell>`.
    async fn announcing(&self, cell: &str) -> BTreeSet<String> {
        let replies = within(
            "ask for a cell",
            self.zenoh
                .get(cell_server_key(cell))
                .target(zenoh::query::QueryTarget::All)
                .consolidation(zenoh::query::ConsolidationMode::None)
                .timeout(Duration::from_secs(2))
                .into_future(),
        )
        .await
        .unwrap();
        let mut ids = BTreeSet::new();
        while let Ok(r) = replies.recv_async().await {
            if let Ok(s) = r.result()
                && let Ok(p) = codec::decode::<v1::PlantServer>(&s.payload().to_bytes())
            {
                ids.insert(p.server_id);
            }
        }
        ids
    }

    async fn close(mut self) {
        for s in &mut self.servers {
            s.kill();
        }
        within("client close", self.zenoh.close().into_future()).await.unwrap();
        within("router close", self.router.close().into_future()).await.unwrap();
    }
}

/// A slow 2-D reach of robot r1 from the origin to (1, 0.5) over 30 s (every resumption replays it from where the
/// robot is: the run outlasts the test).
fn reach() -> dmp::Primitive {
    dmp::Primitive::straight_line(50, 4.0, vec![3050.0; 2], None, 30.0, vec![0.0, 0.0], vec![1.0, 0.5])
        .unwrap()
}

fn request() -> v1::ExecuteRequest {
    v1::ExecuteRequest {
        motion: Some(v1::MotionSpec {
            robot_id: "r1".into(),
            primitive: "reach".into(),
            cell: "a".into(),
            // The DMP's own trajectory: the continuity across a fail-over is judged on it (with the default
            // limits, the resumed run's first points step by twice the speed bound: an open finding).
            limits: Some(dmp_proto::limits::NO_LIMITS),
            margin: -1.0,
            ..Default::default()
        }),
        pacing: v1::Pacing::Realtime as i32,
        ..Default::default()
    }
}

/// The robot: the resumable session and the setpoints it received.
struct Robot {
    session: ResumableSession,
    setpoints: Setpoints,
    /// The wall time (Unix seconds) of the last setpoint received.
    last_due: f64,
}

fn unix_now() -> f64 {
    std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap().as_secs_f64()
}

impl Robot {
    /// Reads one segment.
    async fn read(&mut self) -> v1::Segment {
        let seg = within("a segment", self.session.next_segment()).await.expect("the run goes on").unwrap();
        self.setpoints.push(&seg).unwrap();
        let n = seg.positions.len() / seg.dim.max(1) as usize;
        self.last_due = seg.start_unix_s + n.saturating_sub(1) as f64 * seg.dt;
        seg
    }

    /// Reads segments for `run_s` seconds of the run.
    async fn read_for(&mut self, run_s: f64) {
        let until = self.read().await.start_time + run_s;
        while self.read().await.start_time < until {}
    }

    /// Reads until the session has resumed `n` times in all; when its first segment after that came, and how long
    /// the robot still had setpoints of the stream before then (negative: it waited that long).
    async fn until_resumed(&mut self, n: u32) -> (Instant, f64) {
        loop {
            let due = self.last_due;
            self.read().await;
            if self.session.resumes() >= n {
                return (Instant::now(), due - unix_now());
            }
        }
    }
}

/// Asserts that the setpoints never move farther in one step than the fastest speed of the run allows, and that
/// the velocity never changes by more than the largest acceleration allows: no jump at either resumption.
fn assert_continuous(setpoints: &Setpoints) {
    let t = setpoints.trajectory().expect("setpoints");
    let d = 2;
    let n = t.t.len();
    assert!(n > 500, "{n} setpoints");
    let norm = |v: &[f64]| v[0].hypot(v[1]);
    let rows = |v: &[f64], k: usize| v[k * d..(k + 1) * d].to_vec();
    let vmax = (0..n).map(|k| norm(&rows(&t.xd, k))).fold(0.0, f64::max);
    let amax = (0..n).map(|k| norm(&rows(&t.xdd, k))).fold(0.0, f64::max);
    for k in 1..n {
        let dt = t.t[k] - t.t[k - 1];
        assert!(dt > 0.0 && dt < 1.5e-3, "time step {dt} at {k}");
        let (x0, x1) = (rows(&t.x, k - 1), rows(&t.x, k));
        let (v0, v1) = (rows(&t.xd, k - 1), rows(&t.xd, k));
        let dx = norm(&[x1[0] - x0[0], x1[1] - x0[1]]);
        let dv = norm(&[v1[0] - v0[0], v1[1] - v0[1]]);
        assert!(dx <= 1.5 * vmax * dt + 1e-9, "position jump {dx} at t = {} (vmax {vmax})", t.t[k]);
        assert!(dv <= 1.5 * amax * dt + 1e-6, "velocity jump {dv} at t = {} (amax {amax})", t.t[k]);
    }
}

/// Kills the server of cell a (s1) while the robot streams, and returns the time from the kill to the first segment
/// from the survivor, checking that the one survivor rendezvous hashing picks, and only it, serves the cell.
async fn kill_a(plant: &mut Plant, robot: &mut Robot) -> (Duration, f64, String) {
    let resumes = robot.session.resumes();
    robot.read_for(0.2).await;
    assert_eq!(robot.session.server().server_id, "s1");
    let killed = Instant::now();
    plant.servers[0].kill();
    let (first, margin) = robot.until_resumed(resumes + 1).await;
    let taker = rendezvous("a", ["s2", "s3"]).unwrap().to_owned();
    assert_eq!(robot.session.server().server_id, taker, "the survivor of highest weight took cell a");
    assert_eq!(plant.announcing("a").await, BTreeSet::from([taker.clone()]), "one server serves cell a");
    (first - killed, margin, taker)
}

/// Freezes the server of cell a (s1) while the robot streams, and returns the time from the freeze to the first
/// segment from the survivor; then kills it.
async fn freeze_a(plant: &mut Plant, robot: &mut Robot) -> Duration {
    let resumes = robot.session.resumes();
    robot.read_for(0.2).await;
    assert_eq!(robot.session.server().server_id, "s1");
    let frozen = Instant::now();
    plant.servers[0].freeze();
    let (first, _) = robot.until_resumed(resumes + 1).await;
    assert_eq!(robot.session.server().server_id, rendezvous("a", ["s2", "s3"]).unwrap());
    plant.servers[0].kill();
    first - frozen
}

/// Restarts s1 and waits until the robot is back on it; the time from the restart to the first segment from s1.
async fn restart_a(plant: &mut Plant, robot: &mut Robot) -> Duration {
    let resumes = robot.session.resumes();
    let restarted = Instant::now();
    plant.servers[0].spawn();
    let (first, _) = robot.until_resumed(resumes + 1).await;
    assert_eq!(robot.session.server().server_id, "s1", "cell a went back to its server");
    first - restarted
}

async fn setup() -> (Plant, Robot) {
    setup_with(ResumeOptions::default()).await
}

async fn setup_with(options: ResumeOptions) -> (Plant, Robot) {
    let plant = Plant::start().await;
    let c1 = plant.client("s1").await;
    let put = within("put", c1.put_primitive("r1", "reach", &reach())).await.unwrap();
    for id in ["s2", "s3"] {
        let c = plant.client(id).await;
        until(&format!("the primitive on {id}"), || {
            let c = c.clone();
            async move { c.get("r1", "reach", put.version).await.is_ok() }
        })
        .await;
    }
    let session = within("open", ResumableSession::open(&plant.zenoh, request(), options)).await.unwrap();
    assert_eq!(session.server().server_id, "s1");
    (plant, Robot { session, setpoints: Setpoints::new(), last_due: 0.0 })
}

#[tokio::test(flavor = "multi_thread")]
async fn a_killed_servers_robot_resumes_on_a_survivor_and_comes_back_with_its_cell() {
    let (mut plant, mut robot) = setup().await;
    let (gap, margin, taker) = kill_a(&mut plant, &mut robot).await;
    eprintln!("kill -9 to the first segment from the survivor: {gap:?}; setpoints left then: {margin:.4} s");
    robot.read_for(0.3).await;

    // Learned while s1 is down: s1 catches up when it comes back. A new version of the running primitive, the
    // other way, is learned too: the session runs the version it started with wherever it resumes.
    let missed = within("put missed", plant.client(&taker).await.put_primitive("r1", "missed", &reach()))
        .await
        .unwrap();
    let back =
        dmp::Primitive::straight_line(50, 4.0, vec![3050.0; 2], None, 30.0, vec![0.0; 2], vec![-1.0, -0.5])
            .unwrap();
    within("put the other way", plant.client(&taker).await.put_primitive("r1", "reach", &back))
        .await
        .unwrap();
    restart_a(&mut plant, &mut robot).await;
    assert_eq!(plant.announcing("a").await, BTreeSet::from(["s1".to_owned()]), "the taker gave cell a back");
    let c1 = plant.client("s1").await;
    until("s1 catches up", || {
        let c1 = c1.clone();
        async move { c1.get("r1", "missed", missed.version).await.is_ok() }
    })
    .await;
    robot.read_for(0.3).await;
    assert_eq!(robot.session.resumes(), 2);
    let t = robot.setpoints.trajectory().unwrap();
    let v = &t.xd[t.xd.len() - 2..];
    assert!(v[0] > 0.0 && v[1] > 0.0, "still on the way to (1, 0.5), the version it started with: {v:?}");
    assert_continuous(&robot.setpoints);
    within("stop", robot.session.stop()).await.unwrap();
    plant.close().await;
}

#[tokio::test(flavor = "multi_thread")]
async fn a_frozen_servers_robot_resumes_on_a_survivor_once_the_lease_expires() {
    let (mut plant, mut robot) = setup().await;
    let gap = freeze_a(&mut plant, &mut robot).await;
    eprintln!("SIGSTOP to the first segment from the survivor: {gap:?}");
    // The lease (1 s) bounds it from below: the router declares the frozen server gone only then.
    assert!(gap > Duration::from_millis(500) && gap < Duration::from_secs(5), "{gap:?}");
    robot.read_for(0.3).await;
    restart_a(&mut plant, &mut robot).await;
    robot.read_for(0.3).await;
    assert_continuous(&robot.setpoints);
    within("stop", robot.session.stop()).await.unwrap();
    plant.close().await;
}

/// A robot stopped just before its server dies is stopped on the survivor too: it comes to rest there and its
/// stream ends, never set moving towards the goal again (the resumed session sends the stop again).
#[tokio::test(flavor = "multi_thread")]
async fn a_robot_stopped_as_its_server_dies_comes_to_rest_on_the_survivor() {
    let (mut plant, mut robot) = setup().await;
    robot.read_for(0.5).await;
    within("stop", robot.session.stop()).await.unwrap();
    plant.servers[0].kill();
    within("the stream ends", async {
        while let Some(seg) = robot.session.next_segment().await {
            robot.setpoints.push(&seg.expect("no error")).unwrap();
        }
    })
    .await;
    assert_eq!(robot.session.resumes(), 1, "resumed once, on the survivor");
    let t = robot.setpoints.trajectory().unwrap();
    let n = t.t.len();
    let (x, v) = (&t.x[2 * (n - 1)..], &t.xd[2 * (n - 1)..]);
    assert!(v[0].hypot(v[1]) < 2e-3, "at rest: {v:?}");
    assert!(x[0] < 0.2, "stopped on the way, not taken to the goal (1, 0.5): {x:?}");
    assert_continuous(&robot.setpoints);
    plant.close().await;
}

/// The figure of BENCHMARKS.md: `cargo test -p dmp-server --test failover -- --ignored --nocapture`.
#[tokio::test(flavor = "multi_thread")]
#[ignore = "a measurement: run it with --ignored --nocapture"]
async fn measure_the_fail_over_gap() {
    // 28 resumptions in about 10 s: more than a session allows by default (20 a minute).
    let (mut plant, mut robot) = setup_with(ResumeOptions { max_resumes: 100, ..Default::default() }).await;
    let (mut gaps, mut backs, mut frozen, mut margins) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for _ in 0..9 {
        let (gap, margin, _) = kill_a(&mut plant, &mut robot).await;
        gaps.push(gap);
        margins.push(Duration::from_secs_f64(margin.max(0.0)));
        if margin < 0.0 {
            println!("the robot ran out of setpoints for {:.1} ms", -margin * 1e3);
        }
        robot.read_for(0.2).await;
        backs.push(restart_a(&mut plant, &mut robot).await);
    }
    for _ in 0..5 {
        frozen.push(freeze_a(&mut plant, &mut robot).await);
        robot.read_for(0.2).await;
        restart_a(&mut plant, &mut robot).await;
    }
    assert_continuous(&robot.setpoints);
    let summary = |v: &mut Vec<Duration>| {
        v.sort();
        format!("median {:?}, max {:?}, all {:?}", v[v.len() / 2], v[v.len() - 1], v)
    };
    println!("kill -9 to the first segment from the survivor: {}", summary(&mut gaps));
    println!("restart to the first segment from the server back: {}", summary(&mut backs));
    println!("SIGSTOP to the first segment from the survivor: {}", summary(&mut frozen));
    println!(
        "kill -9: setpoints the robot had left when the survivor's first segment came: {}",
        summary(&mut margins)
    );
    within("stop", robot.session.stop()).await.unwrap();
    plant.close().await;
}
