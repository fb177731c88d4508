//! Checking an input for consistency before anything is drawn: the trajectories, the demonstration and the goal
//! against each other, then the obstacles, true shapes, clearance series and pose against the robots.

use super::group::Group;
use super::input::PlotInput;
use crate::error::PlotError;

/// Checks the trajectories, the demonstration and the goal against each other; returns the DMP dimension `d`.
pub(crate) fn dmp_dimension(input: &PlotInput<'_>) -> Result<usize, PlotError> {
    if input.adapted.is_empty() {
        return Err(PlotError::EmptyTrajectory("adapted"));
    }
    let d = input.adapted.dim();
    if d == 0 {
        return Err(PlotError::Dimension { what: "the adapted trajectory".into(), expected: 1, found: 0 });
    }
    if input.free.dim() != d {
        return Err(PlotError::Dimension {
            what: "the obstacle-free trajectory".into(),
            expected: d,
            found: input.free.dim(),
        });
    }
    for (k, row) in input.demonstration.iter().enumerate() {
        if row.len() != d {
            return Err(PlotError::Dimension {
                what: format!("demonstration row {k}"),
                expected: d,
                found: row.len(),
            });
        }
    }
    if let Some(t) = input.demonstration_t
        && t.len() != input.demonstration.len()
    {
        return Err(PlotError::Length {
            what: "the demonstration's times".into(),
            expected: input.demonstration.len(),
            found: t.len(),
        });
    }
    if let Some(goal) = input.goal
        && goal.len() != d
    {
        return Err(PlotError::Dimension { what: "the goal".into(), expected: d, found: goal.len() });
    }
    Ok(d)
}

/// Checks the obstacles and true shapes against the robots' dimension, the clearance series against the robots,
/// and a pose run's orientations against the trajectories (a pose run has one robot moving in 3-D).
pub(crate) fn against_robots(input: &PlotInput<'_>, groups: &[Group<'_>]) -> Result<(), PlotError> {
    let sub = groups[0].dims.len();
    for o in input.obstacles {
        if o.dim() != sub {
            return Err(PlotError::Dimension {
                what: format!("obstacle `{}`", o.id()),
                expected: sub,
                found: o.dim(),
            });
        }
    }
    for s in input.solids {
        if s.center.len() != sub {
            return Err(PlotError::Dimension {
                what: format!("solid `{}`", s.id),
                expected: sub,
                found: s.center.len(),
            });
        }
    }
    if let Some(series) = input.clearance {
        if series.len() != groups.len() {
            return Err(PlotError::Length {
                what: "the clearance series".into(),
                expected: groups.len(),
                found: series.len(),
            });
        }
        for (k, s) in series.iter().enumerate() {
            if s.t.len() != s.v.len() {
                return Err(PlotError::Length {
                    what: format!("clearance series {k}'s values"),
                    expected: s.t.len(),
                    found: s.v.len(),
                });
            }
        }
    }
    if let Some(pose) = &input.pose {
        if sub != 3 || groups.len() != 1 {
            return Err(PlotError::Dimension { what: "a pose run's robot".into(), expected: 3, found: sub });
        }
        pose.validate(input.adapted.len(), input.free.len())?;
    }
    Ok(())
}
