//! A motion request resolved against the access rules and the store: the primitive, the motion, the avoidance,
//! and the robot's record as the defaults of its limits, safety distance, footprint and tool.

use dmp::execution::GoalTolerance;
use dmp::{Motion, Primitive};
use dmp_proto::avoidance::avoidance_from_proto;
use dmp_proto::check::{check_in_workspace, check_tau, check_vector};
use dmp_proto::keys::check_name;
use dmp_proto::limits::goal_filter_alpha;
use dmp_proto::shape::superquadric_to_shape;
use dmp_proto::v1;

use super::limits_in_force::{self, InForce};
use super::shared::ServiceState;
use super::tool::tool_from_proto;
use crate::access::{Action, Caller};
use crate::cells::cell::Cell;
use crate::error::ServerError;
use crate::runs::served_run::RunAvoidance;
use crate::wire::{obstacle_from_proto, stored_primitive};

/// What a motion request does with its robots.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Intent {
    /// Plan: answers only.
    Plan,
    /// Execute: moves them.
    Execute,
}

impl Intent {
    /// The action of this intent on `robots` in `cell`.
    pub(super) fn action<'a>(self, cell: &'a str, robots: &'a [&'a str]) -> Action<'a> {
        match self {
            Intent::Plan => Action::Plan { cell, robots },
            Intent::Execute => Action::Execute { cell, robots },
        }
    }
}

/// A motion request resolved against the store: the primitive, the motion, the avoidance.
pub(super) struct ResolvedMotion {
    pub(super) robot_id: String,
    /// The robot's cell.
    pub(super) cell: Cell,
    pub(super) primitive: Primitive,
    pub(super) motion: Motion,
    pub(super) avoidance: RunAvoidance,
    pub(super) footprint: Option<dmp::Shape>,
    pub(super) footprint_proto: Option<v1::Superquadric>,
    /// "At the goal and at rest".
    pub(super) goal_tolerance: GoalTolerance,
    /// A pose run: the chart of its orientation dimensions ([`dmp::orientation::pose::pose_motion`]).
    pub(super) chart: Option<nalgebra::UnitQuaternion<f64>>,
    /// A pose run's tool.
    pub(super) tool: Option<dmp::tool::Tool>,
    /// The robot's limits and safety distance: the request's, then its record's, then the server's default
    /// profile, field by field ([`limits_in_force`]).
    pub(super) in_force: InForce,
    /// The goal filter's `alpha_g` (0: off).
    pub(super) goal_filter_alpha: f64,
    /// The velocity at the start, every dimension of the primitive (zeros: at rest).
    pub(super) start_velocity: Vec<f64>,
}

