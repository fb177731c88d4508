//! `visualization_msgs` (with `sensor_msgs/CompressedImage`, a field of the marker): RViz's markers.

use super::builtin_interfaces::Duration;
use super::geometry_msgs::{Point, Pose, Vector3};
use super::std_msgs::{ColorRGBA, Header};

/// `sensor_msgs/msg/CompressedImage`.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct CompressedImage {
    /// Stamp and frame.
    pub header: Header,
    /// The image's format.
    pub format: String,
    /// The compressed image.
    pub data: Vec<u8>,
}

/// `visualization_msgs/msg/UVCoordinate`.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct UVCoordinate {
    /// u.
    pub u: f32,
    /// v.
    pub v: f32,
}

/// `visualization_msgs/msg/MeshFile`.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct MeshFile {
    /// Name (and extension).
    pub filename: String,
    /// The file.
    pub data: Vec<u8>,
}

/// `visualization_msgs/msg/Marker`.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Marker {
    /// Stamp and frame.
    pub header: Header,
    /// Namespace.
    pub ns: String,
    /// Id within the namespace.
    pub id: i32,
    /// [`Marker::CUBE`], ...
    pub r#type: i32,
    /// [`Marker::ADD`], ...
    pub action: i32,
    /// Pose.
    pub pose: Pose,
    /// Scale (a cube's side lengths, a sphere's diameters, a line's width in x).
    pub scale: Vector3,
    /// Colour.
    pub color: ColorRGBA,
    /// Zero: forever.
    pub lifetime: Duration,
    /// Re-transformed into its frame at every frame.
    pub frame_locked: bool,
    /// Points of lists and strips.
    pub points: Vec<Point>,
    /// Per-point colours.
    pub colors: Vec<ColorRGBA>,
    /// Texture URI.
    pub texture_resource: String,
    /// Embedded texture.
    pub texture: CompressedImage,
    /// Texture coordinates.
    pub uv_coordinates: Vec<UVCoordinate>,
    /// Text of text markers.
    pub text: String,
    /// Mesh URI.
    pub mesh_resource: String,
    /// Embedded mesh.
    pub mesh_file: MeshFile,
    /// Use the mesh's materials.
    pub mesh_use_embedded_materials: bool,
}

impl Marker {
    /// An arrow.
    pub const ARROW: i32 = 0;
    /// A box.
    pub const CUBE: i32 = 1;
    /// An ellipsoid.
    pub const SPHERE: i32 = 2;
    /// A cylinder.
    pub const CYLINDER: i32 = 3;
    /// A polyline.
    pub const LINE_STRIP: i32 = 4;
    /// Segments.
    pub const LINE_LIST: i32 = 5;
    /// A triangle list.
    pub const TRIANGLE_LIST: i32 = 11;
    /// Add or modify.
    pub const ADD: i32 = 0;
    /// Delete one.
    pub const DELETE: i32 = 2;
    /// Delete all (of the namespace).
    pub const DELETEALL: i32 = 3;
}

/// `visualization_msgs/msg/MarkerArray`.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct MarkerArray {
    /// The markers.
    pub markers: Vec<Marker>,
}
