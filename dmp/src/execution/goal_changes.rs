//! The goal filter of a run ([`crate::integrate::goal_filter`]): a new goal is approached through
//! `tau dg/dt = alpha_g (g_new - g)`, on by default with `alpha_g =`
//! [`DEFAULT_GOAL_ALPHA`](crate::integrate::goal_filter::DEFAULT_GOAL_ALPHA). The filter is re-anchored at the next
//! output point by every change that affects it (goal, `tau`, pause, resume and stop), and a rollback restores the
//! filtered goal recorded with the point it returns to, so that the filtered goal is as continuous as the state.

use super::Execution;
use crate::error::InvalidInput;

impl Execution {
    /// Sets `alpha_g` of the goal filter from the next output point on; 0 switches it off (a new goal then applies
    /// as a step, the behaviour before the filter). Refused (naming `goal_filter_alpha`) unless finite and
    /// non-negative.
    pub fn set_goal_filter(&mut self, alpha: f64) -> Result<(), InvalidInput> {
        if !(alpha.is_finite() && alpha >= 0.0) {
            return Err(InvalidInput::new(
                "goal_filter_alpha",
                format!("must be a finite number, zero (off) or greater, not {alpha}"),
            ));
        }
        self.rebase();
        let (t, tau) = (self.out_t, self.motion.tau);
        self.integrator.goal_filter_mut().set_alpha(alpha, &self.motion.goal, t, tau);
        Ok(())
    }

    /// `alpha_g` of the goal filter (0: off).
    pub fn goal_filter_alpha(&self) -> f64 {
        self.integrator.goal_filter().alpha()
    }

    /// The goal the DMP steers to at run time `t` (at or after the last change): the filtered goal while a change
    /// is being filtered, the motion's goal otherwise.
    #[cfg(test)]
    pub(crate) fn filtered_goal_at(&self, t: f64, out: &mut [f64]) {
        self.integrator.goal_filter().goal_at(&self.motion.goal, t, self.motion.tau, out);
    }

    /// Re-anchors the goal filter at the next output point (after a rebase), under the goal and `tau` in force
    /// until then; `holding` from there on.
    pub(super) fn anchor_goal(&mut self, holding: bool) {
        let (t, tau) = (self.out_t, self.motion.tau);
        self.integrator.goal_filter_mut().anchor(&self.motion.goal, t, tau, holding);
    }
}
