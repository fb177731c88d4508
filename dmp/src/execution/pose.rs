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
    use crate::integrate::NoPerturbation;
    use crate::integrate::goal_filter::GoalFilter;
    use crate::orientation::jacobian::exp_jacobian;
    use crate::orientation::pose::{ChartChange, chart_for_goal, from_chart, to_chart};
    use crate::orientation::quaternion::{angle_between, from_xyzw};

    fn last3(v: &[f64]) -> Vector3<f64> {
        Vector3::from_column_slice(&v[v.len() - 3..])
    }

    fn set_last3(v: &mut [f64], y: &Vector3<f64>) {
        let n = v.len() - 3;
        v[n..].copy_from_slice(y.as_slice());
    }

    /// The orientation dimensions of the point `x`, `xd` in the new chart of `change`.
    fn map_point(change: &ChartChange, x: &mut [f64], xd: &mut [f64]) {
        let (y, yd) = change.velocity(&last3(x), &last3(xd));
        set_last3(x, &y);
        set_last3(xd, &yd);
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
        /// it) and the orientation (`[x, y, z, w]`, `None` keeps it; the sign nearest the chart is used). The new
        /// goal orientation is reached the short way: when it or the current orientation is more than
        /// [`crate::orientation::pose::WELL_INSIDE`] from the chart's centre, the run first moves to a chart
        /// centred halfway between them (`Execution::move_chart`). Errors name `goal` and `goal_orientation`.
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
                let q = from_xyzw("goal_orientation", q)?;
                // The current orientation: the state at the next output point.
                self.rebase();
                let current = from_chart(&chart, &last3(&self.knot0.x));
                let chart = match chart_for_goal(&chart, &current, &q) {
                    Some(to) => {
                        self.move_chart(ChartChange { from: chart, to });
                        to
                    }
                    None => chart,
                };
                goal[n..].copy_from_slice(to_chart(&chart, &q).as_slice());
            }
            self.set_goal(goal)
        }

        /// Moves a pose run's chart from the next output point on, keeping its orientation, angular velocity and
        /// angular acceleration continuous there, and the DMP's state consistent with the new chart.
        ///
        /// # Formula
        /// At the next output point (time `t`, phase `s`), with `Φ` the change of coordinates of [`ChartChange`]:
        /// - the state `(y, ẏ)` becomes `(Φ(y), J⁻¹(y') J(y) ẏ)`, as do the last point handed out, the points kept
        ///   for rollbacks and the limiter's last points (positions by `Φ`);
        /// - the goal `g` and the filtered goal `g(t)` (the goal filter's anchor, `goal_changes.rs`) become
        ///   `Φ(g)` and `Φ(g(t))`: the filter goes on from there;
        /// - the forcing term `K f(s)` keeps its chart coordinates (it is the primitive's), and the start `y_0`,
        ///   which enters only through `- K (g - y_0) s` (Ginesi et al., `eq:dmp_acc_obst`), is chosen so that the
        ///   transformation system's acceleration at `t` is the old one in the new chart, `ÿ'` of [`ChartChange`]:
        ///   `y'_0 = g'(t) + tau² (ÿ' - a) / (K s)` per dimension, `a` the acceleration with `y'_0 = g'(t)`. The
        ///   difference it absorbs (from the forcing term's and the spring's coordinates) then fades with `s`, as
        ///   the start's own term does, so the run still converges to its goal. Where `K s / tau²` is too small
        ///   for a finite `y'_0` (a phase that has run out), `y'_0 = g'(t)`, the term being negligible anyway.
        ///
        /// The obstacles' terms on a tool and the holding deceleration are left as the new chart gives them:
        /// their accelerations are continuous to first order in the angular velocity.
        fn move_chart(&mut self, change: ChartChange) {
            let d = self.primitive.dim;
            let n = d - 3;
            self.anchor_goal(self.holding);
            let (t, s, tau) = (self.out_t, self.knot0.s, self.motion.tau);
            let mut acc = vec![0.0; d];
            let (x, xd) = (&self.knot0.x, &self.knot0.xd);
            self.integrator.acceleration(&self.motion, &mut NoPerturbation, t, s, x, xd, &mut acc);
            let [y, yd, ydd] = change.motion(&last3(x), &last3(xd), &last3(&acc));
            set_last3(&mut self.knot0.x, &y);
            set_last3(&mut self.knot0.xd, &yd);
            // The goal filter restarts from the filtered goal in the new chart, towards the old goal there (the
            // caller then retargets it).
            let mut g = vec![0.0; d];
            self.integrator.goal_filter().goal_at(&self.motion.goal, t, tau, &mut g);
            let g_now = change.point(&last3(&g));
            set_last3(&mut g, &g_now);
            let old_goal = change.point(&last3(&self.motion.goal));
            set_last3(&mut self.motion.goal, &old_goal);
            let mut filter = GoalFilter::new(self.integrator.goal_filter().alpha(), &g);
            filter.anchor(&g, t, tau, self.holding);
            filter.retarget(&g, &self.motion.goal);
            *self.integrator.goal_filter_mut() = filter;
            // The start that keeps the acceleration: the acceleration is affine in it, with slope K s / tau².
            set_last3(&mut self.motion.start, &g_now);
            let (x, xd) = (&self.knot0.x, &self.knot0.xd);
            self.integrator.acceleration(&self.motion, &mut NoPerturbation, t, s, x, xd, &mut acc);
            for i in 0..3 {
                let slope = self.primitive.k[n + i] * s / (tau * tau);
                let y0 = g_now[i] + (ydd[i] - acc[n + i]) / slope;
                if y0.is_finite() {
                    self.motion.start[n + i] = y0;
                }
            }
            // Everything else kept in chart coordinates: the last point, the history, the limiter's last points.
            map_point(&change, &mut self.last_x, &mut self.last_xd);
            for (x, xd, g) in self.history.points_mut() {
                map_point(&change, x, xd);
                let y = change.point(&last3(g));
                set_last3(g, &y);
            }
            for p in self.limiter.recent_mut() {
                let y = change.point(&last3(p));
                set_last3(p, &y);
            }
            // A generator tracking the DMP takes over again from the mapped last points.
            self.tracker.reset(false);
            self.acc0_current = false;
            self.chart = Some(change.to);
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
