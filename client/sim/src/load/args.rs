//! `dmpctl load`'s flags, their validation (the error names the flag) and what follows from them.

use std::path::PathBuf;

use super::{MAX_DURATION_SLACK_S, MAX_STAGGER_S, layout};
use crate::error::SimError;

const DEFAULT_ROBOTS: usize = 100;
const DEFAULT_RATE: f64 = 1000.0;
const DEFAULT_SEGMENT_S: f64 = 0.01;
const DEFAULT_DURATION: f64 = 10.0;
const DEFAULT_CELL_SIZE: usize = 10;
const DEFAULT_DIM: usize = 3;
const DEFAULT_TAU: f64 = 2.0;
const DEFAULT_PREFIX: &str = "load";
/// Worker threads of the generator by default.
pub(crate) const DEFAULT_THREADS: usize = 1;
/// Most connections by default (one per cell up to this, and at least one per 125 robots): fewer connections kept
/// more setpoints on time at 1,000 robots (BENCHMARKS.md).
pub(crate) const MAX_DEFAULT_CONNECTIONS: usize = 8;
/// Robots per connection the default aims at most (HTTP/2 servers often allow 100 to 250 concurrent streams).
pub(crate) const STREAMS_PER_CONNECTION: usize = 125;
/// The largest internal step the load asks the server for by default, milliseconds (its adaptive step; a fixed
/// RK4 step is at most one segment).
pub const DEFAULT_INTEGRATION_STEP_S: f64 = 0.03;
/// The local error tolerance of the server's adaptive step the load asks for by default: a load robot stays within
/// 1e-3 of the engine's RK4 at 1 ms with it, for fewer evaluations of the field than a fixed 5 ms RK4 step
/// (the server's `runs/accuracy_tests.rs` checks both; the deviations measured are in BENCHMARKS.md).
pub const DEFAULT_INTEGRATION_TOLERANCE: f64 = 3e-6;

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
    /// Segment length, seconds (a whole number of setpoints).
    #[arg(long = "segment-s", default_value_t = DEFAULT_SEGMENT_S, value_name = "S", allow_hyphen_values = true)]
    pub segment_s: f64,
    /// The segment length in milliseconds: the old spelling of `--segment-s`, kept hidden.
    #[arg(
        long = "segment-ms",
        hide = true,
        value_name = "MS",
        allow_hyphen_values = true,
        conflicts_with = "segment_s"
    )]
    pub segment_ms: Option<f64>,
    /// Length of the measurement, seconds, from the first robot's start to the stops.
    #[arg(long = "duration-s", alias = "duration", default_value_t = DEFAULT_DURATION, value_name = "S", allow_hyphen_values = true)]
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
    /// The server's largest internal step, seconds, with the output points interpolated exactly (quintic
    /// Hermite) in between. With `--integration-tolerance 0` it is a fixed RK4 step (at most one segment; 0.005 s
    /// keeps a load robot within 1e-3 of RK4 at 1 ms, the server's `runs/accuracy_tests.rs`); 0 asks for the
    /// server's default.
    #[arg(
        long = "integration-step-s",
        default_value_t = DEFAULT_INTEGRATION_STEP_S,
        value_name = "S",
        allow_hyphen_values = true
    )]
    pub integration_step_s: f64,
    /// The internal step in milliseconds: the old spelling of `--integration-step-s`, kept hidden.
    #[arg(
        long = "integration-step-ms",
        hide = true,
        value_name = "MS",
        allow_hyphen_values = true,
        conflicts_with = "integration_step_s"
    )]
    pub integration_step_ms: Option<f64>,
    /// The server's adaptive internal step: the local error tolerance of its Dormand–Prince 5(4) steps, with
    /// `--integration-step-s` the largest step (the server's `runs/accuracy_tests.rs` checks the default against
    /// RK4 at 1 ms); 0 asks for a fixed RK4 step of `--integration-step-s`. At most 0.01.
    #[arg(
        long = "integration-tolerance",
        default_value_t = DEFAULT_INTEGRATION_TOLERANCE,
        value_name = "TOL",
        allow_hyphen_values = true
    )]
    pub integration_tolerance: f64,
    /// HTTP/2 connections [default: one per cell, at most 8, and at least one per 125 robots].
    #[arg(long, value_name = "N")]
    pub connections: Option<usize>,
    /// Worker threads of the generator's runtime. One keeps up with 1,000 robots at 1 kHz in a third of a core
    /// and leaves the rest of a small machine to the server under test; more spread it over more cores.
    #[arg(long, default_value_t = DEFAULT_THREADS, value_name = "N")]
    pub threads: usize,
    /// Prefix of the cells (`<prefix>-<c>`) and robots (`<prefix>.c<c>.r<k>`).
    #[arg(long, default_value = DEFAULT_PREFIX)]
    pub prefix: String,
    /// Also write the JSON report to `DIR/load.json` (the directory is created).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// A secured server: each robot streams as its own identity, with the token in `DIR/<robot-id>.token` (as
    /// `dmp-server access init` writes them); set-up and monitoring use the command's own credentials.
    #[arg(long, value_name = "DIR")]
    pub tokens: Option<PathBuf>,
    /// Keep the robots' primitives and the cells' fixed obstacles; by default they are deleted when the load ends,
    /// also after an error or Ctrl-C.
    #[arg(long)]
    pub keep: bool,
    /// The load's cells, in order, instead of `<prefix>-<c>`: at least as many as the load has (`--robots` /
    /// `--cell-size`), each a cell some server serves. Letters, digits, `_`, `-` and `.`.
    #[arg(long = "cells", value_name = "A,B,...", value_delimiter = ',')]
    pub cell_names: Vec<String>,
    /// A plant of servers: each cell's server is found through Zenoh (its `dmp/@cells/<cell>` queryable, through
    /// `--zenoh-connect`, default tcp/127.0.0.1:7447) instead of `--server`; robots stream to their cell's
    /// server and the report has a part per server (`servers`).
    #[arg(long = "via-zenoh-discovery")]
    pub via_zenoh_discovery: bool,
    /// Pose robots (3-D only): a pose primitive, start and goal orientations a quarter turn apart (every goal
    /// change turns the robot back), and the Panda's linear and angular limits (`load/pose.rs`).
    #[arg(long)]
    pub pose: bool,
}

