//! `dmpctl load`: many robots streaming in real time against a running server, with obstacle updates over Zenoh;
//! one JSON object of what arrived on time, how late the rest was, how fast scene updates reached the robots, and
//! what the server used.
//!
//! | concept | file |
//! | --- | --- |
//! | the run | `mod.rs` |
//! | the flags and their validation | `args.rs` |
//! | the servers: `--server`, or each cell's found through Zenoh (`--via-zenoh-discovery`) | `servers.rs` |
//! | cells, paths that cross, fixed obstacles, the primitive | `layout.rs` |
//! | pose robots at the Panda profile (`--pose`) | `pose.rs` |
//! | obstacles, primitives and session starts on the server | `setup.rs` |
//! | one robot's session and the accounting of its setpoints | `robot.rs` |
//! | a segment as the robots read it (setpoint arrays undecoded) | `dmp_proto::segment_view` |
//! | the Zenoh obstacle updater and the update-to-segment latency | `scene.rs` |
//! | the server's CPU and memory over the run | `monitor.rs` |
//! | histograms and percentiles | `stats.rs` |
//! | the JSON report | `report.rs` |
//!
//! # The run
//! 1. Connect (`--connections` HTTP/2 connections; a cell's robots share one), open the Zenoh publisher and wait
//!    until the server's subscriber is matched (a put before that would be lost).
//! 2. Set up, at most `setup::SETUP_CONCURRENCY` calls at once: five fixed obstacles per cell (gRPC, in the cell) and a
//!    primitive per robot (primitives are stored per robot).
//! 3. Start the robots spread over the first `MAX_STAGGER_S` seconds (a quarter of the run if shorter): each opens
//!    a session (real-time pacing, its cell, its footprint), changes its goal every `tau` seconds, and sends a stop
//!    at the end of the measurement, `--duration` seconds after the first start.
//! 4. Meanwhile the scene updater moves one obstacle of one cell at a time at `--scene-updates` Hz, and the server
//!    is sampled once a second.
//!
//! Every wait is bounded; a failed setup or stream is counted and reported with its message, never a panic. Due
//! times are the server's wall clock (`start_unix_s`), arrivals this machine's: run both on one machine (or with
//! synchronised clocks).

mod args;
pub mod layout;
mod monitor;
mod per_second;
mod pose;
pub mod report;
mod robot;
mod scene;
mod servers;
pub mod setup;
mod stats;

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use dmp_client::connect::ConnectOptions;
use dmp_client::grpc::DmpClient;
use dmp_client::zenoh_pub::ObstaclePublisher;
use tokio::task::JoinSet;
use tokio::time::Instant;

pub use self::args::{DEFAULT_INTEGRATION_STEP_S, DEFAULT_INTEGRATION_TOLERANCE, LoadArgs, Params};
use self::report::{ErrorCount, LATENESS_DEFINITION, LoadReport, ServerPart, percent};
use self::robot::{Ledger, RobotOutcome, RobotTask, STOP_TIMEOUT, Shared};
use self::scene::{CellProbe, Updates};
use self::stats::SignedHistogram;
use self::stats::{Percentiles, SignedPercentiles};
use crate::error::SimError;

/// The Zenoh endpoint of a server on this machine.
pub(crate) const DEFAULT_ZENOH: &str = "tcp/127.0.0.1:7447";
/// The robots' starts are spread over this long at most.
pub(crate) const MAX_STAGGER_S: f64 = 1.0;
/// Longest wait for the server's Zenoh subscriber.
pub(crate) const ZENOH_MATCH_TIMEOUT: Duration = Duration::from_secs(10);
/// Between the setup and the first start.
const LEAD_IN: Duration = Duration::from_millis(300);
/// A stream's `max_duration_s` is the measurement plus this, a bound should the stop get lost.
pub(crate) const MAX_DURATION_SLACK_S: f64 = 10.0;

/// Messages of what went wrong, counted (shared by every task; rare, so a mutex).
#[derive(Debug, Default)]
pub(crate) struct Errors {
    counts: Mutex<BTreeMap<String, (u64, Option<String>)>>,
}

impl Errors {
    /// Counts `message`.
    pub(crate) fn add(&self, message: String) {
        self.add_for(message, None);
    }

    /// Counts `message`, which happened to `robot`.
    pub(crate) fn add_for(&self, message: String, robot: Option<&str>) {
        let mut m = self.counts.lock().unwrap_or_else(|e| e.into_inner());
        let e = m.entry(message).or_insert((0, robot.map(str::to_string)));
        e.0 += 1;
    }

