//! The `dmpctl` command line: argument parsing and dispatch (the binary only sets up and calls [`run`]).
//!
//! Offline: `scenario run FILE --out DIR` (without `--server`) and `scenario bench`. Everything else talks to the
//! server at `--server` (gRPC), or publishes over Zenoh (`scene ... --via zenoh`).

use std::path::{Path, PathBuf};
use std::str::FromStr;

use clap::{Args, Parser, Subcommand, ValueEnum};

use crate::error::ClientError;
use crate::grpc::{DEFAULT_SERVER, DmpClient};
use crate::offline::{RunSummary, bench_scenario, run_scenario};
use crate::outputs::to_json;
use crate::remote::{self, ZenohArgs};
use crate::remote_scenario::run_scenario_remote;

/// Command line of the DMP cell.
#[derive(Debug, Parser)]
#[command(
    name = "dmpctl",
    version,
    about = "Learn, plan and replay Dynamic Movement Primitives around obstacles"
)]
pub struct Cli {
    /// gRPC address of the server [default: http://127.0.0.1:50051]. `scenario run` uses the server only when
    /// this is given.
    #[arg(long, global = true, value_name = "URL")]
    pub server: Option<String>,
    /// The robot cell (Zenoh keys `dmp/<cell>/...`).
    #[arg(long, global = true, default_value = "default")]
    pub cell: String,
    /// Zenoh endpoint to connect to, e.g. `tcp/127.0.0.1:7447` (repeatable); none: multicast scouting.
    #[arg(long = "zenoh-connect", global = true, value_name = "ENDPOINT")]
    pub zenoh_connect: Vec<String>,
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// Top-level commands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Reproducible experiments in the scenario format (shared/scenarios/SPEC.md).
    #[command(subcommand)]
    Scenario(ScenarioCommand),
    /// Learn a primitive from one demonstration and store it as the next version of (robot, name).
    Learn(LearnArgs),
    /// A simulated robot against the server: writes report.json and figures into --out.
    Sim(crate::sim::SimArgs),
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
    /// Plan a whole trajectory around the cell's obstacles and write DIR/trajectory.csv.
    Plan(PlanArgs),
    /// Execute as a stream of segments (a line per segment on stderr) and write the setpoints in force to
    /// DIR/trajectory.csv.
    Stream(StreamArgs),
    /// The cell's obstacles.
    #[command(subcommand)]
    Scene(SceneCommand),
    /// Many robots streaming in real time against the server (cells of robots avoiding each other, obstacle
    /// updates over Zenoh); prints one JSON object: setpoints on time, lateness, scene update latency, server CPU
    /// and memory. `--zenoh-connect` defaults to tcp/127.0.0.1:7447; `--cell` is not used (cells are
    /// `<prefix>-<c>`).
    Load(crate::load::LoadArgs),
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

/// What to replay and how (shared by `plan` and `stream`).
#[derive(Debug, Args)]
pub struct MotionArgs {
    /// The robot.
    #[arg(long)]
    pub robot: String,
    /// The primitive.
    #[arg(long)]
    pub name: String,
    /// Its version (default: the latest).
    #[arg(long, default_value_t = 0)]
    pub version: u64,
    /// Start [default: the primitive's].
    #[arg(long, value_name = "X,Y,..", allow_hyphen_values = true)]
    pub start: Option<Vector>,
    /// Goal [default: the primitive's].
    #[arg(long, value_name = "X,Y,..", allow_hyphen_values = true)]
    pub goal: Option<Vector>,
    /// Time scale, seconds; larger is slower [default: the primitive's].
    #[arg(long, value_parser = positive, allow_hyphen_values = true)]
    pub tau: Option<f64>,
    /// Avoidance as in the scenario format, e.g. `{"method": "dynamic_volumetric", "lambda": 10, "beta": 2,
    /// "eta": 0.5}`, or `none` [default: the server's].
    #[arg(long, value_name = "JSON", value_parser = parse_avoidance)]
    pub avoidance: Option<dmp::Avoidance>,
    /// Boundary samples per obstacle for the point methods [default: 50].
    #[arg(long = "point-samples", value_name = "N")]
    pub point_samples: Option<usize>,
    /// Ignore the cell's scene.
    #[arg(long = "ignore-scene")]
    pub ignore_scene: bool,
}

/// `dmpctl plan`.
#[derive(Debug, Args)]
pub struct PlanArgs {
    /// What to replay.
    #[command(flatten)]
    pub motion: MotionArgs,
    /// Length of the plan, seconds [default: 1.2 tau].
    #[arg(long, value_parser = positive, allow_hyphen_values = true)]
    pub duration: Option<f64>,
    /// Step, seconds [default: 0.001].
    #[arg(long, value_parser = positive, allow_hyphen_values = true)]
    pub dt: Option<f64>,
    /// Output directory (created).
    #[arg(long)]
    pub out: PathBuf,
}

/// `dmpctl stream`.
#[derive(Debug, Args)]
pub struct StreamArgs {
    /// What to replay.
    #[command(flatten)]
    pub motion: MotionArgs,
    /// Pace segments on the wall clock (default: as fast as they are read).
    #[arg(long)]
    pub realtime: bool,
    /// Step, seconds [default: 0.001].
    #[arg(long, value_parser = positive, allow_hyphen_values = true)]
    pub dt: Option<f64>,
    /// Segment length, seconds [default: 0.01].
    #[arg(long, value_parser = positive, allow_hyphen_values = true)]
    pub segment: Option<f64>,
    /// Real-time lookahead, seconds [default: 0.05].
    #[arg(long, value_parser = positive, allow_hyphen_values = true)]
    pub lookahead: Option<f64>,
    /// Stop after this long, seconds [default: at the goal, or 3 tau].
    #[arg(long = "max-duration", value_parser = positive, allow_hyphen_values = true)]
    pub max_duration: Option<f64>,
    /// Output directory (created).
    #[arg(long)]
    pub out: PathBuf,
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
pub fn run(cli: Cli) -> Result<String, ClientError> {
    match (&cli.command, &cli.server) {
        (Command::Scenario(ScenarioCommand::Run { file, out }), None) => offline_run(file, out),
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
                .map_err(|source| ClientError::Io { path: PathBuf::from("(tokio runtime)"), source })?
                .block_on(run_async(cli))
        }
    }
}

/// Runs a parsed command line inside a multi-threaded tokio runtime.
pub async fn run_async(cli: Cli) -> Result<String, ClientError> {
    let server = cli.server.clone().unwrap_or_else(|| DEFAULT_SERVER.to_string());
    let zenoh = ZenohArgs { cell: cli.cell.clone(), connect: cli.zenoh_connect.clone() };
    let connect = || DmpClient::connect(server.as_str());
    match &cli.command {
        Command::Scenario(ScenarioCommand::Run { file, out }) => match &cli.server {
            None => offline_run(file, out),
            Some(url) => {
                let summary = run_scenario_remote(&connect().await?, file, out).await?;
                for n in &summary.notes {
                    eprintln!("dmpctl: note: {n}");
                }
                Ok(format!("{} (through {url})", summary_line(file, &summary, out)))
            }
        },
        Command::Scenario(ScenarioCommand::Bench { file, repeat }) => bench(file, *repeat),
        Command::Learn(a) => remote::learn(&connect().await?, a).await,
        Command::List { robot } => remote::list(&connect().await?, robot).await,
        Command::Show { robot, name, version } => {
            remote::show(&connect().await?, robot, name, *version).await
        }
        Command::Delete { robot, name } => remote::delete(&connect().await?, robot, name).await,
        Command::Plan(a) => remote::plan(&connect().await?, a).await,
        Command::Stream(a) => remote::stream(&connect().await?, a).await,
        Command::Scene(SceneCommand::Put { file, via, ttl }) => {
            remote::scene_put(&server, &zenoh, file, *via, *ttl).await
        }
        Command::Scene(SceneCommand::Delete { id, via }) => {
            remote::scene_delete(&server, &zenoh, id, *via).await
        }
        Command::Scene(SceneCommand::List) => remote::scene_list(&connect().await?).await,
        Command::Load(a) => {
            let report = crate::load::run(a, &server, &cli.zenoh_connect).await?;
            Ok(to_json(&report))
        }
        Command::Sim(a) => {
            let report = crate::sim::run_sim(a, &server, &cli.cell, &cli.zenoh_connect).await?;
            let problems = report.problems();
            Ok(format!(
                "{}: {} robots, collision: {}, {}; wrote {}",
                report.sim,
                report.robots.len(),
                report.collision,
                if problems.is_empty() { "no problem".to_string() } else { problems.join("; ") },
                a.out.display()
            ))
        }
    }
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

fn offline_run(file: &Path, out: &Path) -> Result<String, ClientError> {
    Ok(summary_line(file, &run_scenario(file, out)?, out))
}

fn bench(file: &Path, repeat: usize) -> Result<String, ClientError> {
    let report = bench_scenario(file, repeat)?;
    Ok(serde_json::to_string(&report).unwrap_or_else(|_| to_json(&report)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grpc::tests::{TestServer, within};

    fn parse(args: &[&str]) -> Cli {
        Cli::try_parse_from(std::iter::once("dmpctl").chain(args.iter().copied()))
            .unwrap_or_else(|e| panic!("{args:?}: {e}"))
    }

    fn refused(args: &[&str]) -> String {
        match Cli::try_parse_from(std::iter::once("dmpctl").chain(args.iter().copied())) {
            Ok(c) => panic!("{args:?} parsed: {c:?}"),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn scenario_commands_stay_offline_without_server() {
        let c = parse(&["scenario", "run", "s.json", "--out", "o"]);
        assert!(c.server.is_none());
        assert!(matches!(c.command, Command::Scenario(ScenarioCommand::Run { .. })));
        let c = parse(&["scenario", "run", "s.json", "--server", "http://127.0.0.1:9", "--out", "o"]);
        assert_eq!(c.server.as_deref(), Some("http://127.0.0.1:9"));
        let c = parse(&["scenario", "bench", "s.json", "--repeat", "3"]);
        assert!(matches!(c.command, Command::Scenario(ScenarioCommand::Bench { repeat: 3, .. })));
    }

    #[test]
    fn global_options_go_anywhere() {
        let c = parse(&["--server", "http://h:1", "--cell", "c1", "list", "--robot", "r"]);
        assert_eq!((c.server.as_deref(), c.cell.as_str()), (Some("http://h:1"), "c1"));
        let c = parse(&["list", "--robot", "r", "--zenoh-connect", "tcp/a:1", "--zenoh-connect", "tcp/b:2"]);
        assert_eq!(c.zenoh_connect, vec!["tcp/a:1", "tcp/b:2"]);
        assert_eq!(c.cell, "default");
    }

    #[test]
    fn learn_takes_exactly_one_source() {
        let c = parse(&[
            "learn",
            "--robot",
            "r",
            "--name",
            "p",
            "--csv",
            "d.csv",
            "--k",
            "100,200",
            "--n-basis",
            "20",
        ]);
        let Command::Learn(a) = c.command else { panic!() };
        assert_eq!(a.source.csv.as_deref(), Some(Path::new("d.csv")));
        assert_eq!(a.k, Some(Vector(vec![100.0, 200.0])));
        assert_eq!(a.n_basis, Some(20));
        let c = parse(&["learn", "--robot", "r", "--name", "p", "--scenario", "s.json"]);
        let Command::Learn(a) = c.command else { panic!() };
        assert!(a.source.scenario.is_some() && a.source.csv.is_none());
        refused(&["learn", "--robot", "r", "--name", "p"]);
        refused(&["learn", "--robot", "r", "--name", "p", "--csv", "a", "--scenario", "b"]);
        assert!(refused(&["learn", "--name", "p", "--csv", "a"]).contains("--robot"));
        assert!(
            refused(&["learn", "--robot", "r", "--name", "p", "--csv", "a", "--alpha", "-1"])
                .contains("--alpha")
        );
    }

    #[test]
    fn load_takes_its_flags_and_the_global_server() {
        let c = parse(&[
            "--server",
            "http://h:1",
            "load",
            "--robots",
            "20",
            "--rate",
            "500",
            "--segment-ms",
            "20",
            "--duration",
            "3",
            "--scene-updates",
            "5",
            "--zenoh-connect",
            "tcp/h:2",
            "--dim",
            "2",
            "--out",
            "r.json",
        ]);
        assert_eq!(
            (c.server.as_deref(), c.zenoh_connect.as_slice()),
            (Some("http://h:1"), &["tcp/h:2".into()][..])
        );
        let Command::Load(a) = c.command else { panic!() };
        let expected = crate::load::LoadArgs {
            robots: 20,
            rate: 500.0,
            segment_ms: 20.0,
            duration: 3.0,
            scene_updates: 5.0,
            dim: 2,
            out: Some(PathBuf::from("r.json")),
            ..Default::default()
        };
        assert_eq!(a, expected);
        let Command::Load(a) = parse(&["load"]).command else { panic!() };
        assert_eq!(a, crate::load::LoadArgs::default());
        assert!(refused(&["load", "--robots", "many"]).contains("--robots"));
        // Numbers clap accepts are checked by the load itself, naming the flag.
        let Command::Load(a) = parse(&["load", "--rate", "-1"]).command else { panic!() };
        assert!(a.validate().unwrap_err().to_string().starts_with("--rate"));
    }

    #[test]
    fn list_show_delete() {
        assert!(matches!(parse(&["list", "--robot", "r"]).command, Command::List { .. }));
        let Command::Show { version, .. } = parse(&["show", "--robot", "r", "--name", "p"]).command else {
            panic!()
        };
        assert_eq!(version, 0);
        let Command::Show { version, .. } =
            parse(&["show", "--robot", "r", "--name", "p", "--version", "3"]).command
        else {
            panic!()
        };
        assert_eq!(version, 3);
        assert!(matches!(parse(&["delete", "--robot", "r", "--name", "p"]).command, Command::Delete { .. }));
        assert!(refused(&["delete", "--robot", "r"]).contains("--name"));
        assert!(refused(&["show", "--robot", "r", "--name", "p", "--version", "x"]).contains("--version"));
    }

    #[test]
    fn plan_parses_vectors_with_negative_entries_and_avoidance() {
        let c = parse(&[
            "plan",
            "--robot",
            "r",
            "--name",
            "p",
            "--goal",
            "-1,0.5",
            "--start",
            "0,0",
            "--tau",
            "2",
            "--duration",
            "3",
            "--dt",
            "0.002",
            "--out",
            "o",
            "--avoidance",
            "none",
            "--ignore-scene",
        ]);
        let Command::Plan(a) = c.command else { panic!() };
        assert_eq!(a.motion.goal, Some(Vector(vec![-1.0, 0.5])));
        assert_eq!(a.motion.start, Some(Vector(vec![0.0, 0.0])));
        assert_eq!((a.motion.tau, a.duration, a.dt), (Some(2.0), Some(3.0), Some(0.002)));
        assert_eq!(a.motion.avoidance, Some(dmp::Avoidance::NONE));
        assert!(a.motion.ignore_scene);
        let spec = remote::motion_spec(&a.motion);
        assert_eq!((spec.goal, spec.tau), (vec![-1.0, 0.5], 2.0));
        assert!(spec.avoidance.is_some());

        let c = parse(&[
            "plan",
            "--robot",
            "r",
            "--name",
            "p",
            "--out",
            "o",
            "--avoidance",
            r#"{"method": "static_volumetric", "A": 10, "eta": 1}"#,
        ]);
        let Command::Plan(a) = c.command else { panic!() };
        assert_eq!(a.motion.avoidance.unwrap().method.name(), "static_volumetric");
        let spec = remote::motion_spec(&a.motion);
        assert!(spec.goal.is_empty() && spec.start.is_empty() && spec.tau == 0.0);

        let e = refused(&["plan", "--robot", "r", "--name", "p", "--goal", "1,x", "--out", "o"]);
        assert!(e.contains("--goal") && e.contains("entry 2"), "{e}");
        assert!(
            refused(&["plan", "--robot", "r", "--name", "p", "--goal", "1,NaN", "--out", "o"])
                .contains("--goal")
        );
        assert!(
            refused(&["plan", "--robot", "r", "--name", "p", "--tau", "0", "--out", "o"]).contains("--tau")
        );
        assert!(refused(&["plan", "--robot", "r", "--name", "p"]).contains("--out"));
        let e = refused(&["plan", "--robot", "r", "--name", "p", "--out", "o", "--avoidance", "magic"]);
        assert!(e.contains("--avoidance") && e.contains("magic"), "{e}");
    }

    #[test]
    fn stream_options() {
        let c = parse(&[
            "stream",
            "--robot",
            "r",
            "--name",
            "p",
            "--realtime",
            "--goal",
            "1,1",
            "--tau",
            "0.5",
            "--segment",
            "0.02",
            "--lookahead",
            "0.1",
            "--max-duration",
            "4",
            "--out",
            "o",
        ]);
        let Command::Stream(a) = c.command else { panic!() };
        assert!(a.realtime);
        assert_eq!((a.segment, a.lookahead, a.max_duration), (Some(0.02), Some(0.1), Some(4.0)));
        let Command::Stream(a) = parse(&["stream", "--robot", "r", "--name", "p", "--out", "o"]).command
        else {
            panic!()
        };
        assert!(!a.realtime && a.motion.goal.is_none());
    }

    #[test]
    fn scene_commands() {
        let Command::Scene(SceneCommand::Put { via, ttl, .. }) = parse(&["scene", "put", "o.json"]).command
        else {
            panic!()
        };
        assert_eq!((via, ttl), (Via::Grpc, None));
        let c = parse(&[
            "scene",
            "put",
            "o.json",
            "--via",
            "zenoh",
            "--ttl",
            "2.5",
            "--zenoh-connect",
            "tcp/h:7447",
        ]);
        let Command::Scene(SceneCommand::Put { via, ttl, .. }) = c.command else { panic!() };
        assert_eq!((via, ttl), (Via::Zenoh, Some(2.5)));
        assert_eq!(c.zenoh_connect, vec!["tcp/h:7447"]);
        let Command::Scene(SceneCommand::Delete { id, via }) =
            parse(&["scene", "delete", "box1", "--via", "zenoh"]).command
        else {
            panic!()
        };
        assert_eq!((id.as_str(), via), ("box1", Via::Zenoh));
        assert!(matches!(parse(&["scene", "list"]).command, Command::Scene(SceneCommand::List)));
        assert!(refused(&["scene", "put", "o.json", "--via", "carrier-pigeon"]).contains("--via"));
        assert!(refused(&["scene", "put", "o.json", "--ttl", "-1"]).contains("--ttl"));
    }

    #[test]
    fn a_closed_port_is_a_connection_failure_not_bad_input() {
        // Port 1 on loopback: nothing listens.
        let e = run(parse(&["--server", "http://127.0.0.1:1", "list", "--robot", "r"])).unwrap_err();
        assert!(matches!(e, ClientError::Connect { .. }), "{e}");
        assert!(!e.is_bad_input());
        assert!(e.to_string().contains("127.0.0.1:1"), "{e}");
        let e = run(parse(&["--server", "http://bad host:1", "list", "--robot", "r"])).unwrap_err();
        assert!(e.is_bad_input(), "{e}");
    }

    /// Runs `dmpctl --server URL ARGS...` (under the tests' timeout).
    async fn run_at(url: &str, args: &[&str]) -> Result<String, ClientError> {
        let mut all = vec!["--server", url];
        all.extend_from_slice(args);
        within(&all.join(" "), run_async(parse(&all))).await
    }

    #[tokio::test(flavor = "multi_thread")]
    async fn server_commands_against_the_server() {
        let server = TestServer::start().await;
        let url = server.url();
        let dir = tempfile::tempdir().unwrap();
        let d = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
        let csv: String = std::iter::once("t,x1,x2".to_string())
            .chain((0..=100).map(|k| {
                let t = k as f64 / 100.0;
                format!("{t},{},{}", t * t, 1.0 - t)
            }))
            .collect::<Vec<_>>()
            .join("\n");
        std::fs::write(d("demo.csv"), csv).unwrap();

        let out = run_at(
            &url,
            &["learn", "--robot", "r", "--name", "p", "--csv", &d("demo.csv"), "--n-basis", "15"],
        )
        .await
        .unwrap();
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert_eq!(
            (v["version"].as_u64(), v["dim"].as_u64(), v["n_basis"].as_u64()),
            (Some(1), Some(2), Some(15))
        );
        let scenario =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/paper-one-obstacle/none.json");
        run_at(&url, &["learn", "--robot", "r", "--name", "paper", "--scenario", scenario.to_str().unwrap()])
            .await
            .unwrap();
        let listed = run_at(&url, &["list", "--robot", "r"]).await.unwrap();
        assert!(listed.starts_with("p\tv1\tdim 2\tN 15") && listed.contains("\npaper\tv1"), "{listed}");

        let shown: serde_json::Value =
            serde_json::from_str(&run_at(&url, &["show", "--robot", "r", "--name", "p"]).await.unwrap())
                .unwrap();
        let p: dmp::Primitive = serde_json::from_value(shown["primitive"].clone()).unwrap();
        assert_eq!(p.n_basis, 15);

        let said = run_at(
            &url,
            &[
                "plan",
                "--robot",
                "r",
                "--name",
                "p",
                "--goal",
                "2,-1",
                "--duration",
                "1.5",
                "--out",
                &d("plan"),
            ],
        )
        .await
        .unwrap();
        assert!(said.contains("1501 points"), "{said}");
        let plan = std::fs::read_to_string(dir.path().join("plan/trajectory.csv")).unwrap();
        assert_eq!(plan.lines().next(), Some("t,x1,x2,xd1,xd2,a1,a2"));
        assert_eq!(plan.lines().count(), 1502);
        let last: Vec<f64> = plan.lines().last().unwrap().split(',').map(|c| c.parse().unwrap()).collect();
        assert!((last[1] - 2.0).abs() < 0.05 && (last[2] + 1.0).abs() < 0.05, "{last:?}");

        let said = run_at(
            &url,
            &[
                "stream",
                "--robot",
                "r",
                "--name",
                "p",
                "--goal",
                "2,-1",
                "--max-duration",
                "1.5",
                "--out",
                &d("stream"),
            ],
        )
        .await
        .unwrap();
        // 1501 points in segments of 10, the last one the point at 1.5 s; the goal is not reached to within 1 mm
        // by then, so the run ends at its maximum duration.
        assert!(
            said.contains("151 segments, 1501 setpoints in force up to t = 1.5 s, last status STOPPED"),
            "{said}"
        );
        let streamed = std::fs::read_to_string(dir.path().join("stream/trajectory.csv")).unwrap();
        assert_eq!(streamed.lines().count(), plan.lines().count());

        let run = run_at(&url, &["scenario", "run", scenario.to_str().unwrap(), "--out", &d("scenario")])
            .await
            .unwrap();
        assert!(run.contains("through http://"), "{run}");
        assert!(dir.path().join("scenario/metrics.json").exists());

        assert_eq!(
            run_at(&url, &["delete", "--robot", "r", "--name", "p"]).await.unwrap(),
            "deleted 1 version of r/p"
        );
        let e = run_at(&url, &["show", "--robot", "r", "--name", "p"]).await.unwrap_err();
        assert!(e.is_bad_input() && e.to_string().contains("NotFound"), "{e}");
        let e =
            run_at(&url, &["plan", "--robot", "r", "--name", "nothing", "--out", &d("x")]).await.unwrap_err();
        assert!(e.is_bad_input(), "{e}");
        let e = run_at(&url, &["learn", "--robot", "r", "--name", "p", "--csv", &d("missing.csv")])
            .await
            .unwrap_err();
        assert!(!e.is_bad_input() && e.to_string().contains("missing.csv"), "{e}");
        server.stop().await;
    }
}
