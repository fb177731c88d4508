//! The scenario's JSON model (serde), exactly the SPEC's fields.

use serde::{Deserialize, Serialize};

use crate::avoidance::Avoidance;

/// One experiment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Scenario {
    /// Its name.
    #[serde(default)]
    pub name: String,
    /// The demonstration to learn from.
    pub demonstration: DemonstrationSpec,
    /// How to learn.
    pub dmp: DmpSpec,
    /// How to roll out.
    pub rollout: RolloutSpec,
    /// Obstacles (per-axis superquadrics, or nested in 3-D).
    #[serde(default)]
    pub obstacles: Vec<ObstacleSpec>,
    /// Boundary samples per obstacle for the point methods.
    #[serde(default = "default_point_samples")]
    pub point_samples: usize,
    /// Method for the obstacles; default `none`.
    #[serde(default = "default_avoidance")]
    pub avoidance: Avoidance,
    /// Robots on one shared phase; empty for one robot owning every dimension.
    #[serde(default)]
    pub robots: Vec<RobotSpec>,
    /// Method of the robot-robot terms; `null` for none.
    #[serde(default)]
    pub robot_avoidance: Option<Avoidance>,
    /// A tool held by the robot (a pose scenario moving in 3-D: `demonstration.q` given): the repulsive terms act
    /// on its control points and turn it ([`crate::tool`]); `null` for a point robot.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tool: Option<ToolSpec>,
}

fn default_point_samples() -> usize {
    50
}

fn default_avoidance() -> Avoidance {
    Avoidance::NONE
}

/// Sample times and positions, and optionally orientations.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DemonstrationSpec {
    /// Increasing sample times.
    pub t: Vec<f64>,
    /// One row of `d` positions per sample.
    pub x: Vec<Vec<f64>>,
    /// Optional: one orientation `[x, y, z, w]` (a unit quaternion) per sample, for a pose primitive (the
    /// rollout then runs the orientation too, and can hold a [`ToolSpec`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub q: Vec<[f64; 4]>,
}

/// A number, or one number per dimension.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum OneOrMany {
    /// The same for every dimension.
    One(f64),
    /// One per dimension.
    Many(Vec<f64>),
}

impl OneOrMany {
    /// As a vector (one entry, or `d`).
    pub fn to_vec(&self) -> Vec<f64> {
        match self {
            OneOrMany::One(v) => vec![*v],
            OneOrMany::Many(v) => v.clone(),
        }
    }
}

/// The DMP's parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DmpSpec {
    /// The paper's `N` (`N + 1` Gaussians).
    #[serde(rename = "N")]
    pub n: usize,
    /// Stiffness.
    #[serde(rename = "K")]
    pub k: OneOrMany,
    /// Damping; `null` for `2 sqrt(K)`.
    #[serde(rename = "D", default)]
    pub d: Option<OneOrMany>,
    /// Canonical decay.
    pub alpha: f64,
}

/// The rollout.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RolloutSpec {
    /// Fixed step.
    pub dt: f64,
    /// Physical duration.
    pub duration: f64,
    /// Start (default: the demonstration's first sample).
    #[serde(default)]
    pub start: Option<Vec<f64>>,
    /// Goal (default: the last sample).
    #[serde(default)]
    pub goal: Option<Vec<f64>>,
    /// Time scale (default: the demonstration's duration).
    #[serde(default)]
    pub tau: Option<f64>,
    /// A pose scenario's start orientation `[x, y, z, w]` (default: the demonstration's first).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub start_orientation: Option<[f64; 4]>,
    /// A pose scenario's goal orientation `[x, y, z, w]` (default: the demonstration's last).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub goal_orientation: Option<[f64; 4]>,
}

/// The nested 3-D form's exponents.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NestedSpec {
    /// Inner exponent `n`.
    pub n: f64,
    /// Outer exponent `m`.
    pub m: f64,
}

/// An obstacle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ObstacleSpec {
    /// Its name, unique in the scenario.
    pub id: String,
    /// Centre at `t = 0`.
    pub center: Vec<f64>,
    /// Semi-axes.
    pub semi_axes: Vec<f64>,
    /// Per-axis exponents `n_i >= 1` (default 1: an ellipsoid).
    #[serde(default)]
    pub exponents: Option<Vec<f64>>,
    /// Rotation `R`, rows (default identity).
    #[serde(default)]
    pub rotation: Option<Vec<Vec<f64>>>,
    /// Constant velocity of the centre (default zero).
    #[serde(default)]
    pub velocity: Option<Vec<f64>>,
    /// The paper's nested 3-D form instead of per-axis exponents.
    #[serde(default)]
    pub nested: Option<NestedSpec>,
}

/// A held tool: a superquadric in the tool frame (the frame of the robot's pose), and where the repulsive terms act
/// on it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ToolSpec {
    /// Semi-axes (3), metres.
    pub semi_axes: Vec<f64>,
    /// Per-axis exponents (default 1: an ellipsoid).
    #[serde(default)]
    pub exponents: Option<Vec<f64>>,
    /// The shape's centre in the tool frame (default: at the controlled point).
    #[serde(default)]
    pub offset: Option<[f64; 3]>,
    /// `axis` (samples along the longest semi-axis, for a long thin tool) or `surface` (default).
    #[serde(default)]
    pub control_points: Option<ToolPointsKind>,
    /// How many control points (default: 25 on the axis, 64 on the surface).
    #[serde(default)]
    pub control_point_count: Option<usize>,
}

/// Where a tool's control points lie.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ToolPointsKind {
    /// Along the longest semi-axis, tips included.
    Axis,
    /// On the surface.
    Surface,
}

/// A robot's footprint.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FootprintSpec {
    /// Semi-axes.
    pub semi_axes: Vec<f64>,
    /// Per-axis exponents (default 1).
    #[serde(default)]
    pub exponents: Option<Vec<f64>>,
}

/// A robot on the shared phase.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RobotSpec {
    /// Its name.
    pub id: String,
    /// The DMP dimensions it owns.
    pub dims: Vec<usize>,
    /// What the others avoid.
    pub footprint: FootprintSpec,
}