    /// Most frequent first.
    pub(crate) fn sorted(&self) -> Vec<ErrorCount> {
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

/// Each robot's token, read from `DIR/<robot-id>.token`.
fn robot_tokens(dir: &std::path::Path, robots: &[layout::RobotPlan]) -> Result<Vec<String>, SimError> {
    robots
        .iter()
        .map(|r| {
            let path = dir.join(format!("{}.token", r.id));
            std::fs::read_to_string(&path)
                .map(|t| t.trim().to_owned())
                .map_err(|e| SimError::argument("--tokens", format!("{}: {e}", path.display())))
        })
        .collect()
}

/// Wall clock, Unix seconds.
pub(crate) fn unix_now() -> f64 {
    std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0.0, |d| d.as_secs_f64())
}

/// Wall clock, Unix nanoseconds.
pub(crate) fn unix_now_ns() -> u64 {
    std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_nanos() as u64)
}

/// Runs the load against the server at `server` (gRPC) and `zenoh_connect` (its Zenoh endpoints; empty:
/// `DEFAULT_ZENOH`). Fails on bad flags, when the server cannot be reached, or when nothing could be set up;
/// failed streams are in the report.
pub async fn run(args: &LoadArgs, server: &str, zenoh_connect: &[String]) -> Result<LoadReport, SimError> {
    run_with(args, server, zenoh_connect, &ConnectOptions::default()).await
}

/// [`run`] with TLS and credentials (`options`); with `--tokens`, each robot streams as its own identity. Unless
/// `--keep`, the robots' primitives and the cells' fixed obstacles are deleted at the end ([`clean_up`]), also
/// when the run failed.
pub async fn run_with(
    args: &LoadArgs,
    server: &str,
    zenoh_connect: &[String],
    options: &ConnectOptions,
) -> Result<LoadReport, SimError> {
    let p = args.validate()?;
    let measured = measure(&p, server, zenoh_connect, options).await;
    let cleaned = if args.keep { Ok(()) } else { clean_up(args, server, zenoh_connect, options).await };
    // The run's own error first: a clean-up that failed after it says less.
    let mut report = measured?;
    if let Err(e) = cleaned {
        report.errors.push(ErrorCount { message: format!("clean-up: {e}"), count: 1, robot: None });
    }
    if let Some(dir) = &args.out {
        let json = serde_json::to_string_pretty(&report).unwrap_or_default();
        std::fs::create_dir_all(dir).map_err(|source| SimError::Io { path: dir.clone(), source })?;
        let path = dir.join("load.json");
        std::fs::write(&path, json + "\n").map_err(|source| SimError::Io { path, source })?;
    }
    Ok(report)
}

/// Deletes what the load with `args` stored on its servers (`server`, or each cell's found through Zenoh at
/// `zenoh_connect`): each robot's primitive and each cell's fixed obstacles, on the cell's server (the robots are
/// the load's own, `layout::robot_id`).
pub async fn clean_up(
    args: &LoadArgs,
    server: &str,
    zenoh_connect: &[String],
    options: &ConnectOptions,
) -> Result<(), SimError> {
    let p = args.validate()?;
    let cells = p.cell_names();
    let servers = servers::find(&cells, server, args.via_zenoh_discovery, zenoh_connect).await?;
    let robots = layout::robots(args.robots, args.cell_size, args.dim, &args.prefix);
    let mut first_error = Ok(());
    for (ti, t) in servers.targets.iter().enumerate() {
        let client = DmpClient::connect_with(&t.url, options).await?;
        let mine: Vec<String> = t.cells.iter().map(|&c| cells[c].clone()).collect();
        let robots: Vec<layout::RobotPlan> =
            robots.iter().filter(|r| servers.of_cell[r.cell] == ti).cloned().collect();
        let done = setup::clean_up(&client, &mine, &robots).await;
        if first_error.is_ok() {
            first_error = done;
        }
    }
    first_error
}

