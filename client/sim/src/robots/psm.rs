//! The da Vinci peg transfer (the paper's section on the da Vinci): two patient-side manipulators, PSM1 on the right
//! and PSM2 on the left, 3-D per arm at 1 kHz like the real arms' controllers. PSM1 picks the ring and brings it to
//! the centre of the board, hands it over, and PSM2 places it on the target peg. The pegs are obstacles; the jaws
//! turn towards the handover (`super::psm_stage`), and where the arms cross they run on one shared phase (one 6-D
//! DMP), each a moving obstacle for the other.
//!
//! # Geometry (metres, a frame common to both arms, `x` right, `y` away from the camera, `z` up)
//! - Board: a box of centre `(0, 0, -0.003)` and half-extents `(0.08, 0.06, 0.003)` (top at `z = 0`).
//! - Pegs: cylinders of radius [`PEG_RADIUS`] and height `2 PEG_HALF_HEIGHT` (top at `z = 0.03`) standing
//!   on the board: `peg-1` at `(0.0264, -0.0141)`, on PSM1's way from the ring to the centre; `peg-2` at
//!   `(-0.0073, -0.0195)`, on PSM2's way from the centre to the target; `target-peg` at `(-0.02, -0.04)`.
//!   `peg-1` and `peg-2` sit 3 mm beside the straight lines, so that the way around is not a tie.
//! - Ring: outer radius `RING_RADIUS`, inner radius [`RING_INNER_RADIUS`], on a stand, grasped at its centre
//!   `(0.05, -0.03, 0.015)`.
//! - Each arm's controlled point is the centre of its jaws; the jaws are a cylinder of radius `JAW_RADIUS` and
//!   length `2 JAW_HALF_LENGTH` along the jaws' `z`, upright at home, turned with the jaws' orientation
//!   (`super::psm_stage`: PSM1 tilts them 20° about `y` and rolls them 45° to grasp the ring, both arms roll them a
//!   quarter turn to open towards each other at the handover, PSM2 half of it at its standby point).
//! - Handover: the centre `CENTRE`; PSM1 holds the ring [`HANDOVER_OFFSET`] in front of it, PSM2 grasps it the
//!   same distance behind (the jaws then have 4 mm between them).
//!
//! # Stages (each starts where the previous one ended; the first two as two pose runs, one per arm, the jaws
//! turning; the third as one `ExecuteGroup`, PSM1 first, the jaws held: `super::psm_stage`)
//! 1. `move-to-ring`: PSM1 from its home `(0.07, 0.02, 0.05)` to the ring; PSM2 from its home
//!    `(-0.06, 0.04, 0.05)` to a standby point `(-0.02, 0.025, 0.03)` behind the centre, on its side.
//! 2. `transfer`: PSM1 carries the ring to the handover point in front of the centre, past `peg-1`; PSM2 approaches
//!    the handover point behind the centre. At the end both are at rest there: the handover (PSM2 closes its
//!    jaws, PSM1 opens its own) happens at that time.
//! 3. `move-to-peg`: PSM2 carries the ring past `peg-2` to `PLACE_HEIGHT` above the target peg (the ring's hole
//!    centred on the peg: released, it drops onto it) while PSM1 retreats to `(0.02, 0.045, 0.05)`, behind and
//!    above. The two cross each other's way (PSM1 goes back, PSM2 forward, from 9 mm apart): without the
//!    robot term their jaws collide.
//!
//! # Primitives
//! Every arm's motion of every stage is learned with `learn` from a human-like demonstration between the
//! nominal start and goal: a minimum-jerk curve (Flash and Hogan) with a lift of `LIFT` (`16 u^2 (1 - u)^2`) in
//! `z`, `TAU` long, sampled at 100 Hz; `N = 50`, `K = 3050`, `D = 2 sqrt(K)`, `alpha = 4`. The first two
//! stages' are pose primitives: their demonstrations turn the jaws from the stage's start orientation to its goal's
//! on the same minimum-jerk profile (`super::demonstration::min_jerk_turn`).
//!
//! # The planner's view
//! Pegs are superquadrics of exponents `(1, 1, 2)` through the cylinders' rims, the board a rounded box of
//! exponent 2 through its corners (as in `super::panda`), with the static potential (`A = STATIC_A`, `eta = 2`;
//! the paper found that the dynamic one did not converge on the da Vinci). They are inflated by the jaws' half
//! length `JAW_HALF_LENGTH` in `move-to-ring`, and by the ring's radius while a ring is carried; one inflation
//! holds for the whole group, so the largest one. The target peg is left out of `move-to-peg` (the ring goes
//! onto it). Each arm's footprint, which the other arm's controlled point avoids with the dynamic potential
//! (`lambda = ROBOT_LAMBDA`, `beta = 2`, `eta = ROBOT_ETA`: it acts only while the arms close in, so
//! that the handover still converges), is the smallest ellipsoid around the set of positions where the two jaws
//! touch (a cylinder of twice the jaw's radius and length): semi-axes `sqrt(3/2) 2 r` and `sqrt(3) 2 h`.
//!
//! The gains are small because the scene is: `grad C` grows as the shapes shrink. The dynamic term brakes like
//! a damping of about `lambda eta C^-(eta + 1) |grad C| / tau`, which near a 6 mm footprint reaches RK4's
//! stability limit at 1 kHz for `lambda` of a few units: the setpoints then break the continuity bounds.
//!
//! # The true world
//! Clearance is measured with parry against the true board and cylinders: of the jaws (turned), or while carrying
//! of the ring (a ball of `RING_RADIUS` around the controlled point, which also holds the jaws); between the arms,
//! of the two jaws, both turned (at the handover the ring touches both on purpose). Each stage is also run without any avoidance
//! (the free plan of the figures) and without the robot term only; their true clearances are reported as
//! metrics (`<arm>/<stage>/free_min_clearance_m/<id>`, and `<arm>/<stage>/no_robot_term_min_clearance_m/<other
//! arm>`): they show what avoidance prevented.

