//! The Panda pick and place (the paper's section on the Panda): move the gripper to the ring, then carry the ring to
//! the green peg past the red peg, 3-D at 1 kHz, as pose runs: the gripper's orientation turns with it. Then the
//! Panda carries a bar through a gap, turning it (`super::panda_bar`).
//!
//! # Geometry (metres, the robot's base frame, `z` up)
//! - Board: a box of centre `(0.5, 0, 0.01)` and half-extents `(0.15, 0.25, 0.01)` (top at `z = 0.02`).
//! - Red peg: a cylinder of radius 0.01 and height 0.12 standing on the board at `(0.5, 0)` (top at `z = 0.14`).
//! - Green peg: the same at `(0.55, 0.17)`.
//! - Ring: outer radius `RING_RADIUS`, on a stand, grasped at its centre `(0.45, -0.17, 0.06)`.
//! - Home: `(0.30, -0.40, 0.35)`; place: `(0.55, 0.17, 0.20)`, above the green peg.
//!
//! # Orientation (the gripper's frame in the base's, `[x, y, z, w]`)
//! - Home: `Q_HOME`, the base's frame.
//! - The ring stands upright on its stand, its axis (the tool's `z`) along `-y`: the gripper grasps it turned a
//!   quarter about `x` ([`Q_GRASP`]).
//! - To go onto the green peg the ring lies flat, its axis along the peg's (`z`), here turned 30° about `z`
//!   ([`Q_PLACE`]): the carry turns it by 93.8°.
//!
//! Each primitive is a pose primitive, learned from a demonstration whose orientation turns from the start's to the
//! goal's on the same minimum-jerk profile as the position (`super::demonstration::min_jerk_turn`); each run gives
//! its start and goal orientation (`MotionSpec.start_orientation`, `goal_orientation`), the carry from where the
//! move to the ring actually stopped.
//!
//! The straight line from the ring to the place crosses `y = 0` at `(0.50, 0, 0.13)`: through the red peg.
//!
//! # The planner's view
//! The pegs are superquadrics of exponents `(1, 1, 2)`, the smallest-volume one through the cylinder's rims
//! (`(r/a)^2 + (h/c)^4 = 1` with `a^2 c` least: `a = r / sqrt(0.8)`, `c = h / 0.2^(1/4)`); the board a rounded box
//! of exponent 2 through its corners (`a_i = h_i 3^(1/4)`). While moving to the ring they are inflated by
//! `GRIPPER_MARGIN`; while carrying, by the ring's radius, and the green peg (the target, which the ring goes onto)
//! is left out. Primitives: `K = 3050`, `alpha = 4`, `D = 2 sqrt(K)` (the paper's), learned by the server from
//! straight minimum-jerk demonstrations of `TAU_REACH` and `TAU_CARRY` seconds. (The paper's null weights give a
//! straight line whose speed peaks right at its start; these start and end at rest.)
//! Moving to the ring uses the dynamic potential (`lambda = 10, eta = 2, beta = 2`); carrying is run twice, with
//! the static (`A = 10, eta = 2`) and the dynamic potential.
//!
//! # The true world
//! The gripper's centre is a point while moving to the ring; while carrying, the ring is its disc, a cylinder of
//! radius `RING_RADIUS` and half-thickness `RING_HALF_THICKNESS` along the tool's `z`, turned with the
//! orientation at every setpoint. The planner inflates the obstacles by the ring's radius, which holds the disc in
//! any orientation, so the orientation follows the DMP (no tool). Clearance is measured with parry against the true
//! box and cylinders. The setpoints must also stay within the Panda's Cartesian limits ([`MAX_SPEED`],
//! [`MAX_ACCELERATION`], [`MAX_JERK`]) and angular ones (the arm's profile, `super::panda_arm`), which the
//! report's peaks are checked against (`super::pose`).

use dmp::Method;
use dmp::avoidance::{DynamicVolumetric, StaticVolumetric};
use dmp_client::grpc::DmpClient;
use dmp_proto::obstacle_json::JsonObstacle;

