//! A run's start and goal against the obstacles known when it is asked for: a start or a goal inside an obstacle's
//! true shape is refused before any work (as MoveIt's START_STATE_IN_COLLISION and GOAL_IN_COLLISION), with the
//! obstacle named. The test is the engine's contact test ([`dmp::RepulsiveField::contacts`], `C <= 0`) on the robot's
//! point, or for a pose robot holding a tool on samples of the tool's true surface at that pose and its centre.

use dmp::field::{Contact, RepulsiveField, Scene};
use dmp::orientation::quaternion::from_xyzw;
use dmp::tool::{Tool, surface_samples};
use dmp::{Avoidance, Obstacle};
use dmp_proto::v1;
use nalgebra::{UnitQuaternion, Vector3};

use crate::cells::cell::Cell;
use crate::error::ServerError;
use crate::runs::control::command_rejected;

/// Samples of a tool's surface checked against the obstacles.
const TOOL_SAMPLES: usize = 64;

/// Which end of a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum End {
    /// Where it starts.
    Start,
    /// Where it goes.
    Goal,
}

impl End {
    /// The field of the motion that gives it.
    pub(crate) fn field(self) -> &'static str {
        match self {
            End::Start => "start",
            End::Goal => "goal",
        }
    }

    /// MoveIt's name for a request refused for it.
    fn moveit(self) -> &'static str {
        match self {
            End::Start => "START_STATE_IN_COLLISION",
            End::Goal => "GOAL_IN_COLLISION",
        }
    }
}

/// The robot at one end of a run: its position, and a pose robot's orientation and tool.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Placed<'a> {
    /// The position (the primitive's position dimensions).
    pub position: &'a [f64],
    /// A pose run's orientation there.
    pub orientation: Option<UnitQuaternion<f64>>,
    /// A tool held (only with an orientation).
    pub tool: Option<&'a Tool>,
}

/// The id of the first of `obstacles` (at run time 0) whose true shape holds the robot `at`; obstacles of another
/// dimension than its position are passed over. At the goal, moving obstacles are passed over too (they will be
/// elsewhere by then).
pub(crate) fn obstacle_holding<'o>(
    obstacles: impl IntoIterator<Item = &'o Obstacle>,
    at: Placed<'_>,
    end: End,
) -> Option<String> {
    let n = at.position.len();
    let kept: Vec<Obstacle> = obstacles
        .into_iter()
        .filter(|o| o.dim() == n)
        .filter(|o| end == End::Start || o.velocity().iter().all(|v| *v == 0.0))
        .cloned()
        .collect();
    if kept.is_empty() || !at.position.iter().all(|v| v.is_finite()) {
        return None;
    }
    let scene = Scene {
        obstacles: kept,
        avoidance: Avoidance::NONE,
        agents: Vec::new(),
        robot_avoidance: Avoidance::NONE,
        point_samples: 0,
    };
    let mut field = RepulsiveField::new(scene, n).ok()?;
    let mut points: Vec<Vec<f64>> = Vec::new();
    match (at.tool, at.orientation) {
        (Some(tool), Some(q)) if n == 3 => {
            let p = Vector3::from_column_slice(at.position);
            points.push((p + q * tool.offset()).as_slice().to_vec());
            points
                .extend(surface_samples(tool, TOOL_SAMPLES).iter().map(|s| (p + q * s).as_slice().to_vec()));
        }
        _ => points.push(at.position.to_vec()),
    }
    let mut contacts = Vec::new();
    for x in &points {
        contacts.clear();
        field.contacts(0.0, x, &mut contacts);
        if let Some(Contact::Obstacle { obstacle, .. }) =
            contacts.iter().find(|c| matches!(c, Contact::Obstacle { .. }))
        {
            return field.scene().obstacles.get(*obstacle).map(|o| o.id().to_owned());
        }
    }
    None
}

/// The reason a run whose `end` is inside obstacle `id` is refused (the robot's tool, with `tool`).
pub(crate) fn inside_reason(end: End, id: &str, tool: bool) -> String {
    let what = if tool { "the robot's tool" } else { "the robot" };
    match end {
        End::Start => format!(
            "{} ({what} starts inside obstacle `{id}`'s true shape): move it out, or the obstacle away, first",
            end.moveit()
        ),
        End::Goal => format!(
            "{} (the goal puts {what} inside obstacle `{id}`'s true shape): it cannot be reached",
            end.moveit()
        ),
    }
}

