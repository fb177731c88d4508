//! The `dmpctl` command line: argument parsing and dispatch (the binary only sets up and calls [`run`]).
//!
//! Offline: `scenario run FILE --out DIR` (without `--server`) and `scenario bench`. Everything else talks to the
//! server at `--server` (gRPC), or publishes over Zenoh (`scene ... --via zenoh`).

use std::path::{Path, PathBuf};
use std::str::FromStr;

use clap::{Args, Parser, Subcommand, ValueEnum};
use dmp_client::grpc::{DEFAULT_SERVER, DmpClient};

use crate::connect_args::{ConnectArgs, TOKEN_ENV};
use crate::error::DmpctlError;
use crate::offline::{RunSummary, bench_scenario, run_scenario};
use crate::outputs::to_json;
use crate::place::resolve_place;
use crate::progress::Progress;
use crate::robot_commands;
pub use crate::robot_commands::RobotCommand;
use crate::scenario_file::load_scenario;
use crate::scenario_through_server::{self, robot_ids, run_scenario_through_server};
use crate::server_commands::{self, ZenohArgs};
use crate::tools::{self, until_interrupted};
use dmp_sim::robots::robot::segments_read;

mod motion_args;
pub use self::motion_args::{MotionArgs, PlanArgs, StreamArgs};

/// Command line of the DMP cell.
#[derive(Debug, Parser)]
#[command(
    name = "dmpctl",
    version,
    about = "Learn, plan and replay Dynamic Movement Primitives around obstacles"
)]
pub struct Cli {
    /// gRPC address of the server [default: with `--cell` and `--zenoh-connect` (or `--zenoh-config`), the server
    /// of the plant serving the cell, asked over Zenoh; else http://127.0.0.1:50051]. `scenario run` uses the
    /// server only when this is given.
    #[arg(long, global = true, value_name = "URL")]
    pub server: Option<String>,
    /// The robot cell of every command: its scene, its motions and its Zenoh keys `dmp/<cell>/...` [default: the
    /// server's own default cell, from GetInfo]. Letters, digits, `_`, `-` and `.`.
    #[arg(long, global = true, value_name = "NAME")]
    pub cell: Option<String>,
    /// Zenoh endpoint to connect to, e.g. `tcp/127.0.0.1:7447` (repeatable) [default: the server's own Zenoh
    /// locators, from GetInfo, unless `--zenoh-config` is given].
    #[arg(long = "zenoh-connect", global = true, value_name = "ENDPOINT")]
    pub zenoh_connect: Vec<String>,
    /// A stock Zenoh configuration file (JSON5) for `--via zenoh`: TLS and credentials, as `dmp-server access init`
    /// writes for a perception node; `--zenoh-connect` replaces its endpoints.
    #[arg(long = "zenoh-config", global = true, value_name = "FILE")]
    pub zenoh_config: Option<PathBuf>,
    /// TLS and the bearer token.
    #[command(flatten)]
    pub connect: ConnectArgs,
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// Top-level commands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Reproducible experiments in the scenario format (JSON; the data model and its rules are `dmp::scenario`'s,
    /// the paper's experiments are in `scenarios/`).
    #[command(subcommand)]
    Scenario(ScenarioCommand),
    /// Learn a primitive from one demonstration and store it as the next version of (robot, name).
    Learn(LearnArgs),
    /// A simulated robot against the server: writes report.json and figures into --out.
    Sim(dmp_sim::robots::SimArgs),
    /// How the server is set up (TLS, access control, what it exposes, its cell, Zenoh locators and limits) and
    /// who this client is to it, as JSON.
    Info,
    /// The server's statistics (GetStats) as JSON: uptime, CPU, memory, streams, compute budgets.
    Stats,
    /// The gRPC health of the server and of each service, one line each (5 s per answer at most); exits with 1
    /// when one is not serving.
    Health,
    /// Every robot that has primitives (those this client may read), one line each: its id, how many primitives,
    /// and when the latest was stored.
    Robots,
    /// The primitives of a robot (latest version of each).
    List {
        /// The robot.
        #[arg(long)]
        robot: String,
    },
    /// One stored primitive, as JSON.
    Show {
        /// The robot.
        #[arg(long)]
        robot: String,
        /// The primitive.
        #[arg(long)]
        name: String,
        /// Its version (default: the latest).
        #[arg(long, default_value_t = 0)]
        version: u64,
    },
    /// Delete every version of a primitive.
    Delete {
        /// The robot.
        #[arg(long)]
        robot: String,
        /// The primitive.
        #[arg(long)]
        name: String,
    },
    /// Plan a whole trajectory around the cell's obstacles and write DIR/trajectory.csv and DIR/plot.svg.
    Plan(PlanArgs),
    /// Execute as a stream of segments (a line per segment on stderr) and write the setpoints in force to
    /// DIR/trajectory.csv, and DIR/plot.svg.
    Stream(StreamArgs),
    /// The cell's obstacles.
    #[command(subcommand)]
    Scene(SceneCommand),
    /// A robot's record: its limits, footprint and tool, the defaults of its motion requests.
    #[command(subcommand)]
    Robot(RobotCommand),
    /// Many robots streaming in real time against the server (cells of robots avoiding each other, obstacle
    /// updates over Zenoh); prints one JSON object: setpoints on time, lateness, scene update latency, server CPU
    /// and memory. With `--scene-updates`, `--zenoh-connect` defaults to the server's loopback Zenoh locators
    /// (GetInfo, when the server is on this host), else tcp/127.0.0.1:7447; `--cell` is not used (cells are
    /// `<prefix>-<c>`).
    Load(dmp_sim::load::LoadArgs),
}