impl Default for LoadArgs {
    fn default() -> Self {
        Self {
            robots: DEFAULT_ROBOTS,
            rate: DEFAULT_RATE,
            segment_s: DEFAULT_SEGMENT_S,
            segment_ms: None,
            duration: DEFAULT_DURATION,
            scene_updates: 0.0,
            cell_size: DEFAULT_CELL_SIZE,
            dim: DEFAULT_DIM,
            tau: DEFAULT_TAU,
            integration_step_s: DEFAULT_INTEGRATION_STEP_S,
            integration_step_ms: None,
            integration_tolerance: DEFAULT_INTEGRATION_TOLERANCE,
            connections: None,
            threads: DEFAULT_THREADS,
            prefix: DEFAULT_PREFIX.into(),
            out: None,
            tokens: None,
            keep: false,
            cell_names: Vec::new(),
            via_zenoh_discovery: false,
            pose: false,
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

fn bad(flag: &str, message: impl Into<String>) -> SimError {
    SimError::argument(flag, message)
}

fn in_range(flag: &str, x: f64, lo: f64, hi: f64, unit: &str) -> Result<(), SimError> {
    if x.is_finite() && x >= lo && x <= hi {
        Ok(())
    } else {
        Err(bad(flag, format!("{x} is not between {lo} and {hi}{unit}")))
    }
}

impl LoadArgs {
    /// Checks every flag (the error names it) and derives the run's parameters.
    pub fn validate(&self) -> Result<Params, SimError> {
        // The old spellings in milliseconds become the seconds they stand for.
        let mut args = self.clone();
        if let Some(ms) = args.segment_ms.take() {
            args.segment_s = ms * 1e-3;
        }
        if let Some(ms) = args.integration_step_ms.take() {
            args.integration_step_s = ms * 1e-3;
        }
        args.validate_seconds()
    }

    fn validate_seconds(self) -> Result<Params, SimError> {
        in_range("--integration-step-s", self.integration_step_s, 0.0, 0.1, " s")?;
        // The server's own bound (it refuses a looser tolerance too).
        in_range("--integration-tolerance", self.integration_tolerance, 0.0, 1e-2, "")?;
        if !(1..=100_000).contains(&self.robots) {
            return Err(bad("--robots", format!("{} is not between 1 and 100000", self.robots)));
        }
        in_range("--rate", self.rate, 10.0, 10_000.0, " Hz")?;
        let dt = 1.0 / self.rate;
        in_range("--segment-s", self.segment_s, 0.0, 10.0, " s")?;
        let points = self.segment_s / dt;
        if points.round() < 1.0 || (points - points.round()).abs() > 1e-6 {
            return Err(bad(
                "--segment-s",
                format!(
                    "{} s is not a whole number (at least one) of setpoints of {} s (--rate {})",
                    self.segment_s, dt, self.rate
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
        if self.pose && self.dim != 3 {
            return Err(bad("--pose", format!("pose robots move in 3-D: use --dim 3, not {}", self.dim)));
        }
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
        if !self.cell_names.is_empty() {
            if self.cell_names.len() < cells {
                return Err(bad(
                    "--cells",
                    format!(
                        "{} cells named, the load has {cells} (--robots {} / --cell-size {})",
                        self.cell_names.len(),
                        self.robots,
                        self.cell_size
                    ),
                ));
            }
            for (i, c) in self.cell_names.iter().enumerate() {
                dmp_proto::keys::check_name("--cells", c)
                    .map_err(|e| bad("--cells", format!("`{c}` {}", e.rule)))?;
                if self.cell_names[..i].contains(c) {
                    return Err(bad("--cells", format!("`{c}` is named twice (a cell is one scene)")));
                }
            }
        }
        let connections = self.connections.unwrap_or_else(|| {
            cells.min(MAX_DEFAULT_CONNECTIONS).max(self.robots.div_ceil(STREAMS_PER_CONNECTION))
        });
        let stagger_s = (self.duration / 4.0).min(MAX_STAGGER_S);
        Ok(Params { args: self, cells, connections, dt, stagger_s })
    }
}

impl Params {
    /// The load's cells: the first of `--cells`, else `<prefix>-<c>`.
    pub(crate) fn cell_names(&self) -> Vec<String> {
        match &self.args.cell_names[..] {
            [] => (0..self.cells).map(|c| layout::cell_name(&self.args.prefix, c)).collect(),
            named => named[..self.cells].to_vec(),
        }
    }
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
        assert_eq!((p.cells, p.connections, p.dt, p.stagger_s), (10, 8, 0.001, 1.0));
        let p = check(|a| a.robots = 1000).unwrap();
        assert_eq!((p.cells, p.connections), (100, 8));
        let p = check(|a| (a.robots, a.cell_size, a.duration) = (5000, 1000, 2.0)).unwrap();
        assert_eq!((p.cells, p.connections, p.stagger_s), (5, 40, 0.5));
        type Edit = fn(&mut LoadArgs);
        let cases: [(&str, Edit); 13] = [
            ("--robots", |a| a.robots = 0),
            ("--rate", |a| a.rate = f64::NAN),
            ("--rate", |a| a.rate = -5.0),
            ("--segment-s", |a| a.segment_s = 0.0005),
            ("--segment-s", |a| a.segment_ms = Some(10.5)),
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
        assert!(check(|a| (a.pose, a.dim) = (true, 2)).unwrap_err().starts_with("--pose"));
        assert!(check(|a| a.pose = true).is_ok());
        let named = |names: &[&str]| names.iter().map(|n| n.to_string()).collect::<Vec<_>>();
        let p = check(|a| (a.robots, a.cell_names) = (25, named(&["a", "b", "c", "d"]))).unwrap();
        assert_eq!(p.cell_names(), ["a", "b", "c"]);
        assert_eq!(check(|a| a.robots = 15).unwrap().cell_names(), ["load-0", "load-1"]);
        let e = check(|a| (a.robots, a.cell_names) = (25, named(&["a", "b"]))).unwrap_err();
        assert!(e.starts_with("--cells: 2 cells named, the load has 3"), "{e}");
        for names in [&["a", "a"][..], &["a/b"]] {
            let e = check(|a| (a.robots, a.cell_names) = (1, named(names))).unwrap_err();
            assert!(e.starts_with("--cells"), "{e}");
        }
        // 2 ms segments at 500 Hz are one setpoint each.
        assert!(check(|a| (a.rate, a.segment_s) = (500.0, 0.002)).is_ok());
        assert!(check(|a| (a.rate, a.segment_ms) = (500.0, Some(2.0))).is_ok());
    }
}
