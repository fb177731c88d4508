//! Simulated robots that drive the real server exactly as real robots and perception nodes would: through gRPC
//! (Execute, ExecuteGroup) and Zenoh only. Each executes its segments at its control rate on a simulated clock (or
//! the wall clock), checks that its setpoints are continuous and on time, measures its clearance to the obstacles'
//! true shapes with parry3d-f64, and writes `report.json` and figures in the paper's style.
//!
//! | concept | file |
//! | --- | --- |
//! | the command line's arguments, the entry point, shared helpers | `mod.rs` |
//! | a robot's controller: supersession, clock, lateness, continuity | `robot.rs` |
//! | true shapes and distances (parry3d-f64) | `world.rs` |
//! | `report.json`: what each robot did, measured against the true shapes; the figures | `report.rs` |
//! | each robot's limit profile: its robot record, finite differences against it | `profile.rs` |
//! | `report.html`: the figures, clearances, limits, pass or fail per check | `html.rs` |
//! | clearance along a whole run, robots side by side, closest approach | `clearance.rs` |
//! | the Panda arm: its profile, its pose primitives, one pose run executed, measured and drawn | `panda_arm.rs` |
//! | the Panda pick and place, carrying the ring with its orientation | `panda.rs` |
//! | the Panda carrying a 0.6 m bar through a 0.3 m gap, turning it (a held tool) | `panda_bar.rs` |
//! | a pose robot's orientation in its report: goal angle, angular finite differences | `pose.rs` |
//! | two da Vinci PSMs' ring transfer with a handover: the cell, its geometry and gains | `psm.rs` |
//! | its stages (on one 6-D phase, or as two pose runs), run one after the other and recorded | `psm_stage.rs` |
//! | the youBot with a perception node over Zenoh | `perception.rs` |
//! | three youBots on one phase, walls and cubes | `youbots.rs` |
//! | fitting an ellipse to a point cloud | `ellipse_fit.rs` |
//! | synthetic demonstrations: constant-speed line, minimum jerk | `demonstration.rs` |

mod clearance;
mod demonstration;
mod ellipse_fit;
mod html;
pub mod panda;
mod panda_arm;
pub mod panda_bar;
mod perception;
pub mod pose;
mod profile;
pub mod psm;
pub mod psm_stage;
mod report;
pub mod robot;
mod world;
mod youbots;

use std::future::Future;
use std::path::{Path, PathBuf};
use std::time::Duration;

use dmp::Trajectory;
use dmp_client::connect::ConnectOptions;
use dmp_client::grpc::DmpClient;
use dmp_proto::v1;
use tokio_stream::StreamExt;

use self::robot::{Controller, Executed};
use crate::error::SimError;

pub use self::report::{RobotReport, SimReport};

/// A still superquadric obstacle (no rotation) inflated by `margin`, as the scene takes it.
pub(crate) fn superquadric(
    id: &str,
    center: &[f64],
    semi_axes: Vec<f64>,
    exponents: Vec<f64>,
    margin: f64,
) -> dmp_proto::obstacle_json::JsonObstacle {
    let spec = dmp::scenario::ObstacleSpec {
        id: id.into(),
        center: center.to_vec(),
        semi_axes,
        exponents: Some(exponents),
        rotation: None,
        velocity: None,
        nested: None,
    };
    dmp_proto::obstacle_json::JsonObstacle { spec, margin, ttl_s: 0.0 }
}

/// The simulations' learning parameters: `N = 50` basis functions, `alpha = 4`, stiffness `k` (the paper's 3050 for
/// the arms) and critical damping `D = 2 sqrt(K)` (the server's default).
pub(crate) fn learn_parameters(k: f64) -> v1::LearnParameters {
    v1::LearnParameters { n_basis: 50, k: vec![k], d: Vec::new(), alpha: 4.0 }
}

/// The namespace of the simulations' robots on the server: the Panda of `dmpctl sim panda` is `sim.panda`, never
/// the quick start's `panda`, so a simulation neither reads nor bumps a real robot's primitives. `.` is allowed in
/// robot ids (`[A-Za-z0-9_.-]`) and in no name of the simulations, so the prefix cannot be mistaken for part of one.
pub(crate) const ROBOT_PREFIX: &str = "sim.";