impl ResolvedMotion {
    /// Resolves a motion of `caller` against the server's `state`; `caller` must be allowed to `intent` its robot
    /// in its cell (checked before the cell is looked up or the store read); the cell must be known
    /// ([`crate::cells::known`]).
    pub(super) async fn resolve(
        state: &ServiceState,
        caller: &Caller,
        intent: Intent,
        spec: Option<&v1::MotionSpec>,
        prefix: &str,
    ) -> Result<ResolvedMotion, ServerError> {
        let spec = spec.ok_or_else(|| ServerError::invalid(prefix, "is required"))?;
        check_name(&format!("{prefix}.robot_id"), &spec.robot_id)?;
        check_name(&format!("{prefix}.primitive"), &spec.primitive)?;
        let cell = state.cells.resolve(&spec.cell).map_err(|e| e.within(prefix))?;
        caller.check(&intent.action(cell, &[&spec.robot_id]))?;
        // Only a known cell: a typo in its name must not run the motion in a new, empty scene. The refusal names
        // the known cells where the caller may do the same, or read the scene.
        let visible = |c: &str| {
            caller.check(&intent.action(c, &[&spec.robot_id])).is_ok()
                || caller.check(&Action::ReadScene { cell: c }).is_ok()
        };
        let cell = state.cells.for_motion(cell, visible).map_err(|e| e.within(prefix))?;
        let store = state.store.clone();
        let (robot, name, version) = (spec.robot_id.clone(), spec.primitive.clone(), spec.version);
        // The primitive, and the robot's record: the defaults of its limits, safety distance, footprint and tool.
        let (record, robot) = tokio::task::spawn_blocking(move || {
            Ok::<_, ServerError>((store.get(&robot, &name, version)?, store.get_robot(&robot)?))
        })
        .await
        .map_err(|e| ServerError::Internal(e.to_string()))??;
        let robot = robot.unwrap_or_default();
        let proto = record
            .primitive
            .ok_or_else(|| ServerError::Internal("stored record without primitive".into()))?;
        let what = format!("{}/{}", spec.robot_id, spec.primitive);
        let limits = &state.config.limits;
        let primitive = stored_primitive(&proto, limits, &what).map_err(|e| e.within(prefix))?;
        // The position's dimensions (a pose primitive's orientation comes in its own fields).
        let d = primitive.position_dim();
        let given_or_default = |field: &str, v: &[f64], default: &[f64]| -> Result<Vec<f64>, ServerError> {
            if v.is_empty() {
                Ok(default.to_vec())
            } else {
                check_vector(&format!("{prefix}.{field}"), v, d)?;
                Ok(v.to_vec())
            }
        };
        let start = given_or_default("start", &spec.start, &primitive.start[..d])?;
        // The start velocity of the position's dimensions; a pose run's orientation starts at rest.
        let mut start_velocity = given_or_default("start_velocity", &spec.start_velocity, &vec![0.0; d])?;
        let max = limits.max_state_speed_m_s;
        if let Some(i) = start_velocity.iter().position(|v| v.abs() > max) {
            return Err(ServerError::invalid(
                format!("{prefix}.start_velocity[{i}]"),
                format!(
                    "must be between -{max} and {max} m/s (limits.max_state_speed_m_s), as a robot's state"
                ),
            ));
        }
        start_velocity.resize(primitive.dim, 0.0);
        let goal = given_or_default("goal", &spec.goal, &primitive.goal[..d])?;
        check_in_workspace(&format!("{prefix}.start"), &start, limits.workspace_m)?;
        check_in_workspace(&format!("{prefix}.goal"), &goal, limits.workspace_m)?;
        let tau = if spec.tau == 0.0 { primitive.tau } else { spec.tau };
        check_tau(&format!("{prefix}.tau"), tau)?;
        let (motion, chart) = pose(&primitive, Motion { start, goal, tau }, spec, prefix)?;
        let defaults = &state.config.defaults;
        let obstacles = avoidance_from_proto(spec.avoidance.as_ref(), defaults.avoidance)
            .map_err(|e| e.within(&format!("{prefix}.avoidance")))?;
        let robots = avoidance_from_proto(spec.robot_avoidance.as_ref(), defaults.robot_avoidance)
            .map_err(|e| e.within(&format!("{prefix}.robot_avoidance")))?;
        if spec.extra_obstacles.len() > state.config.limits.max_obstacles {
            return Err(ServerError::ResourceExhausted(format!(
                "{prefix}.extra_obstacles: more than {} obstacles",
                state.config.limits.max_obstacles
            )));
        }
        let mut extra = Vec::with_capacity(spec.extra_obstacles.len());
        for (i, o) in spec.extra_obstacles.iter().enumerate() {
            check_name(&format!("{prefix}.extra_obstacles[{i}].id"), &o.id)?;
            extra.push(
                obstacle_from_proto(o, limits.workspace_m)
                    .map_err(|e| e.within(&format!("{prefix}.extra_obstacles[{i}]")))?,
            );
        }
        // Checked now, not when the first obstacle or robot appears (which would end a running stream).
        obstacles.0.method.validate(&format!("{prefix}.avoidance"), d)?;
        robots.0.method.validate(&format!("{prefix}.robot_avoidance"), d)?;
        let in_force = limits_in_force::resolve(&spec.robot_id, spec, &robot, defaults, prefix)?;
        // The request's footprint, or the record's.
        let footprint_proto = spec.footprint.clone().or(robot.footprint);
        let footprint = footprint_proto
            .as_ref()
            .map(superquadric_to_shape)
            .transpose()
            .map_err(|e| e.within(&format!("{prefix}.footprint")))?;
        // The request's tool; or the record's, for a pose run in 3-D (a position run of the robot ignores it).
        let tool = match (&spec.tool, &robot.tool) {
            (Some(t), _) => Some(tool(t, chart.is_some(), d, prefix)?),
            (None, Some(t)) if chart.is_some() && d == 3 => Some(tool_from_proto(t, "robot.tool")?),
            _ => None,
        };
        Ok(ResolvedMotion {
            robot_id: spec.robot_id.clone(),
            cell,
            primitive,
            motion,
            avoidance: RunAvoidance { obstacles, robots, extra, ignore_scene: spec.ignore_scene },
            footprint,
            footprint_proto,
            goal_tolerance: goal_tolerance(spec.goal_tolerance.as_ref(), prefix)?,
            tool,
            chart,
            in_force,
            goal_filter_alpha: goal_filter_alpha(spec.goal_filter_alpha).map_err(|e| e.within(prefix))?,
            start_velocity,
        })
    }
}

