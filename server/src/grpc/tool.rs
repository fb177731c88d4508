//! A held tool, wire to engine: a motion request's (`MotionSpec.tool`) and a robot record's (`RobotRecord.tool`).

use dmp_proto::shape::superquadric_to_shape;
use dmp_proto::v1;

use crate::error::ServerError;

/// The most control points a tool may have.
pub(crate) const MAX_TOOL_POINTS: usize = 256;

/// The engine's tool of `t`; errors name `{field}.*` (`field` is where the message sits, e.g. `motion.tool`).
pub(crate) fn tool_from_proto(t: &v1::Tool, field: &str) -> Result<dmp::tool::Tool, ServerError> {
    use dmp::tool::ControlPoints;
    use dmp::tool::sampling::{DEFAULT_AXIS_POINTS, DEFAULT_SURFACE_POINTS};
    let sub = |f: &str| format!("{field}{f}");
    let shape = t.shape.as_ref().ok_or_else(|| ServerError::invalid(sub(".shape"), "is required"))?;
    let shape = superquadric_to_shape(shape).map_err(|e| e.within(&sub(".shape")))?;
    let offset = match t.offset.as_slice() {
        [] => [0.0; 3],
        &[x, y, z] => [x, y, z],
        other => {
            return Err(ServerError::invalid(
                sub(".offset"),
                format!("must be empty or 3 numbers, found {}", other.len()),
            ));
        }
    };
    // Each control point costs a whole field evaluation per step: the server takes at most MAX_TOOL_POINTS.
    if t.control_points as usize > MAX_TOOL_POINTS {
        return Err(ServerError::invalid(
            sub(".control_points"),
            format!(
                "at most {MAX_TOOL_POINTS} (each one costs a field evaluation per step), not {}",
                t.control_points
            ),
        ));
    }
    let count = |default: usize| if t.control_points == 0 { default } else { t.control_points as usize };
    let sampling = if t.axis {
        ControlPoints::Axis { count: count(DEFAULT_AXIS_POINTS) }
    } else {
        ControlPoints::Surface { count: count(DEFAULT_SURFACE_POINTS) }
    };
    dmp::tool::Tool::new(shape, offset, sampling).map_err(|e| match e {
        // The engine names `tool.*` (`tool.control_points.count` is the request's `control_points`).
        dmp::DmpError::Invalid(i) => {
            let rest = i.field.replacen("tool.control_points.count", "tool.control_points", 1);
            ServerError::invalid(sub(rest.strip_prefix("tool").unwrap_or(&format!(".{rest}"))), i.rule)
        }
        other => ServerError::invalid(field, other.to_string()),
    })
}
