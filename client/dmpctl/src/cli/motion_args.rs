//! The flags of the motion commands: what to replay (`MotionArgs`), and `plan` and `stream` around it.

use std::path::PathBuf;

use clap::Args;

use super::{Vector, parse_avoidance, positive};

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
    /// A pose primitive's start orientation, a unit quaternion [default: the primitive's].
    #[arg(long = "start-orientation", value_name = "QX,QY,QZ,QW", allow_hyphen_values = true)]
    pub start_orientation: Option<Vector>,
    /// A pose primitive's goal orientation, a unit quaternion; q and -q are the same [default: the primitive's].
    #[arg(long = "goal-orientation", value_name = "QX,QY,QZ,QW", allow_hyphen_values = true)]
    pub goal_orientation: Option<Vector>,
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
    /// "At the goal": largest distance to the goal, in the demonstration's units [default: 0.001].
    #[arg(long = "goal-tolerance", value_name = "DISTANCE", value_parser = positive)]
    pub goal_tolerance: Option<f64>,
    /// "At rest": largest speed at the goal, in the demonstration's units per second [default: 0.001].
    #[arg(long = "goal-speed-tolerance", value_name = "SPEED", value_parser = positive)]
    pub goal_speed_tolerance: Option<f64>,
}

/// `dmpctl plan`.
#[derive(Debug, Args)]
pub struct PlanArgs {
    /// What to replay.
    #[command(flatten)]
    pub motion: MotionArgs,
    /// Length of the plan, seconds [default: 1.2 tau].
    #[arg(long = "duration-s", alias = "duration", value_name = "S", value_parser = positive, allow_hyphen_values = true)]
    pub duration: Option<f64>,
    /// Step, seconds [default: 0.001].
    #[arg(long = "dt-s", alias = "dt", value_name = "S", value_parser = positive, allow_hyphen_values = true)]
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
    #[arg(long = "dt-s", alias = "dt", value_name = "S", value_parser = positive, allow_hyphen_values = true)]
    pub dt: Option<f64>,
    /// Segment length, seconds [default: 0.01].
    #[arg(long = "segment-s", alias = "segment", value_name = "S", value_parser = positive, allow_hyphen_values = true)]
    pub segment: Option<f64>,
    /// Real-time lookahead, seconds [default: 0.05].
    #[arg(long = "lookahead-s", alias = "lookahead", value_name = "S", value_parser = positive, allow_hyphen_values = true)]
    pub lookahead: Option<f64>,
    /// Stop after this long, seconds [default: at the goal, or 3 tau].
    #[arg(
        long = "max-duration-s",
        alias = "max-duration",
        value_name = "S",
        value_parser = positive,
        allow_hyphen_values = true
    )]
    pub max_duration: Option<f64>,
    /// Output directory (created).
    #[arg(long)]
    pub out: PathBuf,
}
