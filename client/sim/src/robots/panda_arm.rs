//! The Panda arm as the simulations drive it: its control period and limit profile, its pose primitives learned
//! from minimum-jerk demonstrations, and one pose run of it ([`PoseRun`]): requested, executed, measured against
//! the true world and drawn. The pick and place (`super::panda`) and the bar through the gap (`super::panda_bar`)
//! are made of such runs.

use dmp::Method;
use dmp_client::grpc::DmpClient;
use dmp_plot::PoseTrace;
use dmp_proto::obstacle_json::JsonObstacle;
use dmp_proto::v1;

use super::demonstration::{min_jerk, min_jerk_turn};
use super::pose::{add_pose, outline_samples, rows};
use super::report::{Figure, SimReport, measure, write_figure};
use super::robot::Executed;
use super::world::{Body, SolidShape, robot_body};
use super::{SimOptions, avoidance, execute, free_pose_plan, learn_parameters, pacing, server_robot, within};
use crate::error::SimError;

/// Control period: 1 kHz.
pub(crate) const DT: f64 = 1e-3;

/// The arm's limits, in its robot record: every run keeps them, and the report counts setpoints over them.
pub(crate) const PROFILE: dmp::Limits = dmp::Limits::PANDA;

pub(super) const ROBOT: &str = "panda";

/// The robots of this simulation (the server knows them as [`server_robot`] of these).
pub(crate) const ROBOT_IDS: &[&str] = &[ROBOT];

/// Learns the pose primitive `name` on the server from a straight minimum-jerk demonstration from `start` to `goal`,
/// `tau` long, turning from `start_q` to `goal_q` on the same minimum-jerk profile, with stiffness `k`.
#[allow(clippy::too_many_arguments)]
pub(super) async fn learn(
    client: &DmpClient,
    name: &str,
    start: &[f64],
    goal: &[f64],
    (start_q, goal_q): ([f64; 4], [f64; 4]),
    tau: f64,
    k: f64,
) -> Result<(), SimError> {
    let (t, rows) = min_jerk(start, goal, tau, 0.0, 0.01);
    let q = min_jerk_turn(&start_q, &goal_q, tau, 0.01);
    let parameters = learn_parameters(k);
    within("learn", client.learn_pose(&server_robot(ROBOT), name, &t, &rows, &q, parameters)).await??;
    Ok(())
}

/// One motion of the Panda: a pose run from `start` to `goal`, turning from `start_q` to `goal_q`.
pub(super) struct PoseRun {
    pub(crate) key: &'static str,
    pub(crate) title: &'static str,
    pub(crate) primitive: &'static str,
    pub(crate) tau: f64,
    pub(crate) start: Vec<f64>,
    pub(crate) goal: Vec<f64>,
    pub(crate) start_q: [f64; 4],
    pub(crate) goal_q: [f64; 4],
    pub(crate) method: Method,
    pub(crate) obstacles: Vec<JsonObstacle>,
    /// The true shape around the controlled point (turned with the orientation).
    pub(crate) body: SolidShape,
    /// What the body is, for the report.
    pub(crate) body_name: &'static str,
    /// The held tool the server turns around the obstacles (none: the orientation only follows the DMP).
    pub(crate) tool: Option<v1::Tool>,
    /// The shape outlined along the path in the figure (tool frame): none, or a superquadric's semi-axes and
    /// exponents.
    pub(crate) outline: Option<(Vec<f64>, Vec<f64>)>,
    /// The true world.
    pub(crate) world: fn() -> Vec<Body>,
}

impl PoseRun {
    fn spec(&self) -> v1::MotionSpec {
        v1::MotionSpec {
            robot_id: server_robot(ROBOT),
            primitive: self.primitive.into(),
            start: self.start.clone(),
            goal: self.goal.clone(),
            start_orientation: self.start_q.to_vec(),
            goal_orientation: self.goal_q.to_vec(),
            avoidance: Some(avoidance(self.method)),
            extra_obstacles: self.obstacles.iter().map(JsonObstacle::to_proto).collect(),
            // The scene is known in advance: it travels with the request.
            ignore_scene: true,
            tool: self.tool.clone(),
            ..Default::default()
        }
    }

    pub(super) async fn run(&self, client: &DmpClient, options: &SimOptions) -> Result<Executed, SimError> {
        let request = v1::ExecuteRequest {
            motion: Some(self.spec()),
            dt: DT,
            segment_s: 0.01,
            pacing: pacing(options.realtime),
            max_duration_s: 4.0 * self.tau,
            ..Default::default()
        };
        execute(&options.robot_client(client, &server_robot(ROBOT))?, request, options.realtime, |_| {}).await
    }

    pub(super) async fn record(
        &self,
        client: &DmpClient,
        options: &SimOptions,
        exec: &Executed,
        report: &mut SimReport,
    ) -> Result<(), SimError> {
        let body = robot_body(ROBOT, self.body);
        let world = (self.world)();
        let mut r = measure(exec, DT, &self.goal, Some(&PROFILE), &body, &world, &[]);
        add_pose(&mut r, exec, self.goal_q, Some(&PROFILE), self.body_name);
        report.add(&format!("{ROBOT}/{}", self.key), r);
        let (free, free_q) = free_pose_plan(client, &self.spec(), DT).await?;
        let engine: Vec<dmp::Obstacle> = self
            .obstacles
            .iter()
            .map(JsonObstacle::to_engine)
            .collect::<Result<_, _>>()
            .map_err(|e| SimError::Plot(e.to_string()))?;
        let adapted_q = exec.orientations.as_ref().map(|o| rows(&o.q)).unwrap_or_default();
        let surface = match &self.outline {
            Some((semi, exponents)) => outline_samples(semi, exponents)?,
            None => Vec::new(),
        };
        let pose = PoseTrace { orientations: &adapted_q, free_orientations: &free_q, tool_surface: &surface };
        let name = format!("{}.svg", self.key);
        let fig = Figure {
            title: self.title,
            line: (&self.start, &self.goal),
            free: &free,
            adapted: &exec.traj,
            obstacles: &engine,
            robots: &[],
            time: 0.0,
            world: &world,
            seen: &[],
            body: Some(&body),
            method: self.method.name(),
            events: &[],
            pose: (adapted_q.len() == exec.traj.len() && free_q.len() == free.len()).then_some(pose),
        };
        write_figure(&options.out, &name, &fig)?;
        report.plots.push(name);
        Ok(())
    }
}