/// The id the server knows a simulated robot by: [`ROBOT_PREFIX`] and its local name (`panda` is `sim.panda`).
pub(crate) fn server_robot(local: &str) -> String {
    format!("{ROBOT_PREFIX}{local}")
}

/// Longest wait for any one answer of the server (a segment, a put).
pub(crate) const STEP_TIMEOUT: Duration = Duration::from_secs(30);

/// The simulations.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum SimName {
    /// Franka Emika Panda: pick and place past a peg, then a bar carried through a gap, poses at 1 kHz.
    Panda,
    /// One youBot; a perception node publishes an unknown box over Zenoh (always paced in real time: about 20 s).
    YoubotPerception,
    /// Three youBots on one 2-D phase in a walled room with cubes, each a moving obstacle for the others.
    Youbots,
    /// Two da Vinci PSMs: pick, hand over and place a ring among pegs, the jaws turning, 3-D each at 1 kHz.
    Psm,
}

impl SimName {
    /// Its name on the command line.
    pub fn as_str(self) -> &'static str {
        match self {
            SimName::Panda => "panda",
            SimName::YoubotPerception => "youbot-perception",
            SimName::Youbots => "youbots",
            SimName::Psm => "psm",
        }
    }

    /// The robots it stores primitives for, as the server knows them (`sim.<name>`).
    pub fn robot_ids(self) -> Vec<String> {
        let local = match self {
            SimName::Panda => panda_arm::ROBOT_IDS,
            SimName::YoubotPerception => &perception::ROBOT_IDS[..],
            SimName::Youbots => youbots::ROBOT_IDS,
            SimName::Psm => psm::ROBOT_IDS,
        };
        local.iter().map(|id| server_robot(id)).collect()
    }

    /// The obstacles it puts into the cell's scene (each run removes its own; [`clean_up`] removes what an
    /// interrupted run left).
    pub(crate) fn obstacle_ids(self) -> Vec<&'static str> {
        match self {
            SimName::YoubotPerception => perception::unknown_boxes().iter().map(|b| b.id).collect(),
            _ => Vec::new(),
        }
    }
}

/// `dmpctl sim NAME [--server URL] [--realtime] [--tokens DIR] --out DIR`.
#[derive(Debug, Clone, clap::Args)]
pub struct SimArgs {
    /// Which simulation.
    #[arg(value_enum)]
    pub name: SimName,
    /// Pace the robots on the wall clock (the server streams in real time) instead of a simulated clock, where the
    /// runs go as fast as they are computed (`youbot-perception` is always real time).
    #[arg(long)]
    pub realtime: bool,
    /// Folder of `report.json` and the figures.
    #[arg(long)]
    pub out: PathBuf,
    /// A secured server: each robot streams its own run with its own token, `DIR/<robot>.token` (as `access init
    /// --robot` writes them). The set-up (learning, plans, the scene) and the group runs (one stream moves several
    /// robots) use the command's own credentials (`--token`, `DMP_TOKEN` or a certificate), a planner's.
    #[arg(long, value_name = "DIR")]
    pub tokens: Option<PathBuf>,
    /// A collision is expected: it does not make the exit code 3 (the other problems still do).
    #[arg(long)]
    pub allow_collision: bool,
    /// Keep the primitives the simulation stored (robots `sim.<name>`); by default they are deleted when it ends,
    /// also after an error or Ctrl-C.
    #[arg(long)]
    pub keep: bool,
}

/// How a simulation runs.
#[derive(Debug, Clone)]
pub struct SimOptions {
    /// Wall-clock pacing.
    pub realtime: bool,
    /// Output folder (created).
    pub out: PathBuf,
    /// Zenoh endpoints of the server (perception nodes connect there); empty: scouting.
    pub zenoh_connect: Vec<String>,
    /// The server's cell.
    pub cell: String,
    /// A stock Zenoh configuration for the perception node (`--zenoh-config`; `zenoh_connect` still overrides its
    /// endpoints).
    pub zenoh_config: Option<PathBuf>,
    /// Each robot's token, `<dir>/<robot>.token` (`<robot>` as the server knows it: `sim.panda`), for its own
    /// stream (none: the client's credentials).
    pub tokens: Option<PathBuf>,
    /// Keep the primitives stored (else [`clean_up`] deletes them when the simulation ends, even on an error).
    pub keep: bool,
}