/// `dmpctl scenario ...`
#[derive(Debug, Subcommand)]
pub enum ScenarioCommand {
    /// Learn, roll out with and without obstacles, write trajectory.csv, metrics.json and plot.svg. Offline,
    /// unless `--server URL` is given: then the server learns and plans.
    Run {
        /// The scenario file.
        file: PathBuf,
        /// Output directory (created).
        #[arg(long)]
        out: PathBuf,
        /// A collision is expected (the paper's run without avoidance): it does not make the exit code 3.
        #[arg(long)]
        allow_collision: bool,
        /// With `--server`: keep the primitives of the run's robots (`scenario.<name>`), which are otherwise
        /// deleted when it ends, also after an error or Ctrl-C.
        #[arg(long)]
        keep: bool,
    },
    /// Time the avoidance rollout and print one JSON object.
    Bench {
        /// The scenario file.
        file: PathBuf,
        /// Timed repetitions (the median is reported).
        #[arg(long, default_value_t = 5)]
        repeat: usize,
    },
}

/// Where a demonstration comes from.
#[derive(Debug, Args)]
#[group(required = true, multiple = false)]
pub struct LearnSource {
    /// A scenario file: its demonstration and its `dmp` parameters.
    #[arg(long, value_name = "FILE")]
    pub scenario: Option<PathBuf>,
    /// A CSV file: first column the time, then the positions (optional header `t,x1..xd`).
    #[arg(long, value_name = "FILE")]
    pub csv: Option<PathBuf>,
}

/// `dmpctl learn`.
#[derive(Debug, Args)]
pub struct LearnArgs {
    /// The robot.
    #[arg(long)]
    pub robot: String,
    /// The primitive's name.
    #[arg(long)]
    pub name: String,
    /// The demonstration.
    #[command(flatten)]
    pub source: LearnSource,
    /// The paper's N (N + 1 Gaussians) [default: the scenario's, or 50].
    #[arg(long = "n-basis", value_name = "N")]
    pub n_basis: Option<u32>,
    /// Stiffness K, one value or one per dimension [default: the scenario's, or 1050].
    #[arg(long, value_name = "K,..", allow_hyphen_values = true)]
    pub k: Option<Vector>,
    /// Damping D, like K [default: the scenario's, or 2 sqrt(K)].
    #[arg(long, value_name = "D,..", allow_hyphen_values = true)]
    pub d: Option<Vector>,
    /// Canonical decay alpha [default: the scenario's, or 4].
    #[arg(long, value_parser = positive, allow_hyphen_values = true)]
    pub alpha: Option<f64>,
}

/// How an obstacle update travels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Via {
    /// The scene service.
    Grpc,
    /// A put or delete on `dmp/<cell>/obstacles/<id>`.
    Zenoh,
}