use super::panda_arm::{PROFILE, PoseRun, ROBOT, learn};
use super::profile::put_profile;
use super::report::{CartesianLimits, SimReport};
use super::world::{Body, SolidShape};
use super::{SimOptions, server_robot, superquadric};
use crate::error::SimError;

/// Outer radius of the ring.
pub(crate) const RING_RADIUS: f64 = 0.025;
/// Half the ring's thickness.
pub(crate) const RING_HALF_THICKNESS: f64 = 0.004;
/// The gripper's orientation at home (the frame of the base).
pub(crate) const Q_HOME: [f64; 4] = [0.0, 0.0, 0.0, 1.0];
/// The gripper's orientation grasping the ring upright on its stand: a quarter turn about `x` (the ring's axis,
/// the tool's `z`, along `-y`).
pub const Q_GRASP: [f64; 4] = [std::f64::consts::FRAC_1_SQRT_2, 0.0, 0.0, std::f64::consts::FRAC_1_SQRT_2];
/// The orientation placing it: flat (its axis along `z`, the peg's), turned 30° about `z`.
pub const Q_PLACE: [f64; 4] = [0.0, 0.0, 0.258_819_045_102_520_74, 0.965_925_826_289_068_3];
/// Inflation of the obstacles while the bare gripper moves.
pub(crate) const GRIPPER_MARGIN: f64 = 0.01;
/// Time scale of the move to the ring (the duration of its demonstration), seconds.
pub(crate) const TAU_REACH: f64 = 2.0;
/// Time scale of the carry, seconds: slow enough that going round the red peg stays within the Panda's limits.
/// The path hardly depends on `tau` and accelerations scale about as `1 / tau^2`: the carry with the dynamic
/// potential peaked at 49 m/s^2 with a 2 s carry, 20 m/s^2 with 3 s and 9.7 m/s^2 with 4.5 s.
pub(crate) const TAU_CARRY: f64 = 4.5;
/// The Panda's Cartesian limits of its end effector (Franka Control Interface): speed, m/s.
pub const MAX_SPEED: f64 = 1.7;
/// Acceleration, m/s^2.
pub const MAX_ACCELERATION: f64 = 13.0;
/// Jerk, m/s^3.
pub const MAX_JERK: f64 = 6500.0;

const HOME: [f64; 3] = [0.30, -0.40, 0.35];
const RING: [f64; 3] = [0.45, -0.17, 0.06];
const PLACE: [f64; 3] = [0.55, 0.17, 0.20];
const BOARD_C: [f64; 3] = [0.5, 0.0, 0.01];
const BOARD_H: [f64; 3] = [0.15, 0.25, 0.01];
const PEG_R: f64 = 0.01;
const PEG_HH: f64 = 0.06;
const RED: [f64; 3] = [0.5, 0.0, 0.08];
const GREEN: [f64; 3] = [0.55, 0.17, 0.08];

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
pub(super) fn world() -> Vec<Body> {
    vec![
        Body::new("board", SolidShape::Cuboid { half: BOARD_H }, &BOARD_C),
        Body::new("red-peg", SolidShape::CylinderZ { radius: PEG_R, half_height: PEG_HH }, &RED),
        Body::new("green-peg", SolidShape::CylinderZ { radius: PEG_R, half_height: PEG_HH }, &GREEN),
    ]
}

