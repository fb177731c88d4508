//! `dmpctl load`: many robots streaming in real time against a running server, with obstacle updates over Zenoh;
//! one JSON object of what arrived on time, how late the rest was, how fast scene updates reached the robots, and
//! what the server used.
//!
//! | concept | file |
//! | --- | --- |
//! | the flags, their validation, the run | `mod.rs` |
//! | cells, paths that cross, fixed obstacles, the primitive | `layout.rs` |
//! | obstacles, primitives and session starts on the server | `setup.rs` |
//! | one robot's session and the accounting of its setpoints | `robot.rs` |
//! | the Zenoh obstacle updater and the update-to-segment latency | `scene.rs` |
//! | the server's CPU and memory over the run | `monitor.rs` |
//! | histograms and percentiles | `stats.rs` |
//! | the JSON report | `report.rs` |
//!
//! # The run
//! 1. Connect (`--connections` HTTP/2 connections; a cell's robots share one), open the Zenoh publisher and wait
//!    until the server's subscriber is matched (a put before that would be lost).
//! 2. Set up, at most [`setup::SETUP_CONCURRENCY`] calls at once: five fixed obstacles per cell (gRPC, in the cell) and a
//!    primitive per robot (primitives are stored per robot).
//! 3. Start the robots spread over the first [`MAX_STAGGER_S`] seconds (a quarter of the run if shorter): each opens
//!    a session (real-time pacing, its cell, its footprint), changes its goal every `tau` seconds, and sends a stop
//!    at the end of the measurement, `--duration` seconds after the first start.
//! 4. Meanwhile the scene updater moves one obstacle of one cell at a time at `--scene-updates` Hz, and the server
//!    is sampled once a second.
//!
//! Every wait is bounded; a failed setup or stream is counted and reported with its message, never a panic. Due
//! times are the server's wall clock (`start_unix_s`), arrivals this machine's: run both on one machine (or with
//! synchronised clocks).

#[cfg(test)]
mod accuracy;
pub mod layout;
pub mod monitor;
pub mod report;
pub mod robot;
pub mod scene;
pub mod setup;
pub mod stats;

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use tokio::task::JoinSet;
use tokio::time::Instant;

use self::report::{ErrorCount, LATENESS_DEFINITION, LoadReport};
use self::robot::{Ledger, RobotOutcome, RobotTask, STOP_TIMEOUT, Shared};
use self::scene::{CellProbe, Updates};
use self::stats::{Percentiles, SignedPercentiles};
use crate::error::ClientError;
use crate::grpc::DmpClient;
use crate::zenoh_pub::ObstaclePublisher;

/// The Zenoh endpoint of a server on this machine.
pub const DEFAULT_ZENOH: &str = "tcp/127.0.0.1:7447";
/// Worker threads of the generator by default.
pub const DEFAULT_THREADS: usize = 1;
/// Most connections by default (one per cell up to this, and at least one per 100 robots).
pub const MAX_DEFAULT_CONNECTIONS: usize = 16;
/// Robots per connection the default aims at most (HTTP/2 servers often allow 100 or 200 concurrent streams).
pub const STREAMS_PER_CONNECTION: usize = 100;
/// The robots' starts are spread over this long at most.
pub const MAX_STAGGER_S: f64 = 1.0;
/// Longest wait for the server's Zenoh subscriber.
pub const ZENOH_MATCH_TIMEOUT: Duration = Duration::from_secs(10);
/// Between the setup and the first start.
const LEAD_IN: Duration = Duration::from_millis(300);
/// A stream's `max_duration_s` is the measurement plus this, a bound should the stop get lost.
pub(crate) const MAX_DURATION_SLACK_S: f64 = 10.0;

const DEFAULT_ROBOTS: usize = 100;
const DEFAULT_RATE: f64 = 1000.0;
const DEFAULT_SEGMENT_MS: f64 = 10.0;
const DEFAULT_DURATION: f64 = 10.0;
const DEFAULT_CELL_SIZE: usize = 10;
const DEFAULT_DIM: usize = 3;
const DEFAULT_TAU: f64 = 2.0;
const DEFAULT_PREFIX: &str = "load";
/// The server's internal RK4 step the load asks for by default, milliseconds: the largest step at which a load
/// robot stays within 1e-3 of the engine's RK4 at 1 ms (`accuracy.rs`: 5e-4 at 5 ms, 3.5e-3 at 10 ms).
pub const DEFAULT_INTEGRATION_STEP_MS: f64 = 5.0;

