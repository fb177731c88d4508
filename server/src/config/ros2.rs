//! The `[ros2]` section: the domain (`--ros2-domain`), the cell's frame and the static transforms of other frames,
//! and which topics feed which cell.

use dmp_ros2::pose::{PoseError, Rigid};
use serde::{Deserialize, Serialize};

/// ROS 2 over rmw_zenoh. Off unless `domain` is set.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Ros2Config {
    /// The ROS domain id (`ROS_DOMAIN_ID`, the first chunk of rmw_zenoh's keys); none: no ROS 2 bridge.
    pub domain: Option<u32>,
    /// The frame of every cell's scene: a message in this frame is taken as it is.
    pub frame: String,
    /// Frames fixed in the cell's frame: a message in one of them is moved into the cell's frame. Any other frame
    /// is refused (there is no TF listener).
    pub static_transforms: Vec<StaticTransform>,
    /// The topics taken, each into one cell.
    pub topics: Vec<Ros2Topic>,
}

impl Default for Ros2Config {
    fn default() -> Self {
        Self {
            domain: None,
            frame: "world".into(),
            static_transforms: Vec::new(),
            topics: vec![Ros2Topic {
                topic: "/collision_object".into(),
                kind: TopicKind::CollisionObject,
                cell: String::new(),
            }],
        }
    }
}

/// A frame fixed in the cell's frame: where its origin is and how it is turned.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StaticTransform {
    /// The frame's name (`header.frame_id`).
    pub frame: String,
    /// Its origin in the cell's frame, metres.
    pub translation: [f64; 3],
    /// Its rotation in the cell's frame, quaternion `[x, y, z, w]`.
    #[serde(default = "identity")]
    pub rotation: [f64; 4],
}

fn identity() -> [f64; 4] {
    [0.0, 0.0, 0.0, 1.0]
}

/// One topic and the cell it feeds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Ros2Topic {
    /// The topic, e.g. `/collision_object`.
    pub topic: String,
    /// Its message type.
    pub kind: TopicKind,
    /// The cell it feeds; empty: the server's default cell.
    #[serde(default)]
    pub cell: String,
}

/// The message types a topic may carry.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TopicKind {
    /// `moveit_msgs/msg/CollisionObject`.
    CollisionObject,
    /// `nav2_dynamic_msgs/msg/ObstacleArray`.
    ObstacleArray,
}

impl Ros2Config {
    /// Checks the topics' names and the transforms, naming the field at fault.
    pub(crate) fn check(&self) -> Result<(), crate::error::ServerError> {
        use crate::error::ServerError;
        if self.frame.is_empty() {
            return Err(ServerError::invalid("ros2.frame", "must not be empty"));
        }
        for (i, t) in self.topics.iter().enumerate() {
            dmp_ros2::keys::check_topic(&t.topic)
                .map_err(|r| ServerError::invalid(format!("ros2.topics[{i}].topic"), r))?;
            if !t.cell.is_empty() {
                dmp_proto::keys::check_name("cell", &t.cell)
                    .map_err(|e| ServerError::from(e).within(&format!("ros2.topics[{i}]")))?;
            }
        }
        for (i, s) in self.static_transforms.iter().enumerate() {
            s.rigid(&format!("ros2.static_transforms[{i}]"))
                .map_err(|e| ServerError::invalid(e.field, e.reason))?;
        }
        Ok(())
    }

    /// The transform from `frame_id` to the cell's frame: the identity for the cell's frame, a static transform's,
    /// or none (a frame the server does not know). A leading `/` (ROS 1 style) is ignored.
    pub(crate) fn frame_to_cell(&self, frame_id: &str) -> Option<Rigid> {
        let f = frame_id.trim_start_matches('/');
        if f.is_empty() {
            return None;
        }
        if f == self.frame.trim_start_matches('/') {
            return Some(Rigid::IDENTITY);
        }
        let s = self.static_transforms.iter().find(|s| s.frame.trim_start_matches('/') == f)?;
        s.rigid("").ok()
    }
}

impl StaticTransform {
    fn rigid(&self, field: &str) -> Result<Rigid, PoseError> {
        Rigid::new(self.translation, self.rotation, field)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_the_cells_or_static() {
        let mut c = Ros2Config::default();
        c.static_transforms.push(StaticTransform {
            frame: "table".into(),
            translation: [1.0, 0.0, 0.5],
            rotation: identity(),
        });
        assert_eq!(c.frame_to_cell("world"), Some(Rigid::IDENTITY));
        assert_eq!(c.frame_to_cell("/world"), Some(Rigid::IDENTITY));
        assert_eq!(c.frame_to_cell("table").unwrap().t, [1.0, 0.0, 0.5]);
        assert_eq!(c.frame_to_cell("camera"), None);
        assert_eq!(c.frame_to_cell(""), None);
        assert!(c.check().is_ok());
        c.static_transforms[0].rotation = [0.0; 4];
        assert!(c.check().unwrap_err().to_string().starts_with("ros2.static_transforms[0].orientation"));
        c.static_transforms.clear();
        c.topics[0].topic = "/a b".into();
        assert!(c.check().unwrap_err().to_string().starts_with("ros2.topics[0].topic"));
    }
}
