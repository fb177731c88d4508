//! Pose scenarios: a demonstration with orientations (`demonstration.q`) learns a pose primitive (positions, then
//! the rotation vector of the orientation in a chart: [`crate::orientation::pose`]), rolled out with a start and
//! goal orientation, and possibly holding a tool ([`crate::tool`]) that the obstacles push and turn.

use nalgebra::UnitQuaternion;

use super::model::{Scenario, ToolPointsKind, ToolSpec};
use super::to_engine::superquadric;
use crate::error::{DmpError, InvalidInput, Result};
use crate::integrate::Motion;
use crate::learn::{Demonstration, LearnConfig};
use crate::orientation::OrientationDemonstration;
use crate::orientation::pose::{learn_pose, pose_motion};
use crate::primitive::Primitive;
use crate::tool::sampling::{DEFAULT_AXIS_POINTS, DEFAULT_SURFACE_POINTS};
use crate::tool::{ControlPoints, Tool};

/// What a pose scenario adds to its run.
#[derive(Debug, Clone)]
pub struct PoseSetup {
    /// The chart of the orientation dimensions (at the goal orientation: the orientation is `exp(y) ⊗ chart`).
    pub chart: UnitQuaternion<f64>,
    /// The tool the robot holds, if any.
    pub tool: Option<Tool>,
}

/// Learns the pose primitive of `s` (its `demonstration.q` is not empty).
pub(super) fn learn(s: &Scenario, positions: &Demonstration, config: &LearnConfig) -> Result<Primitive> {
    let orientations = OrientationDemonstration::new(s.demonstration.t.clone(), s.demonstration.q.clone())?;
    learn_pose(positions, &orientations, config)
}

/// The pose motion of `p` from the position motion and the rollout's orientations, with its chart; errors name
/// `rollout.start_orientation` and `rollout.goal_orientation`.
pub(super) fn motion(s: &Scenario, p: &Primitive, position: Motion) -> Result<(Motion, UnitQuaternion<f64>)> {
    let r = &s.rollout;
    let m = pose_motion(p, position, r.start_orientation, r.goal_orientation)
        .map_err(|e| DmpError::from(InvalidInput::new(format!("rollout.{}", e.field), e.rule)))?;
    Ok((m.motion, m.chart))
}

/// The tool of a scenario; errors name the field within `tool`.
pub(super) fn tool(spec: &ToolSpec) -> Result<Tool> {
    let within = |e: DmpError| match e {
        DmpError::Invalid(i) if i.field == "tool.control_points.count" => {
            InvalidInput::new("tool.control_point_count", i.rule).into()
        }
        DmpError::Invalid(i) if !i.field.starts_with("tool.") => {
            InvalidInput::new(format!("tool.{}", i.field), i.rule).into()
        }
        other => other,
    };
    let shape = superquadric(&spec.semi_axes, spec.exponents.as_deref()).map_err(within)?;
    let sampling = match spec.control_points.unwrap_or(ToolPointsKind::Surface) {
        ToolPointsKind::Axis => {
            ControlPoints::Axis { count: spec.control_point_count.unwrap_or(DEFAULT_AXIS_POINTS) }
        }
        ToolPointsKind::Surface => {
            ControlPoints::Surface { count: spec.control_point_count.unwrap_or(DEFAULT_SURFACE_POINTS) }
        }
    };
    Tool::new(shape, spec.offset.unwrap_or([0.0; 3]), sampling).map_err(within)
}
