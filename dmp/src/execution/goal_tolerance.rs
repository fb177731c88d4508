//! "At the goal and at rest": the tolerance a run's arrival is judged with, and the time it was first met.
//!
//! A member has arrived when, at an output point, `|x - g| <= position` and `|dx/dt| <= speed` (Euclidean norms over
//! its dimensions, in the units of its demonstration). The run reaches its goal ([`super::Outcome::GoalReached`])
//! when every member has arrived at the last point of a stretch; [`Execution::goal_met_since`] is the time of the
//! first point of the unbroken run of points, up to there, at which every member had arrived.
//!
//! A pose run's orientation has arrived when the angle between it and the goal orientation is at most `angle` and
//! `|ω| <= angular_speed`.
//!
//! The defaults ([`GoalTolerance::DEFAULT`]: 1 mm and 1 mm/s, 1 mrad and 1 mrad/s) are tight on purpose: a robot handed its last
//! setpoint at 1 mm/s stops with a velocity step of at most that. A demonstration that ends while still moving
//! (the paper's curve ends at about 3.3 m/s) passes its goal at `t = tau` and comes back to it, so it arrives well
//! after `tau`; a looser `speed` ends such a run earlier, with a larger step.

use super::Execution;
use crate::error::InvalidInput;

/// The tolerance of "at the goal and at rest", per member.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GoalTolerance {
    /// Largest distance to the goal, in the demonstration's units (metres for a Cartesian robot).
    pub position: f64,
    /// Largest speed, in the demonstration's units per second.
    pub speed: f64,
    /// A pose run: largest angle to the goal orientation, radians.
    pub angle: f64,
    /// A pose run: largest angular speed `|ω|`, rad/s.
    pub angular_speed: f64,
}

impl GoalTolerance {
    /// 1 mm (1e-3) and 1 mm/s (1e-3); 1 mrad (0.057°) and 1 mrad/s.
    pub const DEFAULT: Self = Self { position: 1e-3, speed: 1e-3, angle: 1e-3, angular_speed: 1e-3 };

    /// The default angular tolerance with this position and speed.
    pub const fn linear(position: f64, speed: f64) -> Self {
        Self { position, speed, ..Self::DEFAULT }
    }

    /// Every field finite and greater than zero.
    pub fn validate(&self) -> Result<(), InvalidInput> {
        let fields = [
            ("position", self.position),
            ("speed", self.speed),
            ("angle", self.angle),
            ("angular_speed", self.angular_speed),
        ];
        for (field, v) in fields {
            if !(v.is_finite() && v > 0.0) {
                return Err(InvalidInput::new(
                    field,
                    format!("must be a finite number greater than zero, not {v}"),
                ));
            }
        }
        Ok(())
    }
}

impl Default for GoalTolerance {
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl Execution {
    /// Judges arrival with `tolerance` from the next output point on.
    pub fn set_goal_tolerance(&mut self, tolerance: GoalTolerance) -> Result<(), InvalidInput> {
        tolerance.validate().map_err(|e| e.within("goal_tolerance"))?;
        self.goal_tolerance = tolerance;
        Ok(())
    }

    /// The tolerance arrival is judged with.
    pub fn goal_tolerance(&self) -> GoalTolerance {
        self.goal_tolerance
    }

    /// The time since which every member has been at its goal and at rest, at every output point handed out up to
    /// the last one; `None` when they are not at the last one, or the goal changed since.
    pub fn goal_met_since(&self) -> Option<f64> {
        self.goal_met_since
    }

    /// Whether every member is within the tolerance at the point `x`, `xd`.
    pub(super) fn within_goal_tolerance(&self, x: &[f64], xd: &[f64]) -> bool {
        let tol = self.goal_tolerance;
        self.members().iter().all(|m| {
            let dist2: f64 = m.dims.iter().map(|&i| (x[i] - self.motion.goal[i]).powi(2)).sum();
            let speed2: f64 = m.dims.iter().map(|&i| xd[i].powi(2)).sum();
            dist2 <= tol.position * tol.position && speed2 <= tol.speed * tol.speed
        }) && self.orientation_within_tolerance(x, xd)
    }

    /// Follows [`Execution::goal_met_since`] over the `n` points of a stretch starting at `start_time`. Holding
    /// points (a pause) never count as arrived.
    pub(super) fn track_goal(&mut self, start_time: f64, x: &[f64], xd: &[f64], n: usize) {
        let d = self.primitive.dim;
        let dt = self.stepping.dt;
        for k in 0..n {
            let met =
                !self.holding && self.within_goal_tolerance(&x[k * d..(k + 1) * d], &xd[k * d..(k + 1) * d]);
            self.goal_met_since = match (met, self.goal_met_since) {
                (false, _) => None,
                (true, Some(since)) => Some(since),
                (true, None) => Some(start_time + k as f64 * dt),
            };
        }
    }

    /// After a rollback to `t`: a first-met time at or after it is for points that will be computed again.
    pub(super) fn forget_goal_after(&mut self, t: f64) {
        if self.goal_met_since.is_some_and(|since| since >= t - 0.5 * self.stepping.dt) {
            self.goal_met_since = None;
        }
    }
}