use dmp::Method;
use dmp::avoidance::DynamicVolumetric;
use dmp_proto::obstacle_json::JsonObstacle;
use dmp_proto::v1;

use super::demonstration::min_jerk;
use super::superquadric;
use super::world::{Body, SolidShape, robot_body};

/// Control period: 1 kHz.
pub(crate) const DT: f64 = 1e-3;
/// The limit profile of a PSM, in each arm's record.
pub(crate) const PROFILE: dmp::Limits = dmp::Limits::DVRK_PSM;
/// Duration of every demonstration (and time scale of every stage), seconds.
pub(crate) const TAU: f64 = 1.5;
/// Radius of the jaws' cylinder.
pub(crate) const JAW_RADIUS: f64 = 0.0025;
/// Half length of the jaws' cylinder (1 cm jaws).
pub(crate) const JAW_HALF_LENGTH: f64 = 0.005;
/// Outer radius of the ring.
pub(crate) const RING_RADIUS: f64 = 0.007;
/// Inner radius of the ring (its hole).
pub const RING_INNER_RADIUS: f64 = 0.004;
/// Radius of the pegs.
pub const PEG_RADIUS: f64 = 0.002;
/// Half height of the pegs.
pub(crate) const PEG_HALF_HEIGHT: f64 = 0.015;
/// Height of the lift of the demonstrations.
pub(crate) const LIFT: f64 = 0.006;
/// The centre of the board, where the ring changes hands.
pub(crate) const CENTRE: [f64; 3] = [0.0, 0.0, 0.02];
/// Distance of each arm's jaws from `CENTRE` at the handover (PSM1 in front, PSM2 behind).
pub const HANDOVER_OFFSET: f64 = 0.0045;
/// Height of the ring's centre above the target peg's top when it is released.
pub(crate) const PLACE_HEIGHT: f64 = 0.009;
/// Gain `A` of the static potential of the pegs and the board.
pub(crate) const STATIC_A: f64 = 1.0;
/// Gain `lambda` of the dynamic potential between the arms.
pub(crate) const ROBOT_LAMBDA: f64 = 0.5;
/// Exponent `eta` of the dynamic potential between the arms.
pub(crate) const ROBOT_ETA: f64 = 2.0;

pub(super) const PSM1: &str = "psm1";
pub(super) const PSM2: &str = "psm2";
/// The robots of this simulation (the server knows them as [`server_robot`] of these).
pub(crate) const ROBOT_IDS: &[&str] = &[PSM1, PSM2];
pub(super) const HOME1: [f64; 3] = [0.07, 0.02, 0.05];
pub(super) const HOME2: [f64; 3] = [-0.06, 0.04, 0.05];
pub(super) const STANDBY2: [f64; 3] = [-0.02, 0.025, 0.03];
pub(super) const RING: [f64; 3] = [0.05, -0.03, 0.015];
pub(super) const RETREAT1: [f64; 3] = [0.02, 0.045, 0.05];
const BOARD_C: [f64; 3] = [0.0, 0.0, -0.003];
const BOARD_H: [f64; 3] = [0.08, 0.06, 0.003];
const PEG_1: [f64; 2] = [0.0264, -0.0141];
const PEG_2: [f64; 2] = [-0.0073, -0.0195];
pub(super) const TARGET: [f64; 2] = [-0.02, -0.04];

pub(super) fn handover(arm: usize) -> Vec<f64> {
    let dy = if arm == 0 { -HANDOVER_OFFSET } else { HANDOVER_OFFSET };
    vec![CENTRE[0], CENTRE[1] + dy, CENTRE[2]]
}