/// `dmpctl scene ...`
#[derive(Debug, Subcommand)]
pub enum SceneCommand {
    /// Add or replace obstacles: FILE is one JSON obstacle of the scenario format (plus optional `margin`,
    /// `ttl_s`), or a file whose `obstacles` are all put (e.g. a scenario).
    Put {
        /// The file.
        file: PathBuf,
        /// Transport.
        #[arg(long, value_enum, default_value_t = Via::Grpc)]
        via: Via,
        /// Seconds after which the obstacles expire (replaces the file's `ttl_s`; 0: never).
        #[arg(long, value_parser = non_negative, allow_hyphen_values = true)]
        ttl: Option<f64>,
    },
    /// Remove an obstacle.
    Delete {
        /// Its id.
        id: String,
        /// Transport.
        #[arg(long, value_enum, default_value_t = Via::Grpc)]
        via: Via,
    },
    /// The current obstacles, as JSON.
    List,
}

/// A vector on the command line: comma-separated finite numbers, e.g. `0.5,-1,2e-3`.
#[derive(Debug, Clone, PartialEq)]
pub struct Vector(pub Vec<f64>);

impl FromStr for Vector {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let mut v = Vec::new();
        for (i, part) in s.split(',').enumerate() {
            let part = part.trim();
            match part.parse::<f64>() {
                Ok(x) if x.is_finite() => v.push(x),
                _ => return Err(format!("entry {} (`{part}`) is not a finite number", i + 1)),
            }
        }
        Ok(Vector(v))
    }
}

fn positive(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
        _ => Err(format!("`{s}` is not a finite number greater than zero")),
    }
}

fn non_negative(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x >= 0.0 => Ok(x),
        _ => Err(format!("`{s}` is not a finite number >= 0")),
    }
}

/// The scenario format's avoidance object, or a bare method name (`none`).
fn parse_avoidance(s: &str) -> Result<dmp::Avoidance, String> {
    let t = s.trim();
    let json = if t.starts_with('{') { t.to_string() } else { format!("{{\"method\": \"{t}\"}}") };
    serde_json::from_str(&json).map_err(|e| e.to_string())
}

/// Runs a parsed command line; returns what to print on standard output. Offline commands run on this thread;
/// the others on a multi-threaded tokio runtime (Zenoh needs one).
pub fn run(cli: Cli) -> Result<String, DmpctlError> {
    match (&cli.command, &cli.server) {
        (Command::Scenario(ScenarioCommand::Run { file, out, allow_collision, .. }), None) => {
            offline_run(file, out, *allow_collision)
        }
        (Command::Scenario(ScenarioCommand::Bench { file, repeat }), _) => bench(file, *repeat),
        (command, _) => {
            let mut builder = tokio::runtime::Builder::new_multi_thread();
            if let Command::Load(a) = command {
                // Checked with the other flags once running; the runtime needs at least one.
                builder.worker_threads(a.threads.max(1));
            }
            builder
                .enable_all()
                .build()
                .map_err(|source| DmpctlError::Io { path: PathBuf::from("(tokio runtime)"), source })?
                .block_on(run_async(cli))
        }
    }
}

/// Runs a parsed command line inside a multi-threaded tokio runtime.
pub async fn run_async(cli: Cli) -> Result<String, DmpctlError> {
    // On the heap: the commands' futures together are larger than a test thread's or a worker's stack allows in
    // a debug build.
    Box::pin(dispatch(cli)).await
}