/// The motion of a pose primitive, with its start and goal orientations (the primitive's where not given), and its
/// chart; a position primitive's motion as it is, refusing orientations.
fn pose(
    p: &Primitive,
    position: Motion,
    spec: &v1::MotionSpec,
    prefix: &str,
) -> Result<(Motion, Option<nalgebra::UnitQuaternion<f64>>), ServerError> {
    let quaternion = |field: &str, v: &[f64]| -> Result<Option<[f64; 4]>, ServerError> {
        match v {
            [] => Ok(None),
            &[x, y, z, w] => Ok(Some([x, y, z, w])),
            other => Err(ServerError::invalid(
                format!("{prefix}.{field}"),
                format!("must be empty or 4 numbers (x, y, z, w), found {}", other.len()),
            )),
        }
    };
    let start = quaternion("start_orientation", &spec.start_orientation)?;
    let goal = quaternion("goal_orientation", &spec.goal_orientation)?;
    if p.orientation.is_none() {
        if let Some(field) = [(start, "start_orientation"), (goal, "goal_orientation")]
            .iter()
            .find_map(|(q, field)| q.map(|_| *field))
        {
            return Err(ServerError::invalid(
                format!("{prefix}.{field}"),
                "the primitive has no orientation (it was learned from positions only)",
            ));
        }
        return Ok((position, None));
    }
    let m = dmp::orientation::pose::pose_motion(p, position, start, goal)
        .map_err(|e| ServerError::invalid(format!("{prefix}.{}", e.field), e.rule))?;
    Ok((m.motion, Some(m.chart)))
}

/// The request's tool, for a pose primitive moving in 3-D; errors name `{prefix}.tool.*`.
fn tool(t: &v1::Tool, pose: bool, dim: usize, prefix: &str) -> Result<dmp::tool::Tool, ServerError> {
    if !pose || dim != 3 {
        return Err(ServerError::invalid(
            format!("{prefix}.tool"),
            "a tool needs a pose primitive (learned with orientations) moving in 3-D",
        ));
    }
    tool_from_proto(t, &format!("{prefix}.tool"))
}

/// The request's goal tolerance, a field left 0 (or the whole message unset) taking its default.
fn goal_tolerance(t: Option<&v1::GoalTolerance>, prefix: &str) -> Result<GoalTolerance, ServerError> {
    let default = GoalTolerance::DEFAULT;
    let Some(t) = t else { return Ok(default) };
    let or_default = |v: f64, d: f64| if v == 0.0 { d } else { v };
    let tolerance = GoalTolerance {
        position: or_default(t.position, default.position),
        speed: or_default(t.speed, default.speed),
        angle: or_default(t.angle, default.angle),
        angular_speed: or_default(t.angular_speed, default.angular_speed),
    };
    tolerance.validate().map_err(|e| e.within(&format!("{prefix}.goal_tolerance")))?;
    Ok(tolerance)
}
