//! `shape_msgs`: solid primitives, meshes, planes.

use super::geometry_msgs::{Point, Polygon};

/// `shape_msgs/msg/SolidPrimitive` (Humble and Jazzy: with `polygon`, for prisms).
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct SolidPrimitive {
    /// [`SolidPrimitive::BOX`], ...
    pub r#type: u8,
    /// At most 3: box x, y, z; sphere radius; cylinder or cone height, radius; prism height.
    pub dimensions: Vec<f64>,
    /// A prism's base.
    pub polygon: Polygon,
}

impl SolidPrimitive {
    /// A box: `dimensions` x, y, z (side lengths).
    pub const BOX: u8 = 1;
    /// A sphere: `dimensions` radius.
    pub const SPHERE: u8 = 2;
    /// A cylinder along z: `dimensions` height, radius.
    pub const CYLINDER: u8 = 3;
    /// A cone along z, its tip up: `dimensions` height, base radius.
    pub const CONE: u8 = 4;
    /// A prism: `polygon` extruded along z by `dimensions` height.
    pub const PRISM: u8 = 5;
}

/// `shape_msgs/msg/MeshTriangle`.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct MeshTriangle {
    /// Indices into the mesh's vertices.
    pub vertex_indices: [u32; 3],
}

/// `shape_msgs/msg/Mesh`.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Mesh {
    /// Triangles.
    pub triangles: Vec<MeshTriangle>,
    /// Vertices.
    pub vertices: Vec<Point>,
}

/// `shape_msgs/msg/Plane`: `a x + b y + c z + d = 0`.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Plane {
    /// a, b, c, d.
    pub coef: [f64; 4],
}