async fn dispatch(cli: Cli) -> Result<String, DmpctlError> {
    let options =
        cli.connect.options(std::env::var(TOKEN_ENV).ok(), |w| eprintln!("dmpctl: warning: {w}"))?;
    let default_server = if options.tls.is_some() { "https://127.0.0.1:50051" } else { DEFAULT_SERVER };
    let server = crate::place::resolve_server(&cli, default_server).await;
    // Local inputs first: a bad file is refused before the server is asked anything.
    let obstacles = match &cli.command {
        Command::Scene(SceneCommand::Put { file, ttl, .. }) => server_commands::read_obstacles(file, *ttl)?,
        _ => Vec::new(),
    };
    let place = resolve_place(&cli, &server, &options).await?;
    let zenoh = ZenohArgs {
        cell: place.zenoh_cell().to_owned(),
        connect: place.zenoh_connect.clone(),
        config_file: cli.zenoh_config.clone(),
    };
    let connect = || async {
        Ok::<_, DmpctlError>(DmpClient::connect_with(&server, &options).await?.with_cell(place.grpc_cell()))
    };
    match &cli.command {
        Command::Scenario(ScenarioCommand::Run { file, out, allow_collision, keep }) => match &cli.server {
            None => offline_run(file, out, *allow_collision),
            Some(url) => {
                let client = connect().await?;
                // The robots to clean up after Ctrl-C (an unreadable file stores nothing).
                let robots = load_scenario(file).map(|s| robot_ids(&s)).unwrap_or_default();
                let clean_up = async {
                    let n = scenario_through_server::clean_up(&client, &robots).await?;
                    Ok(tools::deleted(n, &robots))
                };
                let run = run_scenario_through_server(&client, file, out, *keep);
                let progress = Progress::new(format!("scenario run {}", file.display()));
                let n = plural(robots.len(), "robot");
                let status = || format!("{n} through {url}");
                let summary = until_interrupted(run, (!keep).then_some(clean_up), &progress, status).await?;
                for n in &summary.notes {
                    eprintln!("dmpctl: note: {n}");
                }
                let line = format!("{} (through {url})", summary_line(file, &summary, out));
                gate(line, scenario_problems(&summary, *allow_collision))
            }
        },
        Command::Scenario(ScenarioCommand::Bench { file, repeat }) => bench(file, *repeat),
        // Boxed, as the other large commands: one future per command, not the largest of all on the stack.
        Command::Learn(a) => Box::pin(server_commands::learn(&connect().await?, a)).await,
        Command::Robots => server_commands::robots(&connect().await?).await,
        Command::List { robot } => server_commands::list(&connect().await?, robot).await,
        Command::Show { robot, name, version } => {
            server_commands::show(&connect().await?, robot, name, *version).await
        }
        Command::Delete { robot, name } => server_commands::delete(&connect().await?, robot, name).await,
        Command::Plan(a) => server_commands::plan(&connect().await?, a).await,
        Command::Stream(a) => server_commands::stream(&connect().await?, a).await,
        Command::Scene(SceneCommand::Put { via, .. }) => {
            server_commands::scene_put(connect, &zenoh, &obstacles, *via).await
        }
        Command::Scene(SceneCommand::Delete { id, via }) => {
            server_commands::scene_delete(connect, &zenoh, id, *via).await
        }
        Command::Info => Ok(to_json(&server_commands::info_json(&connect().await?.info().await?))),
        Command::Stats => Ok(to_json(&server_commands::stats_json(&connect().await?.stats().await?))),
        Command::Health => server_commands::health(&connect().await?).await,
        Command::Scene(SceneCommand::List) => server_commands::scene_list(&connect().await?).await,
        Command::Robot(RobotCommand::Put { id, limits, footprint, tool }) => {
            // Local inputs first: a bad file is refused before the server is asked anything.
            let limits = limits.as_deref().map(robot_commands::read_limits).transpose()?;
            let tool = tool.as_deref().map(robot_commands::read_tool).transpose()?;
            let record =
                robot_commands::record(id, limits.as_ref(), footprint.as_ref().map(|f| &f.0[..]), tool);
            robot_commands::put(&connect().await?, record).await
        }
        Command::Robot(RobotCommand::Show { id }) => robot_commands::show(&connect().await?, id).await,
        Command::Robot(RobotCommand::Delete { id }) => robot_commands::delete(&connect().await?, id).await,
        Command::Load(a) => {
            let run =
                async { Ok(dmp_sim::load::run_with(a, &server, &place.zenoh_connect, &options).await?) };
            let clean_up = async {
                dmp_sim::load::clean_up(a, &server, &place.zenoh_connect, &options).await?;
                Ok("deleted the robots' primitives and the cells' fixed obstacles".to_string())
            };
            let progress = Progress::new("load");
            let status = || format!("{} streaming", plural(a.robots, "robot"));
            let report = until_interrupted(run, (!a.keep).then_some(clean_up), &progress, status).await?;
            Ok(to_json(&report))
        }
        Command::Sim(a) => {
            let zenoh_config = cli.zenoh_config.as_deref();
            let cell = place.zenoh_cell();
            let run = async {
                let sim =
                    dmp_sim::robots::run_sim(a, &server, &options, cell, &place.zenoh_connect, zenoh_config);
                Ok(sim.await?)
            };
            let clean_up = async {
                let n = dmp_sim::robots::clean_up(&connect().await?.with_cell(cell), a.name).await?;
                Ok(tools::deleted(n, &a.name.robot_ids()))
            };
            let progress = Progress::new(format!("sim {}", a.name.as_str()));
            let robots = plural(a.name.robot_ids().len(), "robot");
            let status = || format!("{robots}, {}", plural(segments_read() as usize, "segment"));
            let report = until_interrupted(run, (!a.keep).then_some(clean_up), &progress, status).await?;
            let mut problems = report.problems_allowing(a.allow_collision);
            // Late setpoints fail the run too (a real robot would have executed stale ones).
            for (id, r) in &report.robots {
                if r.late_setpoints > 0 {
                    problems.push(format!("{id}: {} late setpoints", r.late_setpoints));
                }
            }
            let (robots, runs) = report.robots_and_runs();
            let line = format!(
                "{}: {}, {}, collision: {}, {}; wrote {}",
                report.sim,
                plural(robots, "robot"),
                plural(runs, "run"),
                report.collision,
                if problems.is_empty() { "no problem".to_string() } else { problems.join("; ") },
                a.out.display()
            );
            gate(line, problems)
        }
    }
}