/// `dmpctl load`: the server is `--server` (default http://127.0.0.1:50051), its Zenoh endpoint `--zenoh-connect`
/// (default tcp/127.0.0.1:7447).
#[derive(Debug, Clone, PartialEq, clap::Args)]
pub struct LoadArgs {
    /// Robots streaming at once.
    #[arg(long, default_value_t = DEFAULT_ROBOTS, value_name = "N")]
    pub robots: usize,
    /// Setpoints per second per robot (dt = 1 / rate).
    #[arg(long, default_value_t = DEFAULT_RATE, value_name = "HZ", allow_hyphen_values = true)]
    pub rate: f64,
    /// Segment length, milliseconds (a whole number of setpoints).
    #[arg(long = "segment-ms", default_value_t = DEFAULT_SEGMENT_MS, value_name = "MS", allow_hyphen_values = true)]
    pub segment_ms: f64,
    /// Length of the measurement, seconds, from the first robot's start to the stops.
    #[arg(long, default_value_t = DEFAULT_DURATION, value_name = "S", allow_hyphen_values = true)]
    pub duration: f64,
    /// Obstacle updates per second over Zenoh, round-robin over the cells (0: none).
    #[arg(long = "scene-updates", default_value_t = 0.0, value_name = "HZ", allow_hyphen_values = true)]
    pub scene_updates: f64,
    /// Robots per cell (each avoids its cell-mates and its cell's five fixed obstacles).
    #[arg(long = "cell-size", default_value_t = DEFAULT_CELL_SIZE, value_name = "N")]
    pub cell_size: usize,
    /// Dimension of the motions: 2 or 3.
    #[arg(long, default_value_t = DEFAULT_DIM)]
    pub dim: usize,
    /// The primitives' time scale, seconds; each robot changes its goal every tau.
    #[arg(long, default_value_t = DEFAULT_TAU, value_name = "S", allow_hyphen_values = true)]
    pub tau: f64,
    /// The server's internal RK4 step, milliseconds, with the output points interpolated exactly (quintic
    /// Hermite) in between: 5 ms keeps a load robot within 1e-3 of RK4 at 1 ms (`load/accuracy.rs`); 0 asks
    /// for the server's default (1 ms).
    #[arg(
        long = "integration-step-ms",
        default_value_t = DEFAULT_INTEGRATION_STEP_MS,
        value_name = "MS",
        allow_hyphen_values = true
    )]
    pub integration_step_ms: f64,
    /// HTTP/2 connections [default: one per cell, at most 16, and at least one per 100 robots].
    #[arg(long, value_name = "N")]
    pub connections: Option<usize>,
    /// Worker threads of the generator's runtime. One keeps up with 1,000 robots at 1 kHz in a third of a core
    /// and leaves the rest of a small machine to the server under test; more spread it over more cores.
    #[arg(long, default_value_t = DEFAULT_THREADS, value_name = "N")]
    pub threads: usize,
    /// Prefix of the cells (`<prefix>-<c>`) and robots (`<prefix>-<c>-<k>`).
    #[arg(long, default_value = DEFAULT_PREFIX)]
    pub prefix: String,
    /// Also write the JSON report to this file.
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
}

impl Default for LoadArgs {
    fn default() -> Self {
        Self {
            robots: DEFAULT_ROBOTS,
            rate: DEFAULT_RATE,
            segment_ms: DEFAULT_SEGMENT_MS,
            duration: DEFAULT_DURATION,
            scene_updates: 0.0,
            cell_size: DEFAULT_CELL_SIZE,
            dim: DEFAULT_DIM,
            tau: DEFAULT_TAU,
            integration_step_ms: DEFAULT_INTEGRATION_STEP_MS,
            connections: None,
            threads: DEFAULT_THREADS,
            prefix: DEFAULT_PREFIX.into(),
            out: None,
        }
    }
}

/// Validated flags and what follows from them.
#[derive(Debug, Clone, PartialEq)]
pub struct Params {
    /// The flags.
    pub args: LoadArgs,
    /// Cells.
    pub cells: usize,
    /// Connections.
    pub connections: usize,
    /// Setpoint step, seconds.
    pub dt: f64,
    /// Seconds the starts are spread over.
    pub stagger_s: f64,
}