/// Refuses (FAILED_PRECONDITION, naming `field`, the obstacle and the end) a robot `at` the `end` of a run inside one
/// of `obstacles`.
pub(crate) fn refuse_inside<'o>(
    obstacles: impl IntoIterator<Item = &'o Obstacle>,
    at: Placed<'_>,
    end: End,
    field: &str,
) -> Result<(), ServerError> {
    match obstacle_holding(obstacles, at, end) {
        Some(id) => Err(ServerError::FailedPrecondition(format!(
            "{field}: {}",
            inside_reason(end, &id, at.tool.is_some() && at.orientation.is_some())
        ))),
        None => Ok(()),
    }
}

/// A session's new goals against the cell's obstacles as they are when each arrives (and the run's own): a goal
/// inside one is a rejected command (a warning with the next segment; the run goes on to its former goal).
#[derive(Debug, Clone)]
pub(crate) struct GoalGuard {
    /// The run's cell.
    pub cell: Cell,
    /// The run's own obstacles.
    pub extra: Vec<Obstacle>,
    /// The run ignores the cell's scene.
    pub ignore_scene: bool,
    /// A pose run's tool.
    pub tool: Option<Tool>,
}

impl GoalGuard {
    /// The warning of a new goal `position` (with a pose run's new `orientation`, `[x, y, z, w]`) inside an
    /// obstacle; `None` when it is clear (or gives no position). Without a new orientation, a tool is judged by its
    /// centre.
    pub(crate) fn rejected(&self, position: &[f64], orientation: Option<[f64; 4]>) -> Option<v1::Warning> {
        if position.is_empty() {
            return None;
        }
        let q = orientation.and_then(|q| from_xyzw("goal_orientation", q).ok());
        let snapshot = (!self.ignore_scene).then(|| self.cell.snapshot());
        let scene = snapshot.iter().flat_map(|s| s.obstacles.values().map(|o| &o.engine));
        let tool = self.tool.as_ref().filter(|_| q.is_some());
        let at = Placed { position, orientation: q, tool };
        let id = obstacle_holding(scene.chain(&self.extra), at, End::Goal)?;
        Some(command_rejected("set_goal", "goal", &inside_reason(End::Goal, &id, tool.is_some())))
    }
}

#[cfg(test)]
mod tests {
    use dmp::{Shape, Superquadric};

    use super::*;

    fn wall() -> Obstacle {
        let shape = Shape::Superquadric(Superquadric::new(vec![0.05, 0.5], vec![4.0, 4.0]).unwrap());
        Obstacle::new("wall", shape, vec![0.5, 0.0], None, None).unwrap()
    }

    fn at(position: &[f64]) -> Placed<'_> {
        Placed { position, orientation: None, tool: None }
    }

    #[test]
    fn a_point_inside_names_the_obstacle_and_one_outside_passes() {
        let w = wall();
        assert_eq!(obstacle_holding([&w], at(&[0.5, 0.1]), End::Goal).as_deref(), Some("wall"));
        assert_eq!(obstacle_holding([&w], at(&[0.8, 0.1]), End::Goal), None);
        let err = refuse_inside([&w], at(&[0.5, 0.0]), End::Start, "motion.start").unwrap_err();
        assert!(
            matches!(&err, ServerError::FailedPrecondition(m)
                if m.starts_with("motion.start: START_STATE_IN_COLLISION") && m.contains("`wall`")),
            "{err}"
        );
    }

    #[test]
    fn a_moving_obstacle_is_not_held_against_the_goal_and_other_dimensions_are_passed_over() {
        let shape = Shape::Superquadric(Superquadric::ellipsoid(vec![0.2, 0.2]).unwrap());
        let moving = Obstacle::new("cart", shape, vec![0.0, 0.0], None, Some(vec![1.0, 0.0])).unwrap();
        assert_eq!(obstacle_holding([&moving], at(&[0.0, 0.0]), End::Start).as_deref(), Some("cart"));
        assert_eq!(obstacle_holding([&moving], at(&[0.0, 0.0]), End::Goal), None);
        assert_eq!(obstacle_holding([&moving], at(&[0.0, 0.0, 0.0]), End::Start), None);
    }

    #[test]
    fn a_tool_that_reaches_into_an_obstacle_is_inside_it() {
        let ball = |r: f64| Shape::Superquadric(Superquadric::new(vec![r; 3], vec![1.0; 3]).unwrap());
        let o = Obstacle::new("ball", ball(0.2), vec![0.5, 0.0, 0.0], None, None).unwrap();
        let tool = Tool::new(ball(0.35), [0.0; 3], dmp::tool::ControlPoints::default()).unwrap();
        let placed =
            |tool| Placed { position: &[0.0, 0.0, 0.0], orientation: Some(UnitQuaternion::identity()), tool };
        assert_eq!(obstacle_holding([&o], placed(None), End::Goal), None);
        assert_eq!(obstacle_holding([&o], placed(Some(&tool)), End::Goal).as_deref(), Some("ball"));
    }
}
