//! A segment sent to a robot as the `trajectory_msgs/msg/MultiDOFJointTrajectory` ROS 2 tools read: one joint (the
//! robot), one point per setpoint. A point's transform is the position (its first 3 dimensions; a 2-D robot's `z`
//! is 0, a 1-D robot's `y` and `z` too) turned by the pose's orientation for a pose run, the identity otherwise; its
//! velocity and acceleration are the linear ones with a pose run's angular ones (zero otherwise). The header's stamp
//! is the wall time of the segment's first point (real-time streams; a stream read as fast as possible has no wall
//! time, and is stamped when it is sent), and each point's `time_from_start` counts from it.

use dmp_proto::v1;
use dmp_ros2::msgs::builtin_interfaces::{Duration, Time};
use dmp_ros2::msgs::geometry_msgs::{Quaternion, Transform, Twist, Vector3};
use dmp_ros2::msgs::std_msgs::Header;
use dmp_ros2::msgs::trajectory_msgs::{MultiDOFJointTrajectory, MultiDOFJointTrajectoryPoint};

/// A name as one token of a ROS topic: every character but letters, digits and `_` becomes `_`, and a name that
/// starts with a digit (or is empty) gets a leading `_`.
pub(crate) fn topic_token(name: &str) -> String {
    let mut out: String = name.chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '_' }).collect();
    if out.chars().next().is_none_or(|c| c.is_ascii_digit()) {
        out.insert(0, '_');
    }
    out
}

/// The topic of a robot's trajectory: `/dmp/<robot>/trajectory`.
pub(crate) fn trajectory_topic(robot: &str) -> String {
    format!("/dmp/{}/trajectory", topic_token(robot))
}

/// The message of `segment` in `frame`; `stamp_unix_s` is the wall time of its first point.
pub fn trajectory_message(segment: &v1::Segment, frame: &str, stamp_unix_s: f64) -> MultiDOFJointTrajectory {
    let d = (segment.dim as usize).max(1);
    let n = segment.positions.len() / d;
    let vec3 = |v: &[f64], k: usize, width: usize| -> Vector3 {
        let row = v.get(k * width..(k + 1) * width).unwrap_or(&[]);
        let at = |i: usize| if i < width.min(3) { row.get(i).copied().unwrap_or(0.0) } else { 0.0 };
        Vector3 { x: at(0), y: at(1), z: at(2) }
    };
    let points = (0..n)
        .map(|k| {
            let rotation = match segment.orientations.get(4 * k..4 * k + 4) {
                Some(&[x, y, z, w]) => Quaternion { x, y, z, w },
                _ => Quaternion::default(),
            };
            let twist = |linear: &[f64], angular: &[f64]| Twist {
                linear: vec3(linear, k, d),
                angular: vec3(angular, k, 3),
            };
            MultiDOFJointTrajectoryPoint {
                transforms: vec![Transform { translation: vec3(&segment.positions, k, d), rotation }],
                velocities: vec![twist(&segment.velocities, &segment.angular_velocities)],
                accelerations: vec![twist(&segment.accelerations, &segment.angular_accelerations)],
                time_from_start: Duration::from_s(k as f64 * segment.dt),
            }
        })
        .collect();
    MultiDOFJointTrajectory {
        header: Header { stamp: Time::from_unix_s(stamp_unix_s), frame_id: frame.to_owned() },
        joint_names: vec![segment.robot_id.clone()],
        points,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pose_segment_becomes_transforms_and_twists() {
        let s = v1::Segment {
            robot_id: "arm-1".into(),
            dt: 0.25,
            dim: 3,
            positions: vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0],
            velocities: vec![0.1, 0.2, 0.3, 0.4, 0.5, 0.6],
            accelerations: vec![-1.0, -2.0, -3.0, -4.0, -5.0, -6.0],
            orientations: vec![0.0, 0.0, 0.6, 0.8, 0.0, 0.6, 0.0, 0.8],
            angular_velocities: vec![0.0, 0.0, 1.0, 0.0, 1.0, 0.0],
            angular_accelerations: vec![1.0, 0.0, 0.0, 2.0, 0.0, 0.0],
            ..Default::default()
        };
        let m = trajectory_message(&s, "world", 100.5);
        assert_eq!(m.joint_names, vec!["arm-1".to_string()]);
        assert_eq!(
            (m.header.stamp.sec, m.header.stamp.nanosec, m.header.frame_id.as_str()),
            (100, 5e8 as u32, "world")
        );
        assert_eq!(m.points.len(), 2);
        let p = &m.points[1];
        assert_eq!(p.transforms[0].translation, Vector3 { x: 4.0, y: 5.0, z: 6.0 });
        assert_eq!(p.transforms[0].rotation, Quaternion { x: 0.0, y: 0.6, z: 0.0, w: 0.8 });
        assert_eq!(p.velocities[0].linear, Vector3 { x: 0.4, y: 0.5, z: 0.6 });
        assert_eq!(p.velocities[0].angular, Vector3 { x: 0.0, y: 1.0, z: 0.0 });
        assert_eq!(p.accelerations[0].angular, Vector3 { x: 2.0, y: 0.0, z: 0.0 });
        assert_eq!(p.time_from_start, Duration { sec: 0, nanosec: 250_000_000 });
    }

    #[test]
    fn a_position_segment_has_identity_rotations_and_its_first_three_dimensions() {
        let two = v1::Segment {
            robot_id: "r".into(),
            dt: 0.5,
            dim: 2,
            positions: vec![1.0, 2.0],
            velocities: vec![3.0, 4.0],
            accelerations: vec![5.0, 6.0],
            ..Default::default()
        };
        let p = &trajectory_message(&two, "world", 0.0).points[0];
        assert_eq!(p.transforms[0].translation, Vector3 { x: 1.0, y: 2.0, z: 0.0 });
        assert_eq!(p.transforms[0].rotation, Quaternion::default());
        assert_eq!(p.accelerations[0].linear, Vector3 { x: 5.0, y: 6.0, z: 0.0 });
        assert_eq!(p.velocities[0].angular, Vector3::default());
        let four = v1::Segment { dim: 4, positions: vec![1.0, 2.0, 3.0, 9.0, 5.0, 6.0, 7.0, 9.0], ..two };
        let m = trajectory_message(&four, "world", 0.0);
        assert_eq!(m.points.len(), 2);
        assert_eq!(m.points[1].transforms[0].translation, Vector3 { x: 5.0, y: 6.0, z: 7.0 });
        assert_eq!(m.points[1].time_from_start.as_s(), 0.5);
    }

    #[test]
    fn robot_names_become_topic_tokens() {
        assert_eq!(trajectory_topic("panda-1.a"), "/dmp/panda_1_a/trajectory");
        assert_eq!(trajectory_topic("1st"), "/dmp/_1st/trajectory");
        assert!(dmp_ros2::keys::check_topic(&trajectory_topic("é")).is_ok());
    }
}