/// The run itself, its report not yet written.
async fn measure(
    p: &args::Params,
    server: &str,
    zenoh_connect: &[String],
    options: &ConnectOptions,
) -> Result<LoadReport, SimError> {
    let a = &p.args;
    let setup_started = Instant::now();
    let cells = p.cell_names();
    let servers = servers::find(&cells, server, a.via_zenoh_discovery, zenoh_connect).await?;
    // One client per cell (`clients[c]`), sharing the connections of its server.
    let clients = servers.connect(p.connections, options).await?;
    let robots = layout::robots(a.robots, a.cell_size, a.dim, &a.prefix);
    let tokens = match &a.tokens {
        Some(dir) => Some(robot_tokens(dir, &robots)?),
        None => None,
    };
    eprintln!(
        "dmpctl load: {} robots in {} cells over {} connections to {} server(s), {} Hz, {} s segments, {} s",
        a.robots,
        p.cells,
        servers.connections(p.connections).iter().sum::<usize>(),
        servers.targets.len(),
        a.rate,
        p.args.segment_s,
        a.duration
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
    let setup_failed = setup::set_up(p, &clients, &cells, &robots).await?;
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
    let seconds = (p.stagger_s + a.duration).ceil() as usize + 1;
    let shared = Arc::new(Shared::new(unix_of(begin), seconds));
    let probes: Vec<Arc<CellProbe>> = (0..p.cells).map(|_| Arc::new(CellProbe::default())).collect();
    let lateness_of: Vec<Arc<SignedHistogram>> =
        servers.targets.iter().map(|_| Arc::new(SignedHistogram::new())).collect();

    let mut tasks = JoinSet::new();
    let mut outcomes: Vec<RobotOutcome> = Vec::with_capacity(robots.len());
    for (i, (r, failed)) in robots.iter().zip(setup_failed).enumerate() {
        let start_at = begin + Duration::from_secs_f64(p.stagger_s * i as f64 / robots.len() as f64);
        let task = RobotTask {
            plan: r.clone(),
            start: setup::start_request(p, r, &cells[r.cell]),
            start_at,
            end_at: end,
            start_unix: unix_of(start_at),
            end_unix,
            rate: a.rate,
            retarget_every: Duration::from_secs_f64(a.tau),
            server_lateness: lateness_of[servers.of_cell[r.cell]].clone(),
            orientations: a.pose.then(|| pose::orientations(r)),
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
        let shared_client = &clients[r.cell % clients.len()];
        let client = match &tokens {
            Some(t) => shared_client.with_token(Some(&t[i]))?,
            None => shared_client.clone(),
        };
        let (probe, shared) = (probes[r.cell].clone(), shared.clone());
        tasks.spawn(robot::run_robot(client, task, probe, shared));
    }

    // Each server sampled on its first cell's connection.
    let monitors: Vec<_> = servers
        .targets
        .iter()
        .map(|t| {
            let (client, errors) = (clients[t.cells[0]].clone(), errors.clone());
            tokio::spawn(async move { monitor::watch(&client, begin, end, &errors).await })
        })
        .collect();
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
    let mut each_watched = Vec::with_capacity(monitors.len());
    for m in monitors {
        each_watched.push(m.await.unwrap_or_default());
    }
    let watched = each_watched[0].clone();
    // Each robot's outcome by its server.
    let server_of_robot: BTreeMap<&str, usize> =
        robots.iter().map(|r| (r.id.as_str(), servers.of_cell[r.cell])).collect();
    let parts: Vec<ServerPart> = servers
        .targets
        .iter()
        .enumerate()
        .map(|(t, target)| {
            let mine = || outcomes.iter().filter(|o| server_of_robot.get(o.id.as_str()) == Some(&t));
            let (expected, on_time) = mine().fold((0, 0), |(e, o), r| (e + r.expected, o + r.on_time));
            let w = &each_watched[t];
            ServerPart {
                server_id: target.server_id.clone(),
                grpc_address: target.url.clone(),
                cells: target.cells.iter().map(|&c| cells[c].clone()).collect(),
                robots: robots.iter().filter(|r| servers.of_cell[r.cell] == t).count(),
                setpoints_expected: expected,
                setpoints_on_time: on_time,
                setpoints_on_time_percent: percent(on_time, expected),
                lateness_ms: Percentiles::clamped(&lateness_of[t]),
                cpu_percent: w.cpu_percent(),
                rss_mib_max: w.rss_mib().into_iter().reduce(f64::max),
                segments_sent: w
                    .begin
                    .as_ref()
                    .zip(w.end.as_ref())
                    .map(|(b, e)| e.segments_sent.saturating_sub(b.segments_sent)),
            }
        })
        .collect();
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
        segment_ms: p.args.segment_s * 1e3,
        duration_s: a.duration,
        scene_updates_hz: a.scene_updates,
        dim: a.dim,
        pose: a.pose,
        tau_s: a.tau,
        connections: servers.connections(p.connections).iter().sum(),
        stagger_s: p.stagger_s,
        setup_s: (setup_s * 1e3).round() / 1e3,
        streams_started: sum(|o| o.started as u64),
        streams_failed: outcomes.iter().filter(|o| o.error.is_some()).count() as u64
            + (a.robots - outcomes.len().min(a.robots)) as u64,
        setpoints_expected: expected,
        setpoints_on_time: on_time,
        setpoints_on_time_percent: percent(on_time, expected),
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
        late_segments_per_second: shared.late_per_second.counts(),
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
        servers: parts,
        errors: errors.sorted(),
    };
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test(flavor = "multi_thread")]
    async fn bad_flags_fail_before_connecting_and_a_missing_server_fails_fast() {
        let bad = LoadArgs { dim: 7, ..Default::default() };
        let e = run(&bad, "http://127.0.0.1:1", &[]).await.unwrap_err();
        assert!(e.is_bad_input() && e.to_string().starts_with("--dim"), "{e}");
        let e = run(&LoadArgs::default(), "http://127.0.0.1:1", &[]).await.unwrap_err();
        assert!(matches!(e, SimError::Client(dmp_client::ClientError::Connect { .. })), "{e}");
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
