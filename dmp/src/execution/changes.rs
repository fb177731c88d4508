//! Changes of a run: goal, `tau` and start, pause, resume and stop, each from the next output point on (the
//! position and the velocity stay continuous), and rollbacks to a recent point.

use super::Execution;
use super::stepping::check_stability;
use crate::dense::interpolate;
use crate::error::{InvalidInput, Result, check_vector};
use crate::integrate::State;

impl Execution {
    /// Changes the goal from the next output point on: the goal the DMP steers to moves there through the goal
    /// filter ([`Execution::set_goal_filter`]; on by default), so that the acceleration stays continuous.
    pub fn set_goal(&mut self, goal: Vec<f64>) -> Result<(), InvalidInput> {
        check_vector("goal", &goal, self.primitive.dim)?;
        self.restart_at_output();
        self.rebase();
        self.anchor_goal(self.holding);
        self.integrator.goal_filter_mut().retarget(&self.motion.goal, &goal);
        self.motion.goal = goal;
        // Arrival is judged afresh against the new goal, from the next point on.
        self.goal_met_since = None;
        Ok(())
    }

    /// Starts the run at velocity `v` (`dx/dt`, every dimension) instead of at rest, from its start: a run that
    /// takes over a robot already moving (a session resumed on another server after a fail-over) keeps the robot's
    /// velocity continuous. Only before the run's first output point; the limiter takes the robot as having moved
    /// at `v` until then.
    pub fn set_start_velocity(&mut self, v: Vec<f64>) -> Result<(), InvalidInput> {
        check_vector("start_velocity", &v, self.primitive.dim)?;
        if self.has_last || self.out_t > 0.0 {
            return Err(InvalidInput::new("start_velocity", "can only be set before the run's first point"));
        }
        self.knot0.xd.copy_from_slice(&v);
        self.scratch.xd.copy_from_slice(&v);
        self.knot1 = None;
        self.acc0_current = false;
        self.restore_limiter();
        Ok(())
    }

    /// Changes `tau` from the next output point on (the state keeps `dx/dt`, so the velocity is continuous).
    pub fn set_tau(&mut self, tau: f64) -> Result<(), InvalidInput> {
        if !(tau.is_finite() && tau > 0.0) {
            return Err(InvalidInput::new("tau", "must be a finite number greater than zero"));
        }
        check_stability(&self.primitive.k, self.stepping.internal_step(), tau, "tau")?;
        self.rebase();
        self.anchor_goal(self.holding);
        self.base_tau = tau;
        self.motion.tau = tau * self.tau_scale;
        Ok(())
    }

    /// Holds (decelerates to rest under the DMP's damping, phase frozen) or resumes. A stop is not resumed.
    pub fn set_holding(&mut self, holding: bool) {
        let holding = holding || self.stopping;
        if holding != self.holding {
            if holding {
                self.restart_at_output();
            }
            self.rebase();
            self.anchor_goal(holding);
        }
        self.holding = holding;
    }

    /// Decelerates to rest and ends there ([`super::Outcome::Stopped`]); nothing resumes it.
    pub fn stop(&mut self) {
        self.stopping = true;
        self.set_holding(true);
    }

    /// Rolls back to the first recorded output point at or after `t` (no-op when `t` is at or past the current
    /// time, or older than the history): the points from there on will be computed again, under the changes made
    /// after this call. Returns the time the run continues from.
    pub fn rollback_to(&mut self, t: f64) -> f64 {
        if t >= self.out_t {
            return self.out_t;
        }
        let mut restored = std::mem::replace(&mut self.scratch, State::at_rest(&[]));
        let mut g = std::mem::take(&mut self.rollback_g);
        if self.history.rollback_into(t, 0.5 * self.stepping.dt, &mut restored, &mut g) {
            self.integrator.goal_filter_mut().restore(restored.t, &g, &self.motion.goal);
            self.restart_at(&restored);
            self.restore_limiter();
            self.guard.rollback(restored.t - self.stepping.dt, &self.limiter);
            // The last point handed out is now the one before the restored point.
            match self.history.last() {
                Some((x, xd)) => {
                    self.last_x.copy_from_slice(x);
                    self.last_xd.copy_from_slice(xd);
                }
                None => self.has_last = false,
            }
        }
        self.scratch = restored;
        self.rollback_g = g;
        self.forget_goal_after(self.out_t);
        self.out_t
    }

    /// Restarts the internal grid at `s` (an output point): the next knot is computed afresh.
    fn restart_at(&mut self, s: &State) {
        self.knot0.t = s.t;
        self.knot0.s = s.s;
        self.knot0.x.clone_from(&s.x);
        self.knot0.xd.clone_from(&s.xd);
        self.spare = self.knot1.take().or(self.spare.take());
        self.acc0_current = false;
        // The restored point was handed out by the DMP, not the limiter; the coupling's rate is decided again at
        // the next period.
        self.tau_rate = 0.0;
        self.out_t = s.t;
    }

    /// Restarts the internal grid at the next output point, so that a change applies from there: the point is
    /// interpolated between the current knots (it is what RK4 at the output rate would hold there, to the
    /// interpolation's accuracy).
    pub(super) fn rebase(&mut self) {
        // Whatever changes, the field or the motion no longer gives the acceleration stored at knot0.
        self.acc0_current = false;
        let Some(k1) = self.knot1.take() else { return };
        if self.out_t < k1.t - 0.5 * self.stepping.dt {
            self.cost.restarts += 1;
        }
        if self.out_t > self.knot0.t {
            // Into the scratch state, then the knot: no allocation (this runs every stretch with cell-mates).
            let st = &mut self.scratch;
            st.s = interpolate(&self.knot0, &k1, self.out_t, &mut st.x, &mut st.xd, &mut self.xdd);
            self.knot0.t = self.out_t;
            self.knot0.s = st.s;
            self.knot0.x.copy_from_slice(&st.x);
            self.knot0.xd.copy_from_slice(&st.xd);
        }
        // The next knot is computed afresh, in these buffers.
        self.spare = Some(k1);
    }
}
