//! `nav2_dynamic_msgs` (with `unique_identifier_msgs/UUID`): tracked obstacles around mobile bases.

use super::geometry_msgs::{Point, Vector3};
use super::std_msgs::Header;

/// `unique_identifier_msgs/msg/UUID`.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Uuid {
    /// The 16 bytes.
    pub uuid: [u8; 16],
}

/// `nav2_dynamic_msgs/msg/Obstacle`.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Obstacle {
    /// The track's identity.
    pub uuid: Uuid,
    /// Detection confidence.
    pub score: f32,
    /// Centre.
    pub position: Point,
    /// Velocity of the centre.
    pub velocity: Vector3,
    /// Size along x, y, z.
    pub size: Vector3,
}

/// `nav2_dynamic_msgs/msg/ObstacleArray`.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct ObstacleArray {
    /// The frame of every obstacle.
    pub header: Header,
    /// The obstacles.
    pub obstacles: Vec<Obstacle>,
}
