//! The Panda carries a 0.6 m bar through the gap between two rails: the `scenarios/bar-through-gap/` experiment
//! (its tool, its planner's obstacles, its gains) on the Panda, through the server and within the Panda's limits.
//! Held across the gap the bar cannot pass; the server's obstacle-aware orientation (the held tool's control
//! points pushed by the rails' ends, their moments turning it) turns it upright, and the DMP turns it back once it
//! is through.
//!
//! # Geometry (metres, the robot's base frame, `z` up)
//! - Rails: boxes of half-extents [`RAIL_HALF`] along `y` (the way the bar goes), centred at `(0.5 ∓ 0.2, 0, 0.4)`:
//!   [`GAP`] between them. (The scenario's pegs lie along its motion too: the bar meets their ends.)
//! - The bar: a box of `0.6 x 0.02 x 0.02` along the tool's `x`, held at its middle (its true shape).
//! - The bar's centre goes from `(0.5, -0.45, 0.4)` to `(0.5, 0.45, 0.4)`, the bar across the gap, tilted 10° about
//!   `y` (so that the way it turns is not a tie), at the start and at the goal. To pass it must turn about `y`
//!   towards upright.
//!
//! # The planner's view (the scenario's)
//! - Rails: superquadrics of semi-axes `(0.065, 0.225, 0.065)` and exponents `(1, 4, 1)` (the scenario's pegs, laid
//!   along `y`), which hold the boxes (`2 (0.04 / 0.065)^2 + (0.185 / 0.225)^8 = 0.97 <= 1`).
//! - Tool: a superquadric of semi-axes `(0.3, 0.01, 0.01)` and exponents `(4, 4, 4)`, sampled on its axis
//!   (`MotionSpec.tool.axis`).
//! - Static volumetric potential, `A = 10`, `eta = 1`; `K = 1050`, `N = 50`, `alpha = 4`, learned from a straight
//!   minimum-jerk demonstration of `TAU_BAR` seconds at a fixed orientation.
//! - The Panda's profile in its robot record: where the avoidance would exceed it, the server slows the phase.

use dmp::Method;
use dmp::avoidance::StaticVolumetric;
use dmp_client::grpc::DmpClient;
use dmp_proto::obstacle_json::JsonObstacle;
use dmp_proto::v1;

use super::panda_arm::{PoseRun, ROBOT, learn};
use super::pose::about;
use super::report::SimReport;
use super::world::{Body, SolidShape};
use super::{SimOptions, superquadric};
use crate::error::SimError;

/// Half-extents of the true rails.
pub const RAIL_HALF: [f64; 3] = [0.04, 0.185, 0.04];
/// Distance of each rail's axis from the middle of the gap.
pub(crate) const RAIL_OFFSET: f64 = 0.2;
/// The free gap between the true rails.
pub const GAP: f64 = 2.0 * (RAIL_OFFSET - RAIL_HALF[0]);
/// Half the bar's length.
pub(crate) const BAR_HALF_LENGTH: f64 = 0.3;
/// Half the bar's thickness.
pub const BAR_HALF_THICKNESS: f64 = 0.01;
/// Time scale of the carry (the duration of its demonstration), seconds.
pub(crate) const TAU_BAR: f64 = 3.0;

const START: [f64; 3] = [0.5, -0.45, 0.4];
const GOAL: [f64; 3] = [0.5, 0.45, 0.4];

fn rail_centers() -> [[f64; 3]; 2] {
    [[0.5 - RAIL_OFFSET, 0.0, 0.4], [0.5 + RAIL_OFFSET, 0.0, 0.4]]
}

/// The true rails.
fn world() -> Vec<Body> {
    let [a, b] = rail_centers();
    let rail = SolidShape::Cuboid { half: RAIL_HALF };
    vec![Body::new("rail-left", rail, &a), Body::new("rail-right", rail, &b)]
}

/// The bar's orientation at the start and the goal: across the gap, tilted 10° about `y`.
pub(crate) fn bar_orientation() -> [f64; 4] {
    about([0.0, 1.0, 0.0], 10f64.to_radians())
}

/// Carries the bar through the gap and adds the run (`panda/carry-bar`) to `report`.
pub(crate) async fn run(
    client: &DmpClient,
    options: &SimOptions,
    report: &mut SimReport,
) -> Result<(), SimError> {
    let q = bar_orientation();
    learn(client, "carry-bar", &START, &GOAL, (q, q), TAU_BAR, 1050.0).await?;
    let [a, b] = rail_centers();
    let rails: Vec<JsonObstacle> = [("rail-left", a), ("rail-right", b)]
        .iter()
        .map(|(id, c)| superquadric(id, c, vec![0.065, 0.225, 0.065], vec![1.0, 4.0, 1.0], 0.0))
        .collect();
    let semi = vec![BAR_HALF_LENGTH, BAR_HALF_THICKNESS, BAR_HALF_THICKNESS];
    let exponents = vec![4.0; 3];
    let tool = v1::Tool {
        shape: Some(v1::Superquadric { semi_axes: semi.clone(), exponents: exponents.clone() }),
        offset: Vec::new(),
        axis: true,
        control_points: 0,
    };
    let bar = PoseRun {
        key: "carry-bar",
        title: "Panda: carry a 0.6 m bar between two rails, turning it (static potential)",
        primitive: "carry-bar",
        tau: TAU_BAR,
        start: START.to_vec(),
        goal: GOAL.to_vec(),
        start_q: q,
        goal_q: q,
        method: Method::StaticVolumetric(StaticVolumetric { a: 10.0, eta: 1.0 }),
        obstacles: rails,
        body: SolidShape::Cuboid { half: [BAR_HALF_LENGTH, BAR_HALF_THICKNESS, BAR_HALF_THICKNESS] },
        body_name: "the bar (a 0.6 x 0.02 x 0.02 m box)",
        tool: Some(tool),
        outline: Some((semi, exponents)),
        world,
    };
    report.notes.push(format!(
        "{ROBOT}/carry-bar: a 0.6 m bar carried through the {GAP:.2} m gap between two rails (scenarios/bar-through-gap \
         on the Panda: see client/sim/src/robots/panda_bar.rs); held across, the bar only passes turned"
    ));
    let exec = bar.run(client, options).await?;
    bar.record(client, options, &exec, report).await
}
