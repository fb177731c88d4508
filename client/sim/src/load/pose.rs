//! `--pose`: pose robots at the Panda profile. Each robot's primitive is the load's straight line with three
//! orientation dimensions (a pose primitive, its chart at the identity, those dimensions a null-weight line from 0
//! to 0); the session gives its start and goal orientations, and every goal change gives the other one, so that
//! each leg turns the robot by [`TURN`] about a horizontal axis as it crosses the cell. The session's limits are
//! the Panda's (`dmp::Limits::PANDA`, linear and angular), so the server's limits act on position and orientation.
//!
//! A pose robot's segments must carry the orientations, angular velocities and accelerations of every point
//! ([`dmp_proto::segment_view::SegmentView::has_pose`]): one that does not ends the robot with an error, and its
//! setpoints from then on are not on time.

use std::f64::consts::PI;

use dmp::primitive::OrientationChart;
use dmp_proto::limits::limits_to_proto;
use dmp_proto::v1;

use super::layout::{self, RobotPlan};
use crate::error::SimError;

/// The turn of each leg, radians.
pub(crate) const TURN: f64 = 0.5 * PI;

/// A unit quaternion, `[x, y, z, w]`.
pub(crate) type Quaternion = [f64; 4];

/// The robot's two orientations, in the order of its goals ([`RobotPlan::goals`]): turned by [`TURN`] about x,
/// then back to its start's. The start's is a turn about z by the robot's angle on its circle, so that the robots
/// of a cell face different ways.
pub(crate) fn orientations(robot: &RobotPlan) -> [Quaternion; 2] {
    let a = robot.start[1].atan2(robot.start[0]);
    let (s, c) = (0.5 * a).sin_cos();
    let (u, v) = (0.5 * TURN).sin_cos();
    // Rz(a) ⊗ Rx(TURN).
    let turned = [c * u, s * u, s * v, c * v];
    [turned, [0.0, 0.0, s, c]]
}

/// The pose primitive of a robot: the load's line in position, a null line in the chart at the identity.
pub(crate) fn primitive(robot: &RobotPlan, tau: f64) -> Result<dmp::Primitive, SimError> {
    let mut line = layout::primitive(robot, tau)?;
    let dim = line.dim + 3;
    let (mut start, mut goal) = (line.start.clone(), line.goal.clone());
    start.extend([0.0; 3]);
    goal.extend([0.0; 3]);
    line = dmp::Primitive::straight_line(
        layout::N_BASIS,
        layout::ALPHA,
        vec![layout::STIFFNESS; dim],
        None,
        tau,
        start,
        goal,
    )
    .map_err(|e| SimError::argument("--pose", format!("no pose primitive for {}: {e}", robot.id)))?;
    line.orientation = Some(OrientationChart { reference: [0.0, 0.0, 0.0, 1.0] });
    line.validate().map_err(|e| SimError::argument("--pose", format!("{}: {e}", robot.id)))?;
    Ok(line)
}

/// Makes a session start a pose robot's: its start and goal orientations, and the Panda's limits.
pub(crate) fn pose_start(motion: &mut v1::MotionSpec, robot: &RobotPlan) {
    let [goal, start] = orientations(robot);
    motion.start_orientation = start.to_vec();
    motion.goal_orientation = goal.to_vec();
    motion.limits = Some(limits_to_proto(&dmp::Limits::PANDA));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pose_robots_turn_a_quarter_between_unit_orientations_at_the_panda_profile() {
        let robots = layout::robots(10, 10, 3, "load");
        for r in &robots {
            let [a, b] = orientations(r);
            for q in [a, b] {
                assert!((q.iter().map(|v| v * v).sum::<f64>() - 1.0).abs() < 1e-12, "{q:?}");
            }
            // The angle between them: 2 acos(|<a, b>|).
            let dot: f64 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
            assert!((2.0 * dot.abs().min(1.0).acos() - TURN).abs() < 1e-9);
            let p = primitive(r, 2.0).unwrap();
            assert_eq!((p.dim, p.position_dim()), (6, 3));
            let mut m = v1::MotionSpec::default();
            pose_start(&mut m, r);
            assert_eq!((m.start_orientation.len(), m.goal_orientation.len()), (4, 4));
            assert_eq!(m.limits.unwrap().max_angular_speed, dmp::Limits::PANDA.max_angular_speed);
        }
        assert_ne!(
            orientations(&robots[0])[1],
            orientations(&robots[3])[1],
            "the robots face different ways"
        );
    }
}
