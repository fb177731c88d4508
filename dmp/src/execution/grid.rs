//! The run's internal grid: the knot after `knot0`, by one RK4 step of `step_points` output steps, by an adaptive
//! Dormand–Prince 5(4) step, or by the exact holding deceleration.

use super::Execution;
use super::hold::{hold_acc, hold_step};
use crate::dense::Knot;
use crate::field::RepulsiveField;
use crate::integrate::{Perturbation, dormand_prince};

/// The run's field and its cell-mates' field, summed.
struct FieldSum<'a>(&'a mut RepulsiveField, &'a mut RepulsiveField);

impl Perturbation for FieldSum<'_> {
    fn add(&mut self, t: f64, x: &[f64], v: &[f64], tau: f64, out: &mut [f64]) {
        self.0.add(t, x, v, tau, out);
        self.1.add(t, x, v, tau, out);
    }
}

impl Execution {
    /// Computes the knot after `knot0` (one RK4 step of `step_points` output steps, an adaptive step, or the
    /// exact holding deceleration), and the accelerations at both knots under the current field and motion.
    pub(super) fn next_knot(&mut self) {
        let h = self.stepping.internal_step();
        let mut k1 = self
            .knot1
            .take()
            .or_else(|| self.spare.take())
            .unwrap_or_else(|| Knot::zeros(self.primitive.dim));
        self.start_from_knot0();
        let s = &mut self.scratch;
        if let (Some(tol), false) = (self.stepping.tolerance, self.holding) {
            self.adaptive_step(tol, &mut k1);
        } else if self.holding {
            hold_step(&self.primitive, self.motion.tau, s, h, &mut self.knot0.xdd);
            hold_acc(&self.primitive, self.motion.tau, &s.xd, &mut k1.xdd);
        } else {
            let mut both = FieldSum(&mut self.field, &mut self.cellmates);
            let known = self.acc0_current;
            self.integrator.step_from(&self.motion, &mut both, s, h, &mut self.knot0.xdd, known);
            self.cost.steps += 1;
            self.cost.evaluations += 3 + u64::from(!known) + u64::from(self.stepping.step_points > 1);
            if self.stepping.step_points > 1 {
                s.t = (s.t / self.stepping.dt).round() * self.stepping.dt;
                self.integrator.acceleration(&self.motion, &mut both, s.t, s.s, &s.x, &s.xd, &mut k1.xdd);
            }
        }
        // Times are whole multiples of dt, not a drifting sum.
        let s = &mut self.scratch;
        s.t = (s.t / self.stepping.dt).round() * self.stepping.dt;
        k1.t = s.t;
        k1.s = s.s;
        k1.x.clone_from(&s.x);
        k1.xd.clone_from(&s.xd);
        self.knot1 = Some(k1);
    }

    /// The scratch state at `knot0`, where a step starts.
    fn start_from_knot0(&mut self) {
        let s = &mut self.scratch;
        s.t = self.knot0.t;
        s.s = self.knot0.s;
        s.x.clone_from(&self.knot0.x);
        s.xd.clone_from(&self.knot0.xd);
    }

    /// One adaptive step from `knot0` into the scratch state, with the accelerations at both ends (`knot0.xdd`,
    /// `k1.xdd`): the step tried is the controller's last proposal (cut at the knot limit), shrunk and retried
    /// from `knot0` while its error is above the tolerance and it is longer than one output step.
    fn adaptive_step(&mut self, tol: f64, k1: &mut Knot) {
        let max = self.stepping.step_points;
        let mut points = self.next_points.clamp(1, max);
        let to_limit = ((self.knot_limit - self.knot0.t) / self.stepping.dt).round();
        let limited = to_limit >= 1.0 && to_limit < points as f64;
        if limited {
            points = to_limit as usize;
        }
        let mut known = self.acc0_current;
        let mut retried = false;
        loop {
            let h = points as f64 * self.stepping.dt;
            let mut both = FieldSum(&mut self.field, &mut self.cellmates);
            let err = self.integrator.step_dormand_prince(
                &self.motion,
                &mut both,
                &mut self.scratch,
                h,
                &mut self.knot0.xdd,
                known,
                &mut k1.xdd,
                tol,
            );
            self.cost.evaluations += 6 + u64::from(!known);
            known = true;
            let proposal = (dormand_prince::next_step(points as f64, err).floor() as usize).clamp(1, max);
            if err <= 1.0 || points == 1 {
                // A step cut at the limit says nothing against the longer one proposed before it; right after a
                // rejection, the step does not grow.
                self.next_points = match (limited, retried) {
                    (_, true) => proposal.min(points),
                    (true, false) => proposal.max(self.next_points),
                    (false, false) => proposal,
                };
                self.cost.steps += 1;
                return;
            }
            self.cost.rejected += 1;
            retried = true;
            points = proposal.min(points - 1);
            self.start_from_knot0();
        }
    }
}