fn bad(flag: &str, message: impl Into<String>) -> ClientError {
    ClientError::argument(flag, message)
}

fn in_range(flag: &str, x: f64, lo: f64, hi: f64, unit: &str) -> Result<(), ClientError> {
    if x.is_finite() && x >= lo && x <= hi {
        Ok(())
    } else {
        Err(bad(flag, format!("{x} is not between {lo} and {hi}{unit}")))
    }
}

impl LoadArgs {
    /// Checks every flag (the error names it) and derives the run's parameters.
    pub fn validate(&self) -> Result<Params, ClientError> {
        if !(self.integration_step_ms.is_finite() && (0.0..=100.0).contains(&self.integration_step_ms)) {
            return Err(bad(
                "--integration-step-ms",
                format!("{} is not between 0 and 100", self.integration_step_ms),
            ));
        }
        if !(1..=100_000).contains(&self.robots) {
            return Err(bad("--robots", format!("{} is not between 1 and 100000", self.robots)));
        }
        in_range("--rate", self.rate, 10.0, 10_000.0, " Hz")?;
        let dt = 1.0 / self.rate;
        in_range("--segment-ms", self.segment_ms, 0.0, 10_000.0, " ms")?;
        let points = self.segment_ms * 1e-3 / dt;
        if points.round() < 1.0 || (points - points.round()).abs() > 1e-6 {
            return Err(bad(
                "--segment-ms",
                format!(
                    "{} ms is not a whole number (at least one) of setpoints of {} ms (--rate {})",
                    self.segment_ms,
                    dt * 1e3,
                    self.rate
                ),
            ));
        }
        in_range("--duration", self.duration, 0.1, 86_400.0, " s")?;
        let steps = (self.duration + MAX_DURATION_SLACK_S) * self.rate;
        if steps > dmp::rollout::MAX_ROLLOUT_STEPS as f64 {
            return Err(bad(
                "--duration",
                format!(
                    "{} s at {} Hz (plus {MAX_DURATION_SLACK_S} s for the stop) exceeds the server's limit of {} steps \
                     per stream",
                    self.duration,
                    self.rate,
                    dmp::rollout::MAX_ROLLOUT_STEPS
                ),
            ));
        }
        in_range("--scene-updates", self.scene_updates, 0.0, 1_000.0, " Hz")?;
        if !(1..=1_000).contains(&self.cell_size) {
            return Err(bad("--cell-size", format!("{} is not between 1 and 1000", self.cell_size)));
        }
        if !matches!(self.dim, 2 | 3) {
            return Err(bad("--dim", format!("{} is neither 2 nor 3", self.dim)));
        }
        in_range("--tau", self.tau, 0.1, 3_600.0, " s")?;
        if let Some(c) = self.connections
            && !(1..=1_024).contains(&c)
        {
            return Err(bad("--connections", format!("{c} is not between 1 and 1024")));
        }
        if !(1..=256).contains(&self.threads) {
            return Err(bad("--threads", format!("{} is not between 1 and 256", self.threads)));
        }
        let p = &self.prefix;
        if p.is_empty()
            || p.len() > 64
            || !p.chars().all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '.' | '-'))
        {
            return Err(bad("--prefix", format!("`{p}` is not 1 to 64 characters of [A-Za-z0-9_.-]")));
        }
        let cells = layout::cell_count(self.robots, self.cell_size);
        let connections = self.connections.unwrap_or_else(|| {
            cells.min(MAX_DEFAULT_CONNECTIONS).max(self.robots.div_ceil(STREAMS_PER_CONNECTION))
        });
        let stagger_s = (self.duration / 4.0).min(MAX_STAGGER_S);
        Ok(Params { args: self.clone(), cells, connections, dt, stagger_s })
    }
}

/// Messages of what went wrong, counted (shared by every task; rare, so a mutex).
#[derive(Debug, Default)]
pub struct Errors {
    counts: Mutex<BTreeMap<String, (u64, Option<String>)>>,
}

impl Errors {
    /// Counts `message`.
    pub fn add(&self, message: String) {
        self.add_for(message, None);
    }