impl SimOptions {
    /// The client robot `id` streams with: `client` with the robot's own token under [`SimOptions::tokens`].
    pub(crate) fn robot_client(&self, client: &DmpClient, id: &str) -> Result<DmpClient, SimError> {
        let Some(dir) = &self.tokens else { return Ok(client.clone()) };
        let path = dir.join(format!("{id}.token"));
        let token = std::fs::read_to_string(&path)
            .map_err(|e| SimError::argument("--tokens", format!("{}: {e}", path.display())))?;
        Ok(client.with_token(Some(token.trim()))?)
    }
}

/// Runs the simulation of `args` (the `dmpctl sim` command) and writes its report; fails when the simulation
/// could not run. A run that misses a goal or collides still returns its report (see [`SimReport::problems`]).
pub async fn run_sim(
    args: &SimArgs,
    server: &str,
    connect: &ConnectOptions,
    cell: &str,
    zenoh_connect: &[String],
    zenoh_config: Option<&Path>,
) -> Result<SimReport, SimError> {
    let options = SimOptions {
        realtime: args.realtime,
        out: args.out.clone(),
        zenoh_connect: zenoh_connect.to_vec(),
        cell: cell.to_string(),
        zenoh_config: zenoh_config.map(Path::to_owned),
        tokens: args.tokens.clone(),
        keep: args.keep,
    };
    run_with(server, connect, args.name, &options).await
}

/// Runs one simulation against the server at `url`.
pub async fn run(url: &str, name: SimName, options: &SimOptions) -> Result<SimReport, SimError> {
    run_with(url, &ConnectOptions::default(), name, options).await
}

/// [`run`] with TLS and credentials (`connect`).
pub async fn run_with(
    url: &str,
    connect: &ConnectOptions,
    name: SimName,
    options: &SimOptions,
) -> Result<SimReport, SimError> {
    let client = DmpClient::connect_with(url, connect).await?.with_cell(options.cell.as_str());
    std::fs::create_dir_all(&options.out)
        .map_err(|source| SimError::Io { path: options.out.clone(), source })?;
    let ran = match name {
        SimName::Panda => panda::run(&client, options).await,
        SimName::YoubotPerception => perception::run(&client, options).await,
        SimName::Youbots => youbots::run(&client, options).await,
        SimName::Psm => psm_stage::run(&client, options).await,
    };
    let cleaned = if options.keep { Ok(0) } else { clean_up(&client, name).await };
    // The simulation's own error first: a clean-up that failed after it says less.
    let mut report = ran?;
    if let Err(e) = cleaned {
        report
            .notes
            .push(format!("clean-up: the primitives of {} may be left: {e}", name.robot_ids().join(", ")));
    }
    report.write_json(&options.out)?;
    html::write_html(&report, &options.out)?;
    Ok(report)
}

/// Deletes every primitive and the record of the simulation's robots and the obstacles it may have left in
/// `client`'s cell; returns how many primitive versions were deleted. Each robot's primitives are all the simulation's: its ids are
/// its own (`server_robot`).
pub async fn clean_up(client: &DmpClient, name: SimName) -> Result<u64, SimError> {
    let mut deleted = 0;
    for robot in name.robot_ids() {
        deleted += within("clean-up", client.delete_robot_primitives(&robot)).await??;
        match within("clean-up: record", client.delete_robot(&robot)).await? {
            Err(e) if !e.is_not_found() => return Err(e.into()),
            _ => {}
        }
    }
    let ids = name.obstacle_ids();
    if !ids.is_empty() {
        let scene = within("clean-up: scene", client.list_obstacles()).await??;
        for o in scene.obstacles.iter().filter(|o| ids.contains(&o.id.as_str())) {
            within("clean-up: obstacle", client.delete_obstacle(&o.id)).await??;
        }
    }
    Ok(deleted)
}