pub(super) fn place() -> Vec<f64> {
    vec![TARGET[0], TARGET[1], 2.0 * PEG_HALF_HEIGHT + PLACE_HEIGHT]
}

fn peg_center(xy: [f64; 2]) -> [f64; 3] {
    [xy[0], xy[1], PEG_HALF_HEIGHT]
}

const PEGS: [(&str, [f64; 2]); 3] = [("peg-1", PEG_1), ("peg-2", PEG_2), ("target-peg", TARGET)];

/// A peg's superquadric of exponents (1, 1, 2) through the cylinder's rims (see `super::panda`).
fn peg(id: &str, xy: [f64; 2], margin: f64) -> JsonObstacle {
    let a = PEG_RADIUS / 0.8f64.sqrt();
    let c = PEG_HALF_HEIGHT / 0.2f64.powf(0.25);
    superquadric(id, &peg_center(xy), vec![a, a, c], vec![1.0, 1.0, 2.0], margin)
}

fn board(margin: f64) -> JsonObstacle {
    let k = 3f64.powf(0.25);
    superquadric("board", &BOARD_C, BOARD_H.iter().map(|h| h * k).collect(), vec![2.0; 3], margin)
}

/// The planner's obstacles of a stage: the board and the pegs but `skip`, inflated by `margin`.
pub(super) fn planned(margin: f64, skip: Option<&str>) -> Vec<JsonObstacle> {
    let mut v = vec![board(margin)];
    v.extend(PEGS.iter().filter(|(id, _)| Some(*id) != skip).map(|(id, xy)| peg(id, *xy, margin)));
    v
}

/// The true shapes.
pub(super) fn world() -> Vec<Body> {
    let mut v = vec![Body::new("board", SolidShape::Cuboid { half: BOARD_H }, &BOARD_C)];
    for (id, xy) in PEGS {
        let solid = SolidShape::CylinderZ { radius: PEG_RADIUS, half_height: PEG_HALF_HEIGHT };
        v.push(Body::new(id, solid, &peg_center(xy)));
    }
    v
}

pub(super) fn jaws(id: &str) -> Body {
    robot_body(id, SolidShape::CylinderZ { radius: JAW_RADIUS, half_height: JAW_HALF_LENGTH })
}

/// Semi-axes of each arm's footprint (module documentation).
pub(crate) fn footprint_semi_axes() -> [f64; 3] {
    let (r, h) = (2.0 * JAW_RADIUS, 2.0 * JAW_HALF_LENGTH);
    [1.5f64.sqrt() * r, 1.5f64.sqrt() * r, 3f64.sqrt() * h]
}

pub(super) fn footprint() -> v1::Superquadric {
    v1::Superquadric { semi_axes: footprint_semi_axes().to_vec(), exponents: vec![1.0; 3] }
}

/// The demonstration of a motion from `start` to `goal`: minimum jerk with a lift of [`LIFT`], [`TAU`] long, at
/// 100 Hz.
pub(crate) fn demonstration(start: &[f64], goal: &[f64]) -> (Vec<f64>, Vec<Vec<f64>>) {
    min_jerk(start, goal, TAU, LIFT, 0.01)
}

/// How the arms avoid each other on a shared phase (module documentation).
pub(super) fn robot_method() -> Method {
    Method::DynamicVolumetric(DynamicVolumetric { lambda: ROBOT_LAMBDA, beta: 2.0, eta: ROBOT_ETA })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robots::clearance::distance;

    #[test]
    fn demonstration_starts_and_ends_at_rest_with_a_lift() {
        let (t, rows) = demonstration(&RING, &handover(0));
        assert_eq!(t.len(), rows.len());
        assert!((t[t.len() - 1] - TAU).abs() < 1e-12);
        assert!(distance(&rows[0], &RING) < 1e-12);
        assert!(distance(&rows[rows.len() - 1], &handover(0)) < 1e-12);
        // Half way: half the way, plus the whole lift.
        let mid = &rows[rows.len() / 2];
        let line_z = 0.5 * (RING[2] + CENTRE[2]);
        assert!((mid[2] - line_z - LIFT).abs() < 1e-12, "{mid:?}");
    }

    #[test]
    fn footprint_holds_every_contact_of_the_jaws() {
        // The jaws touch when the other arm's point is in a cylinder of twice their radius and length: its rims
        // are on the ellipsoid, the rest inside.
        let [a, _, c] = footprint_semi_axes();
        let (r, h) = (2.0 * JAW_RADIUS, 2.0 * JAW_HALF_LENGTH);
        assert!(((r / a).powi(2) + (h / c).powi(2) - 1.0).abs() < 1e-12);
        // The jaws have room at the handover: the points are outside each other's footprint.
        let d = distance(&handover(0), &handover(1));
        assert!(d > a && d > 2.0 * JAW_RADIUS, "{d}");
    }
}
