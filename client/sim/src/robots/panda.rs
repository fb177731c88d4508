//! The Panda pick and place (the paper's section on the Panda): move the gripper to the ring, then carry the ring to
//! the green peg past the red peg, 3-D at 1 kHz.
//!
//! # Geometry (metres, the robot's base frame, `z` up)
//! - Board: a box of centre `(0.5, 0, 0.01)` and half-extents `(0.15, 0.25, 0.01)` (top at `z = 0.02`).
//! - Red peg: a cylinder of radius 0.01 and height 0.12 standing on the board at `(0.5, 0)` (top at `z = 0.14`).
//! - Green peg: the same at `(0.55, 0.17)`.
//! - Ring: outer radius [`RING_RADIUS`], on a stand, grasped at its centre `(0.45, -0.17, 0.06)`.
//! - Home: `(0.30, -0.40, 0.35)`; place: `(0.55, 0.17, 0.20)`, above the green peg.
//!
//! The straight line from the ring to the place crosses `y = 0` at `(0.50, 0, 0.13)`: through the red peg.
//!
//! # The planner's view
//! The pegs are superquadrics of exponents `(1, 1, 2)`, the smallest-volume one through the cylinder's rims
//! (`(r/a)^2 + (h/c)^4 = 1` with `a^2 c` least: `a = r / sqrt(0.8)`, `c = h / 0.2^(1/4)`); the board a rounded box
//! of exponent 2 through its corners (`a_i = h_i 3^(1/4)`). While moving to the ring they are inflated by
//! [`GRIPPER_MARGIN`]; while carrying, by the ring's radius, and the green peg (the target, which the ring goes onto)
//! is left out. Primitives: `K = 3050`, `alpha = 4`, `D = 2 sqrt(K)` (the paper's), learned by the server from
//! straight minimum-jerk demonstrations of [`TAU_REACH`] and [`TAU_CARRY`] seconds. (The paper's null weights give a
//! straight line whose speed peaks right at its start; these start and end at rest.)
//! Moving to the ring uses the dynamic potential (`lambda = 10, eta = 2, beta = 2`); carrying is run twice, with
//! the static (`A = 10, eta = 2`) and the dynamic potential.
//!
//! # The true world
//! The gripper's centre is a point while moving to the ring; while carrying, the ring is the ball of radius
//! [`RING_RADIUS`] around it. Clearance is measured with parry against the true box and cylinders. The setpoints
//! must also stay within the Panda's Cartesian limits ([`MAX_SPEED`], [`MAX_ACCELERATION`], [`MAX_JERK`]), which
//! the report's peaks are checked against.

use super::profile::put_profile;
use dmp_client::grpc::DmpClient;
use dmp_proto::obstacle_json::JsonObstacle;
use dmp_proto::v1;

use super::demonstration::min_jerk;
use super::report::{Figure, SimReport, measure, write_figure};
use super::robot::Executed;
use super::world::{Body, Solid, robot_body};
use super::{Method, SimOptions, avoidance, execute, free_plan, pacing, server_robot, superquadric, within};
use crate::error::SimError;

/// Control period: 1 kHz.
pub const DT: f64 = 1e-3;
/// Outer radius of the ring.
pub const RING_RADIUS: f64 = 0.025;
/// Inflation of the obstacles while the bare gripper moves.
pub const GRIPPER_MARGIN: f64 = 0.01;
/// Time scale of the move to the ring (the duration of its demonstration), seconds.
pub const TAU_REACH: f64 = 2.0;
/// Time scale of the carry, seconds: slow enough that going round the red peg stays within the Panda's limits.
/// The path hardly depends on `tau` and accelerations scale about as `1 / tau^2`: the carry with the dynamic
/// potential peaked at 49 m/s^2 with a 2 s carry, 20 m/s^2 with 3 s and 9.7 m/s^2 with 4.5 s.
pub const TAU_CARRY: f64 = 4.5;
/// The Panda's Cartesian limits of its end effector (Franka Control Interface): speed, m/s.
pub const MAX_SPEED: f64 = 1.7;
/// Acceleration, m/s^2.
pub const MAX_ACCELERATION: f64 = 13.0;
/// Jerk, m/s^3.
pub const MAX_JERK: f64 = 6500.0;
/// The arm's limits, in its robot record: every run keeps them, and the report counts setpoints over them.
pub const PROFILE: dmp::Limits = dmp::Limits::PANDA;

