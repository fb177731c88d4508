//! rmw_zenoh's key expressions: a topic `/a/b` of type `pkg/msg/T` in domain `d` is published on
//! `d/a/b/pkg::msg::dds_::T_/<type hash>`. Jazzy's rmw_zenoh puts the type's `RIHS01_<sha256>` hash there (REP
//! 2011); a subscriber that takes any hash (Humble's rmw_zenoh, later revisions of a type) ends with `*`.

/// A ROS 2 message type: its name as `pkg/msg/Type` and its RIHS01 hash (of the Jazzy definition).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RosType {
    /// `pkg/msg/Type`.
    pub name: &'static str,
    /// `RIHS01_<64 hex digits>`.
    pub hash: &'static str,
}

impl RosType {
    /// The DDS name rmw_zenoh puts in keys: `pkg::msg::dds_::Type_`.
    pub(crate) fn dds_name(&self) -> String {
        format!("{}_", self.name.replace("/msg/", "::msg::dds_::"))
    }
}

/// `moveit_msgs/msg/CollisionObject` (taken with any hash).
pub const COLLISION_OBJECT: RosType = RosType { name: "moveit_msgs/msg/CollisionObject", hash: "" };
/// `nav2_dynamic_msgs/msg/ObstacleArray` (taken with any hash).
pub const OBSTACLE_ARRAY: RosType = RosType { name: "nav2_dynamic_msgs/msg/ObstacleArray", hash: "" };
/// `trajectory_msgs/msg/MultiDOFJointTrajectory`; the hash is rosbags 0.11.9's of the Jazzy definition (the golden
/// test computes it again).
pub const MULTI_DOF_JOINT_TRAJECTORY: RosType = RosType {
    name: "trajectory_msgs/msg/MultiDOFJointTrajectory",
    hash: "RIHS01_3a18fd095292a65cfde8833c72985a30af981f3ec44494655c6267262b443a4a",
};
/// `visualization_msgs/msg/MarkerArray`; the hash as for [`MULTI_DOF_JOINT_TRAJECTORY`].
pub const MARKER_ARRAY: RosType = RosType {
    name: "visualization_msgs/msg/MarkerArray",
    hash: "RIHS01_86cb8800b6fb05b5eff1abd7a56f62a5641d3ae9a1c29e78e67e704f1d067dcf",
};

/// A topic name without its leading `/` (`/collision_object` and `collision_object` are one topic at the root
/// namespace).
pub(crate) fn topic_chunks(topic: &str) -> &str {
    topic.trim_start_matches('/')
}

/// The key a publisher of `ty` on `topic` in `domain` puts on.
pub fn topic_key(domain: u32, topic: &str, ty: &RosType) -> String {
    format!("{domain}/{}/{}/{}", topic_chunks(topic), ty.dds_name(), ty.hash)
}

/// The expression a subscriber of `ty` on `topic` in `domain` declares: any type hash.
pub fn topic_subscription(domain: u32, topic: &str, ty: &RosType) -> String {
    format!("{domain}/{}/{}/*", topic_chunks(topic), ty.dds_name())
}

/// Whether `topic` is a valid ROS 2 topic name for these keys: `/`-separated tokens of letters, digits and `_`,
/// not starting with a digit (no `~`, no substitutions, no empty token).
pub fn check_topic(topic: &str) -> Result<(), String> {
    let t = topic_chunks(topic);
    if t.is_empty() {
        return Err("must not be empty".into());
    }
    for token in t.split('/') {
        let mut chars = token.chars();
        match chars.next() {
            None => return Err("has an empty token (`//` or a trailing `/`)".into()),
            Some(c) if c.is_ascii_digit() => return Err(format!("token `{token}` starts with a digit")),
            _ => {}
        }
        if let Some(c) = token.chars().find(|c| !(c.is_ascii_alphanumeric() || *c == '_')) {
            return Err(format!("has `{c}`: only letters, digits, `_` and `/` are allowed"));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_are_rmw_zenohs() {
        assert_eq!(
            topic_subscription(0, "/collision_object", &COLLISION_OBJECT),
            "0/collision_object/moveit_msgs::msg::dds_::CollisionObject_/*"
        );
        assert_eq!(
            topic_key(3, "/dmp/r1/trajectory", &MULTI_DOF_JOINT_TRAJECTORY),
            "3/dmp/r1/trajectory/trajectory_msgs::msg::dds_::MultiDOFJointTrajectory_/RIHS01_\
             3a18fd095292a65cfde8833c72985a30af981f3ec44494655c6267262b443a4a"
        );
        assert!(check_topic("/dmp/cell_a/markers").is_ok());
        assert!(check_topic("/a//b").is_err());
        assert!(check_topic("/a/1b").is_err());
        assert!(check_topic("/a/b-c").is_err());
        assert!(check_topic("").is_err());
    }
}