/// Runs the pick and place: the move to the ring, then both carries (at once: they are alternatives), then the bar
/// through the gap ([`super::panda_bar`]).
pub(crate) async fn run(client: &DmpClient, options: &SimOptions) -> Result<SimReport, SimError> {
    learn(client, "move-to-ring", &HOME, &RING, (Q_HOME, Q_GRASP), TAU_REACH, 3050.0).await?;
    learn(client, "carry", &RING, &PLACE, (Q_GRASP, Q_PLACE), TAU_CARRY, 3050.0).await?;
    put_profile(client, &server_robot(ROBOT), &PROFILE, None).await?;
    let dynamic = Method::DynamicVolumetric(DynamicVolumetric { lambda: 10.0, beta: 2.0, eta: 2.0 });
    let to_ring = PoseRun {
        key: "move-to-ring",
        title: "Panda: move to ring, turning the gripper (dynamic potential)",
        primitive: "move-to-ring",
        tau: TAU_REACH,
        start: HOME.to_vec(),
        goal: RING.to_vec(),
        start_q: Q_HOME,
        goal_q: Q_GRASP,
        method: dynamic,
        obstacles: vec![
            board(GRIPPER_MARGIN),
            peg("red-peg", &RED, GRIPPER_MARGIN),
            peg("green-peg", &GREEN, GRIPPER_MARGIN),
        ],
        body: SolidShape::Point,
        body_name: "the gripper's centre (a point)",
        tool: None,
        outline: None,
        world,
    };
    let mut report = SimReport::new("panda", options.realtime);
    report.limits =
        Some(CartesianLimits { speed: MAX_SPEED, acceleration: MAX_ACCELERATION, jerk: MAX_JERK });
    report.notes.push(
        "geometry and gains: see client/sim/src/robots/panda.rs (board box, red and green pegs as cylinders; \
         pegs planned as superquadrics (1, 1, 2), board as a rounded box of exponent 2) and panda_bar.rs"
            .into(),
    );
    report.notes.push(format!(
        "the Panda's Cartesian limits: {MAX_SPEED} m/s, {MAX_ACCELERATION} m/s^2, {MAX_JERK} m/s^3, and {} rad/s, \
         {} rad/s^2, {} rad/s^3 (peaks and finite differences must stay within them)",
        PROFILE.max_angular_speed, PROFILE.max_angular_acceleration, PROFILE.max_angular_jerk
    ));
    report.notes.push(
        "orientation: every Panda run is a pose run; the gripper turns a quarter about x to grasp the ring standing \
         on its stand, and the carry lays it flat to go onto the green peg; the ring's clearance is its true disc's \
         (a cylinder of its outer radius and thickness) turned with the orientation"
            .into(),
    );
    let moved = to_ring.run(client, options).await?;
    to_ring.record(client, options, &moved, &mut report).await?;
    // Carry from where the gripper actually stopped, as it is turned.
    if moved.traj.is_empty() {
        return Err(SimError::protocol("the move to the ring streamed no setpoint".into()));
    }
    let grasp = super::report::position(&moved.traj, moved.traj.len() - 1).to_vec();
    let grasp_q = moved
        .orientations
        .as_ref()
        .and_then(|o| o.q.rchunks_exact(4).next())
        .map_or(Q_GRASP, |q| [q[0], q[1], q[2], q[3]]);
    let carry = |key, title, method| PoseRun {
        key,
        title,
        primitive: "carry",
        tau: TAU_CARRY,
        start: grasp.clone(),
        goal: PLACE.to_vec(),
        start_q: grasp_q,
        goal_q: Q_PLACE,
        method,
        obstacles: vec![board(RING_RADIUS), peg("red-peg", &RED, RING_RADIUS)],
        body: SolidShape::CylinderZ { radius: RING_RADIUS, half_height: RING_HALF_THICKNESS },
        body_name: "the ring's disc (a cylinder of its outer radius and thickness)",
        tool: None,
        outline: Some((vec![RING_RADIUS, RING_RADIUS, RING_HALF_THICKNESS], vec![1.0, 1.0, 4.0])),
        world,
    };
    let carry_static = carry(
        "carry-static",
        "Panda: carry the ring past the red peg, laying it flat (static potential)",
        Method::StaticVolumetric(StaticVolumetric { a: 10.0, eta: 2.0 }),
    );
    let carry_dynamic = carry(
        "carry-dynamic",
        "Panda: carry the ring past the red peg, laying it flat (dynamic potential)",
        dynamic,
    );
    // One after the other: a robot executes one stream at a time.
    let a = carry_static.run(client, options).await?;
    let b = carry_dynamic.run(client, options).await?;
    carry_static.record(client, options, &a, &mut report).await?;
    carry_dynamic.record(client, options, &b, &mut report).await?;
    super::panda_bar::run(client, options, &mut report).await?;
    Ok(report)
}