    /// Counts `message`, which happened to `robot`.
    pub fn add_for(&self, message: String, robot: Option<&str>) {
        let mut m = self.counts.lock().unwrap_or_else(|e| e.into_inner());
        let e = m.entry(message).or_insert((0, robot.map(str::to_string)));
        e.0 += 1;
    }

    /// Most frequent first.
    pub fn sorted(&self) -> Vec<ErrorCount> {
        let m = self.counts.lock().unwrap_or_else(|e| e.into_inner());
        let mut v: Vec<ErrorCount> = m
            .iter()
            .map(|(message, (count, robot))| ErrorCount {
                message: message.clone(),
                count: *count,
                robot: robot.clone(),
            })
            .collect();
        v.sort_by(|a, b| b.count.cmp(&a.count).then_with(|| a.message.cmp(&b.message)));
        v
    }
}

/// Wall clock, Unix seconds.
pub fn unix_now() -> f64 {
    std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0.0, |d| d.as_secs_f64())
}

/// Wall clock, Unix nanoseconds.
pub fn unix_now_ns() -> u64 {
    std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_nanos() as u64)
}

/// Runs the load against the server at `server` (gRPC) and `zenoh_connect` (its Zenoh endpoints; empty:
/// [`DEFAULT_ZENOH`]). Fails on bad flags, when the server cannot be reached, or when nothing could be set up;
/// failed streams are in the report.
pub async fn run(args: &LoadArgs, server: &str, zenoh_connect: &[String]) -> Result<LoadReport, ClientError> {
    let p = args.validate()?;
    let a = &p.args;
    let setup_started = Instant::now();
    let mut clients = Vec::with_capacity(p.connections);
    for _ in 0..p.connections {
        clients.push(DmpClient::connect(server).await?);
    }
    let cells: Vec<String> = (0..p.cells).map(|c| layout::cell_name(&a.prefix, c)).collect();
    let robots = layout::robots(a.robots, a.cell_size, a.dim, &a.prefix);
    eprintln!(
        "dmpctl load: {} robots in {} cells over {} connections, {} Hz, {} ms segments, {} s",
        a.robots, p.cells, p.connections, a.rate, a.segment_ms, a.duration
    );
    let publisher = if a.scene_updates > 0.0 {
        let default = [DEFAULT_ZENOH.to_string()];
        let connect = if zenoh_connect.is_empty() { &default[..] } else { zenoh_connect };
        let publisher = ObstaclePublisher::open(&cells[0], connect, &[]).await?;
        publisher.wait_for_subscriber(ZENOH_MATCH_TIMEOUT).await?;
        Some(publisher)
    } else {
        None
    };
    let setup_failed = setup::set_up(&p, &clients, &cells, &robots).await?;
    let setup_s = setup_started.elapsed().as_secs_f64();

    // The schedule, on both clocks.
    let begin = Instant::now() + LEAD_IN;
    let unix_of = {
        let (i0, u0) = (Instant::now(), unix_now());
        move |i: Instant| u0 + i.saturating_duration_since(i0).as_secs_f64()
    };
    let end = begin + Duration::from_secs_f64(a.duration);
    let end_unix = unix_of(end);
    let errors = Arc::new(Errors::default());
    let shared = Arc::new(Shared::default());
    let probes: Vec<Arc<CellProbe>> = (0..p.cells).map(|_| Arc::new(CellProbe::default())).collect();

    let mut tasks = JoinSet::new();
    let mut outcomes: Vec<RobotOutcome> = Vec::with_capacity(robots.len());
    for (i, (r, failed)) in robots.iter().zip(setup_failed).enumerate() {
        let start_at = begin + Duration::from_secs_f64(p.stagger_s * i as f64 / robots.len() as f64);
        let task = RobotTask {
            plan: r.clone(),
            start: setup::start_request(&p, r, &cells[r.cell]),
            start_at,
            end_at: end,
            start_unix: unix_of(start_at),
            end_unix,
            rate: a.rate,
            retarget_every: Duration::from_secs_f64(a.tau),
        };
        if let Some(e) = failed {
            // Its setpoints are expected all the same, and none is on time.
            let (expected, on_time) = Ledger::new(end_unix).finish(task.start_unix, a.rate);
            errors.add_for(e.clone(), Some(&r.id));
            outcomes.push(RobotOutcome {
                id: r.id.clone(),
                expected,
                on_time,
                error: Some(e),
                ..Default::default()
            });
            continue;
        }
        let client = clients[r.cell % clients.len()].clone();
        let (probe, shared) = (probes[r.cell].clone(), shared.clone());
        tasks.spawn(robot::run_robot(client, task, probe, shared));
    }

    let monitor = {
        let (client, errors) = (clients[0].clone(), errors.clone());
        tokio::spawn(async move { monitor::watch(&client, begin, end, &errors).await })
    };
    let updater = publisher.map(|publisher| {
        let (errors, probes) = (errors.clone(), probes.clone());
        let listing: Vec<DmpClient> = cells
            .iter()
            .enumerate()
            .map(|(c, cell)| clients[c % clients.len()].clone().with_cell(cell.clone()))
            .collect();
        let updates = Updates {
            hz: a.scene_updates,
            cells: cells.clone(),
            dim: a.dim,
            // Once every robot streams, until shortly before the stops.
            begin: begin + Duration::from_secs_f64(p.stagger_s + 0.2),
            end: end - Duration::from_millis(250),
        };
        tokio::spawn(async move {
            let settle = end.saturating_duration_since(updates.end);
            let out = scene::run_updater(&publisher, &listing, &probes, &errors, &updates, settle).await;
            if let Err(e) = publisher.close().await {
                errors.add(format!("closing the Zenoh publisher: {e}"));
            }
            out
        })
    });

    let deadline = end + STOP_TIMEOUT + robot::STALL_TIMEOUT + Duration::from_secs(5);
    loop {
        match tokio::time::timeout_at(deadline, tasks.join_next()).await {
            Ok(Some(Ok(o))) => {
                if let Some(e) = &o.error {
                    errors.add_for(e.clone(), Some(&o.id));
                }
                outcomes.push(o);
            }
            Ok(Some(Err(e))) => errors.add(format!("a robot task failed: {e}")),
            Ok(None) => break,
            Err(_) => {
                errors.add(format!("{} robots still running past the deadline: aborted", tasks.len()));
                tasks.abort_all();
                break;
            }
        }
    }
    let watched = monitor.await.unwrap_or_default();
    let updated = match updater {
        Some(u) => u.await.unwrap_or_default(),
        None => Default::default(),
    };

    let sum = |f: fn(&RobotOutcome) -> u64| outcomes.iter().map(f).sum::<u64>();
    let expected = sum(|o| o.expected);
    let on_time = sum(|o| o.on_time);
    let rss = watched.rss_mib();
    let report = LoadReport {
        robots: a.robots,
        cells: p.cells,
        cell_size: a.cell_size,
        rate_hz: a.rate,
        segment_ms: a.segment_ms,
        duration_s: a.duration,
        scene_updates_hz: a.scene_updates,
        dim: a.dim,
        tau_s: a.tau,
        connections: p.connections,
        stagger_s: p.stagger_s,
        setup_s: (setup_s * 1e3).round() / 1e3,
        streams_started: sum(|o| o.started as u64),
        streams_failed: outcomes.iter().filter(|o| o.error.is_some()).count() as u64
            + (a.robots - outcomes.len().min(a.robots)) as u64,
        setpoints_expected: expected,
        setpoints_on_time: on_time,
        setpoints_on_time_percent: if expected > 0 {
            (1e4 * on_time as f64 / expected as f64).floor() / 1e2
        } else {
            0.0
        },
        segments: sum(|o| o.segments),
        late_segments: sum(|o| o.late_segments),
        late_first_segments: sum(|o| o.late_first_segment as u64),
        superseding_segments: sum(|o| o.superseding_segments),
        stalled_segments: sum(|o| o.stalled_segments),
        collision_segments: sum(|o| o.collision_segments),
        retargets: sum(|o| o.retargets),
        lateness_definition: LATENESS_DEFINITION,
        lateness_ms: Percentiles::clamped(&shared.lateness),
        superseding_lateness_ms: Percentiles::clamped(&shared.superseding_lateness),
        arrival_minus_due_ms: SignedPercentiles::of(&shared.lateness),
        scene_updates_sent: updated.sent,
        scene_updates_unanswered: updated.unanswered,
        scene_update_latency_ms: Percentiles::of(&shared.scene_latency),
        server_cpu_percent: watched.cpu_percent(),
        server_rss_mib: watched.end.as_ref().map(|s| monitor::mib(s.rss_bytes)),
        server_rss_mib_start: watched.begin.as_ref().map(|s| monitor::mib(s.rss_bytes)),
        server_rss_mib_max: rss.iter().copied().reduce(f64::max),
        server_rss_mib_series: rss,
        server_open_streams_max: watched.samples.iter().map(|s| s.open_streams).max(),
        server_segments_sent: watched
            .begin
            .as_ref()
            .zip(watched.end.as_ref())
            .map(|(b, e)| e.segments_sent.saturating_sub(b.segments_sent)),
        generator_cpu_percent: watched.own_cpu_percent(),
        errors: errors.sorted(),
    };
    if let Some(path) = &a.out {
        let json = serde_json::to_string_pretty(&report).unwrap_or_default();
        std::fs::write(path, json + "\n").map_err(|source| ClientError::Io { path: path.clone(), source })?;
    }
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(f: impl FnOnce(&mut LoadArgs)) -> Result<Params, String> {
        let mut a = LoadArgs::default();
        f(&mut a);
        a.validate().map_err(|e| e.to_string())
    }

    #[test]
    fn flags_are_validated_with_their_name() {
        let p = check(|_| {}).unwrap();
        assert_eq!((p.cells, p.connections, p.dt, p.stagger_s), (10, 10, 0.001, 1.0));
        let p = check(|a| a.robots = 1000).unwrap();
        assert_eq!((p.cells, p.connections), (100, 16));
        let p = check(|a| (a.robots, a.cell_size, a.duration) = (5000, 1000, 2.0)).unwrap();
        assert_eq!((p.cells, p.connections, p.stagger_s), (5, 50, 0.5));
        type Edit = fn(&mut LoadArgs);
        let cases: [(&str, Edit); 13] = [
            ("--robots", |a| a.robots = 0),
            ("--rate", |a| a.rate = f64::NAN),
            ("--rate", |a| a.rate = -5.0),
            ("--segment-ms", |a| a.segment_ms = 0.5),
            ("--segment-ms", |a| a.segment_ms = 10.5),
            ("--duration", |a| a.duration = 0.0),
            ("--duration", |a| a.duration = 2000.0),
            ("--scene-updates", |a| a.scene_updates = -1.0),
            ("--cell-size", |a| a.cell_size = 0),
            ("--dim", |a| a.dim = 4),
            ("--tau", |a| a.tau = 0.0),
            ("--prefix", |a| a.prefix = "a/b".into()),
            ("--threads", |a| a.threads = 0),
        ];
        for (flag, f) in cases {
            let e = check(f).unwrap_err();
            assert!(e.starts_with(flag), "{flag}: {e}");
        }
        assert!(check(|a| a.connections = Some(0)).unwrap_err().starts_with("--connections"));
        // 2 ms segments at 500 Hz are one setpoint each.
        assert!(check(|a| (a.rate, a.segment_ms) = (500.0, 2.0)).is_ok());
    }

    #[tokio::test(flavor = "multi_thread")]
    async fn bad_flags_fail_before_connecting_and_a_missing_server_fails_fast() {
        let bad = LoadArgs { dim: 7, ..Default::default() };
        let e = run(&bad, "http://127.0.0.1:1", &[]).await.unwrap_err();
        assert!(e.is_bad_input() && e.to_string().starts_with("--dim"), "{e}");
        let e = run(&LoadArgs::default(), "http://127.0.0.1:1", &[]).await.unwrap_err();
        assert!(matches!(e, ClientError::Connect { .. }), "{e}");
    }

    #[test]
    fn errors_are_counted_most_frequent_first() {
        let e = Errors::default();
        e.add_for("b".into(), Some("r1"));
        e.add_for("b".into(), Some("r2"));
        e.add("a".into());
        let s = e.sorted();
        assert_eq!(s.len(), 2);
        assert_eq!((s[0].message.as_str(), s[0].count, s[0].robot.as_deref()), ("b", 2, Some("r1")));
        assert_eq!((s[1].message.as_str(), s[1].count, s[1].robot.as_deref()), ("a", 1, None));
    }
}
