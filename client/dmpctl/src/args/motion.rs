//! The flags of the motion commands: what to replay (`MotionArgs`, and the motion it asks the server for), and
//! `plan` and `stream` around it.

use std::path::PathBuf;

use clap::Args;
use dmp_proto::avoidance::avoidance_to_proto;
use dmp_proto::v1;

use super::schedule::{GoalAt, TauAt, stop_time};
use super::values::{Vector, parse_avoidance, positive};

/// What to replay and how (shared by `plan` and `stream`).
#[derive(Debug, Args)]
pub(crate) struct MotionArgs {
    /// The robot.
    #[arg(long)]
    pub(crate) robot: String,
    /// The primitive.
    #[arg(long)]
    pub(crate) name: String,
    /// Its version (default: the latest).
    #[arg(long, default_value_t = 0)]
    pub(crate) version: u64,
    /// Start [default: the primitive's].
    #[arg(long, value_name = "X,Y,..", allow_hyphen_values = true)]
    pub(crate) start: Option<Vector>,
    /// Goal [default: the primitive's].
    #[arg(long, value_name = "X,Y,..", allow_hyphen_values = true)]
    pub(crate) goal: Option<Vector>,
    /// A pose primitive's start orientation, a unit quaternion [default: the primitive's].
    #[arg(long = "start-orientation", value_name = "QX,QY,QZ,QW", allow_hyphen_values = true)]
    pub(crate) start_orientation: Option<Vector>,
    /// A pose primitive's goal orientation, a unit quaternion; q and -q are the same [default: the primitive's].
    #[arg(long = "goal-orientation", value_name = "QX,QY,QZ,QW", allow_hyphen_values = true)]
    pub(crate) goal_orientation: Option<Vector>,
    /// Time scale, seconds; larger is slower [default: the primitive's].
    #[arg(long, value_parser = positive, allow_hyphen_values = true)]
    pub(crate) tau: Option<f64>,
    /// Avoidance as in the scenario format, e.g. `{"method": "dynamic_volumetric", "lambda": 10, "beta": 2,
    /// "eta": 0.5}`, or `none` [default: the server's].
    #[arg(long, value_name = "JSON", value_parser = parse_avoidance)]
    pub(crate) avoidance: Option<dmp::Avoidance>,
    /// Boundary samples per obstacle for the point methods [default: 50].
    #[arg(long = "point-samples", value_name = "N")]
    pub(crate) point_samples: Option<usize>,
    /// Ignore the cell's scene.
    #[arg(long = "ignore-scene")]
    pub(crate) ignore_scene: bool,
    /// "At the goal": largest distance to the goal, in the demonstration's units [default: 0.001].
    #[arg(long = "goal-tolerance", value_name = "DISTANCE", value_parser = positive)]
    pub(crate) goal_tolerance: Option<f64>,
    /// "At rest": largest speed at the goal, in the demonstration's units per second [default: 0.001].
    #[arg(long = "goal-speed-tolerance", value_name = "SPEED", value_parser = positive)]
    pub(crate) goal_speed_tolerance: Option<f64>,
    /// No limits and no safety distance: the DMP's own trajectory [default: the robot's record, then the server's
    /// default profile].
    #[arg(long = "no-limits")]
    pub(crate) no_limits: bool,
}

impl MotionArgs {
    /// The motion these flags ask for, as the schema's message (a flag not given is the message's default: the
    /// primitive's or the server's).
    pub(crate) fn spec(&self) -> v1::MotionSpec {
        let vector = |v: &Option<Vector>| v.as_ref().map(|v| v.0.clone()).unwrap_or_default();
        let samples = self.point_samples.unwrap_or(0);
        let tolerance = self.goal_tolerance.is_some() || self.goal_speed_tolerance.is_some();
        v1::MotionSpec {
            robot_id: self.robot.clone(),
            primitive: self.name.clone(),
            version: self.version,
            start: vector(&self.start),
            goal: vector(&self.goal),
            start_orientation: vector(&self.start_orientation),
            goal_orientation: vector(&self.goal_orientation),
            tau: self.tau.unwrap_or(0.0),
            avoidance: self.avoidance.as_ref().map(|a| avoidance_to_proto(a, samples)),
            ignore_scene: self.ignore_scene,
            goal_tolerance: tolerance.then(|| v1::GoalTolerance {
                position: self.goal_tolerance.unwrap_or(0.0),
                speed: self.goal_speed_tolerance.unwrap_or(0.0),
                ..Default::default()
            }),
            limits: self.no_limits.then_some(dmp_proto::limits::NO_LIMITS),
            margin: if self.no_limits { -1.0 } else { 0.0 },
            ..Default::default()
        }
    }
}

