//! `trajectory_msgs`: multi-DOF trajectories.

use super::builtin_interfaces::Duration;
use super::geometry_msgs::{Transform, Twist};
use super::std_msgs::Header;

/// `trajectory_msgs/msg/MultiDOFJointTrajectoryPoint`.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct MultiDOFJointTrajectoryPoint {
    /// One transform per joint.
    pub transforms: Vec<Transform>,
    /// One velocity per joint.
    pub velocities: Vec<Twist>,
    /// One acceleration per joint.
    pub accelerations: Vec<Twist>,
    /// From the trajectory's stamp.
    pub time_from_start: Duration,
}

/// `trajectory_msgs/msg/MultiDOFJointTrajectory`.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct MultiDOFJointTrajectory {
    /// The frame, and the time `time_from_start` counts from.
    pub header: Header,
    /// The joints.
    pub joint_names: Vec<String>,
    /// The points.
    pub points: Vec<MultiDOFJointTrajectoryPoint>,
}
