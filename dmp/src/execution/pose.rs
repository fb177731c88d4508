//! Pose runs: a primitive whose last three dimensions are the rotation vector of the orientation in a chart
//! ([`crate::OrientationChart`], [`crate::orientation::pose`]). The run's one robot owns the position dimensions
//! (obstacles, cell-mates and contacts act on them only); the orientation dimensions follow Koutras and Doulgeri's
//! DMP on the same phase, so every change (goal, `tau`, pause, stop, rollback) acts on both.

use super::{Execution, Stretch};
use crate::error::{InvalidInput, Result};
use crate::primitive::Primitive;

/// Orientations, angular velocities and angular accelerations of points of a pose run (empty for a position run).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct OrientationPoints {
    /// `[x, y, z, w]` per point, continuous in sign along the points.
    pub q: Vec<f64>,
    /// `ω`, world frame, rad/s, 3 per point.
    pub omega: Vec<f64>,
    /// `ω̇`, world frame, rad/s², 3 per point.
    pub omega_dot: Vec<f64>,
}

/// The chart of a pose run, or nothing (the crate built without orientation has no pose runs).
#[cfg(feature = "orientation")]
pub(super) type Chart = nalgebra::UnitQuaternion<f64>;
#[cfg(not(feature = "orientation"))]
pub(super) type Chart = std::convert::Infallible;

/// A tool held by a pose run ([`crate::tool`]), or nothing.
#[cfg(feature = "orientation")]
pub(super) type HeldTool = crate::tool::Tool;
#[cfg(not(feature = "orientation"))]
pub(super) type HeldTool = std::convert::Infallible;

/// The chart of a primitive: its own (a learned pose primitive's is at its goal).
pub(super) fn chart_of(p: &Primitive) -> Result<Option<Chart>> {
    #[cfg(feature = "orientation")]
    {
        Ok(crate::orientation::pose::chart_of(p)?)
    }
    #[cfg(not(feature = "orientation"))]
    match p.orientation {
        None => Ok(None),
        Some(_) => Err(InvalidInput::new("orientation", "this build has no orientation DMPs").into()),
    }
}

#[cfg(not(feature = "orientation"))]
impl Execution {
    pub(super) fn orientation_within_tolerance(&self, _: &[f64], _: &[f64]) -> bool {
        true
    }

    pub(super) fn fill_orientations(&self, _: &mut Stretch) {}
}

#[cfg(feature = "orientation")]
mod with_orientation {
    use nalgebra::{UnitQuaternion, Vector3};

    use super::OrientationPoints;
    use super::{Execution, InvalidInput, Stretch};
    use crate::error::check_vector;
    use crate::orientation::jacobian::exp_jacobian;
    use crate::orientation::pose::{from_chart, to_chart};
    use crate::orientation::quaternion::{angle_between, from_xyzw};

    fn last3(v: &[f64]) -> Vector3<f64> {
        Vector3::from_column_slice(&v[v.len() - 3..])
    }

    impl Execution {
        /// Puts the run's orientation dimensions in the chart at `chart` (e.g. a replay's goal,
        /// [`crate::orientation::pose::pose_motion`]); only before the first point, and only for a pose primitive.
        pub fn set_orientation_chart(&mut self, chart: UnitQuaternion<f64>) -> Result<(), InvalidInput> {
            if self.chart.is_none() {
                return Err(InvalidInput::new("orientation", "the primitive has no orientation"));
            }
            if self.has_last || self.out_t != 0.0 {
                return Err(InvalidInput::new("orientation", "the chart is set before the first point"));
            }
            self.chart = Some(chart);
            Ok(())
        }

        /// Changes a pose run's goal from the next output point on: the position part (`n` values, `None` keeps
        /// it) and the orientation (`[x, y, z, w]`, `None` keeps it; the sign nearest the chart is used). Errors
        /// name `goal` and `goal_orientation`.
        pub fn set_pose_goal(
            &mut self,
            position: Option<Vec<f64>>,
            orientation: Option<[f64; 4]>,
        ) -> Result<(), InvalidInput> {
            let Some(chart) = self.chart else {
                if orientation.is_some() {
                    return Err(InvalidInput::new("goal_orientation", "the run has no orientation"));
                }
                return match position {
                    Some(goal) => self.set_goal(goal),
                    None => Ok(()),
                };
            };
            let n = self.primitive.dim - 3;
            let mut goal = self.motion.goal.clone();
            if let Some(p) = position {
                check_vector("goal", &p, n)?;
                goal[..n].copy_from_slice(&p);
            }
            if let Some(q) = orientation {
                let y = to_chart(&chart, &from_xyzw("goal_orientation", q)?);
                goal[n..].copy_from_slice(y.as_slice());
            }
            self.set_goal(goal)
        }

        /// Whether a pose run's orientation is within the goal tolerance at the point `x`, `xd` (true for a
        /// position run).
        pub(in crate::execution) fn orientation_within_tolerance(&self, x: &[f64], xd: &[f64]) -> bool {
            let Some(chart) = &self.chart else { return true };
            let tol = self.goal_tolerance;
            let y = last3(x);
            let goal = from_chart(chart, &last3(&self.motion.goal));
            let omega = exp_jacobian(&y) * last3(xd);
            omega.norm() <= tol.angular_speed && angle_between(&from_chart(chart, &y), &goal) <= tol.angle
        }

        /// Fills a pose run's orientations, angular velocities and accelerations.
        pub(in crate::execution) fn fill_orientations(&self, p: &mut Stretch) {
            if let Some(chart) = &self.chart {
                p.orientation = OrientationPoints::of(chart, self.primitive.dim, &p.x, &p.xd, &p.xdd);
            }
        }
    }
}

#[cfg(not(feature = "orientation"))]
impl Execution {
    pub(super) fn tool_margin(&self) -> f64 {
        0.0
    }
}
