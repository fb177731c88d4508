//! `moveit_msgs` (with `object_recognition_msgs/ObjectType`, its only dependency outside common_interfaces): the
//! collision objects of MoveIt's planning scene.

use super::geometry_msgs::Pose;
use super::shape_msgs::{Mesh, Plane, SolidPrimitive};
use super::std_msgs::Header;

/// `object_recognition_msgs/msg/ObjectType`.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct ObjectType {
    /// The object's key in its database.
    pub key: String,
    /// The database's parameters.
    pub db: String,
}

/// `moveit_msgs/msg/CollisionObject`.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct CollisionObject {
    /// The frame of `pose`.
    pub header: Header,
    /// The object's pose; its shapes' poses are relative to it.
    pub pose: Pose,
    /// Its name in the scene.
    pub id: String,
    /// Its type in a database of objects.
    pub r#type: ObjectType,
    /// Solids.
    pub primitives: Vec<SolidPrimitive>,
    /// One pose per solid.
    pub primitive_poses: Vec<Pose>,
    /// Meshes.
    pub meshes: Vec<Mesh>,
    /// One pose per mesh.
    pub mesh_poses: Vec<Pose>,
    /// Planes.
    pub planes: Vec<Plane>,
    /// One pose per plane.
    pub plane_poses: Vec<Pose>,
    /// Named frames on the object.
    pub subframe_names: Vec<String>,
    /// One pose per named frame.
    pub subframe_poses: Vec<Pose>,
    /// [`CollisionObject::ADD`], ...
    pub operation: u8,
}

impl CollisionObject {
    /// Adds the object, replacing one of the same id.
    pub const ADD: u8 = 0;
    /// Removes the object (every object, with an empty id).
    pub const REMOVE: u8 = 1;
    /// Adds shapes to the object (adds it when it does not exist).
    pub const APPEND: u8 = 2;
    /// Moves the object to `pose`.
    pub const MOVE: u8 = 3;
}