/// `dmpctl plan`.
#[derive(Debug, Args)]
pub(crate) struct PlanArgs {
    /// What to replay.
    #[command(flatten)]
    pub(crate) motion: MotionArgs,
    /// Length of the plan, seconds [default: 1.2 tau].
    #[arg(long = "duration-s", alias = "duration", value_name = "S", value_parser = positive, allow_hyphen_values = true)]
    pub(crate) duration: Option<f64>,
    /// Step, seconds [default: 0.001].
    #[arg(long = "dt-s", alias = "dt", value_name = "S", value_parser = positive, allow_hyphen_values = true)]
    pub(crate) dt: Option<f64>,
    /// Output directory (created).
    #[arg(long)]
    pub(crate) out: PathBuf,
    /// A collision is expected (a plan without avoidance): it does not make the exit code 3.
    #[arg(long)]
    pub(crate) allow_collision: bool,
}

/// `dmpctl stream`.
#[derive(Debug, Args)]
pub(crate) struct StreamArgs {
    /// What to replay.
    #[command(flatten)]
    pub(crate) motion: MotionArgs,
    /// Pace segments on the wall clock (default: as fast as they are read).
    #[arg(long)]
    pub(crate) realtime: bool,
    /// Step, seconds [default: 0.001].
    #[arg(long = "dt-s", alias = "dt", value_name = "S", value_parser = positive, allow_hyphen_values = true)]
    pub(crate) dt: Option<f64>,
    /// Segment length, seconds [default: 0.01].
    #[arg(long = "segment-s", alias = "segment", value_name = "S", value_parser = positive, allow_hyphen_values = true)]
    pub(crate) segment: Option<f64>,
    /// Real-time lookahead, seconds [default: 0.05].
    #[arg(long = "lookahead-s", alias = "lookahead", value_name = "S", value_parser = positive, allow_hyphen_values = true)]
    pub(crate) lookahead: Option<f64>,
    /// Stop after this long, seconds [default: at the goal, or 3 tau].
    #[arg(
        long = "max-duration-s",
        alias = "max-duration",
        value_name = "S",
        value_parser = positive,
        allow_hyphen_values = true
    )]
    pub(crate) max_duration: Option<f64>,
    /// Output directory (created).
    #[arg(long)]
    pub(crate) out: PathBuf,
    /// A collision is expected (a run without avoidance): it does not make the exit code 3.
    #[arg(long)]
    pub(crate) allow_collision: bool,
    /// No line per segment: only warnings, problems and the summary.
    #[arg(long)]
    pub(crate) quiet: bool,
    /// At the run's time T (seconds), change the goal to X,Y,...; repeatable.
    #[arg(long = "goal-at", value_name = "T=X,Y[,Z]", allow_hyphen_values = true)]
    pub(crate) goal_at: Vec<GoalAt>,
    /// At the run's time T (seconds), change tau (larger is slower); repeatable.
    #[arg(long = "tau-at", value_name = "T=TAU")]
    pub(crate) tau_at: Vec<TauAt>,
    /// At the run's time T (seconds), stop: decelerate to rest and end the run.
    #[arg(long = "stop-at", value_name = "T", value_parser = stop_time)]
    pub(crate) stop_at: Option<f64>,
    /// Read commands from stdin during the stream, one a line: `goal X Y [Z]`, `tau T`, `pause`, `resume`,
    /// `stop`; a bad line is reported and ignored.
    #[arg(long)]
    pub(crate) stdin: bool,
}