const HOME: [f64; 3] = [0.30, -0.40, 0.35];
const RING: [f64; 3] = [0.45, -0.17, 0.06];
const PLACE: [f64; 3] = [0.55, 0.17, 0.20];
const BOARD_C: [f64; 3] = [0.5, 0.0, 0.01];
const BOARD_H: [f64; 3] = [0.15, 0.25, 0.01];
const PEG_R: f64 = 0.01;
const PEG_HH: f64 = 0.06;
const RED: [f64; 3] = [0.5, 0.0, 0.08];
const GREEN: [f64; 3] = [0.55, 0.17, 0.08];

const ROBOT: &str = "panda";
/// The robots of this simulation (the server knows them as [`server_robot`] of these).
pub const ROBOT_IDS: &[&str] = &[ROBOT];

/// A z-axis cylinder's superquadric of exponents (1, 1, 2) (module documentation).
fn peg(id: &str, center: &[f64], margin: f64) -> JsonObstacle {
    let a = PEG_R / 0.8f64.sqrt();
    let c = PEG_HH / 0.2f64.powf(0.25);
    superquadric(id, center, vec![a, a, c], vec![1.0, 1.0, 2.0], margin)
}

fn board(margin: f64) -> JsonObstacle {
    let k = 3f64.powf(0.25);
    superquadric("board", &BOARD_C, BOARD_H.iter().map(|h| h * k).collect(), vec![2.0; 3], margin)
}

/// The true shapes.
fn world() -> Vec<Body> {
    vec![
        Body::new("board", Solid::Cuboid { half: BOARD_H }, &BOARD_C),
        Body::new("red-peg", Solid::CylinderZ { radius: PEG_R, half_height: PEG_HH }, &RED),
        Body::new("green-peg", Solid::CylinderZ { radius: PEG_R, half_height: PEG_HH }, &GREEN),
    ]
}

/// Learns `name` on the server from a straight minimum-jerk demonstration from `start` to `goal`, `tau` long.
async fn learn(
    client: &DmpClient,
    name: &str,
    start: &[f64],
    goal: &[f64],
    tau: f64,
) -> Result<(), SimError> {
    let (t, rows) = min_jerk(start, goal, tau, 0.0, 0.01);
    let parameters = super::learn_parameters(3050.0);
    within("learn", client.learn(&server_robot(ROBOT), name, &t, &rows, parameters)).await??;
    Ok(())
}

struct Motion {
    key: &'static str,
    title: &'static str,
    primitive: &'static str,
    tau: f64,
    start: Vec<f64>,
    goal: Vec<f64>,
    method: Method,
    obstacles: Vec<JsonObstacle>,
    body: Solid,
}

impl Motion {
    fn spec(&self) -> v1::MotionSpec {
        v1::MotionSpec {
            robot_id: server_robot(ROBOT),
            primitive: self.primitive.into(),
            start: self.start.clone(),
            goal: self.goal.clone(),
            avoidance: Some(avoidance(self.method)),
            extra_obstacles: self.obstacles.iter().map(JsonObstacle::to_proto).collect(),
            // The scene is known in advance: it travels with the request.
            ignore_scene: true,
            ..Default::default()
        }
    }