/// `1 robot`, `3 robots`.
fn plural(n: usize, what: &str) -> String {
    format!("{n} {what}{}", if n == 1 { "" } else { "s" })
}

fn summary_line(file: &Path, summary: &RunSummary, out: &Path) -> String {
    let m = &summary.metrics;
    format!(
        "{}: {} steps in {:.3} s, collision: {}, eps_max {:.4}, final goal distance {:.2e}; wrote {}",
        file.display(),
        m.steps,
        m.compute_seconds,
        m.collision,
        m.eps_max,
        m.final_goal_distance,
        out.display()
    )
}

fn offline_run(file: &Path, out: &Path, allow_collision: bool) -> Result<String, DmpctlError> {
    let progress = Progress::new(format!("scenario run {}", file.display()));
    progress.set_message("rolling out");
    let summary = run_scenario(file, out);
    drop(progress);
    let summary = summary?;
    gate(summary_line(file, &summary, out), scenario_problems(&summary, allow_collision))
}

/// What went wrong in a scenario run that completed: a collision (unless allowed), a stall, non-finite values, or
/// a goal not reached (within 1 cm, `time_to_goal`).
fn scenario_problems(summary: &RunSummary, allow_collision: bool) -> Vec<String> {
    let m = &summary.metrics;
    let mut problems = Vec::new();
    if m.collision && !allow_collision {
        problems.push("collision (--allow-collision if it is meant to)".to_string());
    }
    for s in &m.stalls {
        problems
            .push(format!("{} stalled at t = {:.3} s, {:.3} m from its goal", s.robot, s.since, s.distance));
    }
    if !m.finite {
        problems.push("non-finite values in the trajectory".into());
    }
    if m.time_to_goal.is_none() {
        problems.push(format!("goal not reached ({:.3e} m away at the end)", m.final_goal_distance));
    }
    problems
}

/// `line` when nothing went wrong, else [`DmpctlError::Problems`] (exit code 3).
fn gate(line: String, problems: Vec<String>) -> Result<String, DmpctlError> {
    if problems.is_empty() { Ok(line) } else { Err(DmpctlError::Problems { summary: line, problems }) }
}

fn bench(file: &Path, repeat: usize) -> Result<String, DmpctlError> {
    let progress = Progress::new(format!("scenario bench {}", file.display()));
    progress.set_message(format!("{} timed rollouts", repeat));
    let report = bench_scenario(file, repeat);
    drop(progress);
    let report = report?;
    Ok(serde_json::to_string(&report).unwrap_or_else(|_| to_json(&report)))
}

#[cfg(test)]
mod tests;
