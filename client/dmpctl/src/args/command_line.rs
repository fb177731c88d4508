//! The command line as a whole: its global flags and its commands.

use std::path::PathBuf;

use clap::{Parser, Subcommand};

use super::connect::ConnectArgs;
use super::learn::LearnArgs;
use super::motion::{PlanArgs, StreamArgs};
use super::robot::RobotCommand;
use super::scenario::ScenarioCommand;
use super::scene::SceneCommand;

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
    /// server only when this is given (or `DMP_SERVER` is set).
    #[arg(long, global = true, value_name = "URL", env = "DMP_SERVER")]
    pub(crate) server: Option<String>,
    /// The robot cell of every command: its scene, its motions and its Zenoh keys `dmp/<cell>/...` [default: the
    /// server's own default cell, from GetInfo]. Letters, digits, `_`, `-` and `.`.
    #[arg(long, global = true, value_name = "NAME", env = "DMP_CELL")]
    pub(crate) cell: Option<String>,
    /// Zenoh endpoint to connect to, e.g. `tcp/127.0.0.1:7447` (repeatable) [default: the server's own Zenoh
    /// locators, from GetInfo, unless `--zenoh-config` is given].
    #[arg(long = "zenoh-connect", global = true, value_name = "ENDPOINT")]
    pub(crate) zenoh_connect: Vec<String>,
    /// A stock Zenoh configuration file (JSON5) for `--via zenoh`: TLS and credentials, as `dmp-server access init`
    /// writes for a perception node; `--zenoh-connect` replaces its endpoints.
    #[arg(long = "zenoh-config", global = true, value_name = "FILE")]
    pub(crate) zenoh_config: Option<PathBuf>,
    /// TLS and the bearer token.
    #[command(flatten)]
    pub(crate) connect: ConnectArgs,
    /// What to do.
    #[command(subcommand)]
    pub(crate) command: Command,
}

/// Top-level commands.
#[derive(Debug, Subcommand)]
pub(crate) enum Command {
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