    async fn run(&self, client: &DmpClient, options: &SimOptions) -> Result<Executed, SimError> {
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

    async fn record(
        &self,
        client: &DmpClient,
        options: &SimOptions,
        exec: &Executed,
        report: &mut SimReport,
    ) -> Result<(), SimError> {
        let body = robot_body(ROBOT, self.body);
        let world = world();
        let r = measure(exec, DT, &self.goal, Some(&PROFILE), &body, &world, &[]);
        report.add(&format!("{ROBOT}/{}", self.key), r);
        let free = free_plan(client, &self.spec(), DT).await?;
        let engine: Vec<dmp::Obstacle> = self
            .obstacles
            .iter()
            .map(JsonObstacle::to_engine)
            .collect::<Result<_, _>>()
            .map_err(|e| SimError::Plot(e.to_string()))?;
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
        };
        write_figure(&options.out, &name, &fig)?;
        report.plots.push(name);
        Ok(())
    }
}

/// Runs the pick and place: the move to the ring, then both carries (at once: they are alternatives).
pub async fn run(client: &DmpClient, options: &SimOptions) -> Result<SimReport, SimError> {
    learn(client, "move-to-ring", &HOME, &RING, TAU_REACH).await?;
    learn(client, "carry", &RING, &PLACE, TAU_CARRY).await?;
    put_profile(client, &server_robot(ROBOT), &PROFILE).await?;
    let dynamic = Method::Dynamic { lambda: 10.0, beta: 2.0, eta: 2.0 };
    let to_ring = Motion {
        key: "move-to-ring",
        title: "Panda: move to ring (dynamic potential)",
        primitive: "move-to-ring",
        tau: TAU_REACH,
        start: HOME.to_vec(),
        goal: RING.to_vec(),
        method: dynamic,
        obstacles: vec![
            board(GRIPPER_MARGIN),
            peg("red-peg", &RED, GRIPPER_MARGIN),
            peg("green-peg", &GREEN, GRIPPER_MARGIN),
        ],
        body: Solid::Point,
    };
    let mut report = SimReport::new("panda", options.realtime);
    report.limits =
        Some(super::html::Limits { speed: MAX_SPEED, acceleration: MAX_ACCELERATION, jerk: MAX_JERK });
    report.notes.push(
        "geometry and gains: see client/sim/src/robots/panda.rs (board box, red and green pegs as cylinders; \
         pegs planned as superquadrics (1, 1, 2), board as a rounded box of exponent 2)"
            .into(),
    );
    report.notes.push(format!(
        "the Panda's Cartesian limits: {MAX_SPEED} m/s, {MAX_ACCELERATION} m/s^2, {MAX_JERK} m/s^3 \
         (peak_speed, peak_acceleration and peak_jerk must stay within them)"
    ));
    let moved = to_ring.run(client, options).await?;
    to_ring.record(client, options, &moved, &mut report).await?;
    // Carry from where the gripper actually stopped.
    if moved.traj.is_empty() {
        return Err(SimError::protocol("the move to the ring streamed no setpoint".into()));
    }
    let grasp = super::report::position(&moved.traj, moved.traj.len() - 1).to_vec();
    let carry = |key, title, method| Motion {
        key,
        title,
        primitive: "carry",
        tau: TAU_CARRY,
        start: grasp.clone(),
        goal: PLACE.to_vec(),
        method,
        obstacles: vec![board(RING_RADIUS), peg("red-peg", &RED, RING_RADIUS)],
        body: Solid::Ball { radius: RING_RADIUS },
    };
    let carry_static = carry(
        "carry-static",
        "Panda: carry the ring past the red peg (static potential)",
        Method::Static { a: 10.0, eta: 2.0 },
    );
    let carry_dynamic =
        carry("carry-dynamic", "Panda: carry the ring past the red peg (dynamic potential)", dynamic);
    // One after the other: a robot executes one stream at a time.
    let a = carry_static.run(client, options).await?;
    let b = carry_dynamic.run(client, options).await?;
    carry_static.record(client, options, &a, &mut report).await?;
    carry_dynamic.record(client, options, &b, &mut report).await?;
    Ok(report)
}