/// `f`, failing after [`STEP_TIMEOUT`].
pub(crate) async fn within<F: Future>(what: &str, f: F) -> Result<F::Output, SimError> {
    tokio::time::timeout(STEP_TIMEOUT, f)
        .await
        .map_err(|_| SimError::protocol(format!("timed out after {STEP_TIMEOUT:?}: {what}")))
}

/// The pacing of `options`.
pub(crate) fn pacing(realtime: bool) -> i32 {
    if realtime { v1::Pacing::Realtime as i32 } else { v1::Pacing::AsFastAsRead as i32 }
}

/// Streams one robot's execution to its end through a [`Controller`]; `on_segment` sees the controller after each
/// segment (e.g. to trigger perception events at the robot's time).
pub(crate) async fn execute(
    client: &DmpClient,
    request: v1::ExecuteRequest,
    realtime: bool,
    mut on_segment: impl FnMut(&Controller),
) -> Result<Executed, SimError> {
    let id = request.motion.as_ref().map(|m| m.robot_id.clone()).unwrap_or_default();
    let mut stream = within("execute", client.execute(request)).await??;
    let mut robot = Controller::new(id, realtime);
    while let Some(seg) = within("a segment", stream.next()).await? {
        robot.push(&seg?)?;
        on_segment(&robot);
    }
    Ok(robot.finish())
}

/// The obstacle-free trajectory of a motion (the server's plan, no avoidance, no scene).
pub(crate) async fn free_plan(
    client: &DmpClient,
    motion: &v1::MotionSpec,
    dt: f64,
) -> Result<Trajectory, SimError> {
    Ok(free_pose_plan(client, motion, dt).await?.0)
}

/// [`free_plan`] with a pose run's orientations, `[x, y, z, w]` per row (empty for a position run).
pub(crate) async fn free_pose_plan(
    client: &DmpClient,
    motion: &v1::MotionSpec,
    dt: f64,
) -> Result<(Trajectory, Vec<[f64; 4]>), SimError> {
    let mut m = motion.clone();
    m.avoidance = Some(avoidance(dmp::Method::None));
    m.ignore_scene = true;
    m.extra_obstacles.clear();
    let plan = within("plan", client.plan(v1::PlanRequest { motion: Some(m), dt, duration: 0.0 })).await??;
    let seg = plan.trajectory.ok_or_else(|| SimError::protocol("the plan has no trajectory".into()))?;
    let mut s = dmp_client::setpoints::Setpoints::new();
    s.push(&seg)?;
    let q = s.orientations().map(|o| pose::rows(&o.q)).unwrap_or_default();
    Ok((s.into_trajectory(), q))
}

/// The message of an avoidance method (relative velocity on, the server's default boundary samples).
pub(crate) fn avoidance(method: dmp::Method) -> v1::Avoidance {
    dmp_proto::avoidance::avoidance_to_proto(&dmp::Avoidance::new(method), 0)
}

/// Streams a group's execution to its end, one [`Controller`] per member (in request order).
pub(crate) async fn execute_group(
    client: &DmpClient,
    request: v1::ExecuteGroupRequest,
    realtime: bool,
) -> Result<Vec<Executed>, SimError> {
    let mut robots: Vec<Controller> = request
        .members
        .iter()
        .map(|m| Controller::new(m.motion.as_ref().map(|m| m.robot_id.clone()).unwrap_or_default(), realtime))
        .collect();
    let mut stream = within("execute group", client.execute_group(request)).await??;
    while let Some(group) = within("a group segment", stream.next()).await? {
        let group = group?;
        if group.segments.len() != robots.len() {
            return Err(SimError::protocol(format!(
                "a group step has {} segments for {} members",
                group.segments.len(),
                robots.len()
            )));
        }
        for (robot, seg) in robots.iter_mut().zip(&group.segments) {
            robot.push(seg)?;
        }
    }
    Ok(robots.into_iter().map(Controller::finish).collect())
}
