//! The run's internal grid: the knot after `knot0`, by one RK4 step of `step_points` output steps, by an adaptive
//! Dormand–Prince 5(4) step, or by the exact holding deceleration.

use super::Execution;
use super::diagnosis::{Diagnosis, step_is_finite};
use super::field_sum::FieldSum;
use super::hold::{hold_acc, hold_step};
use crate::dense::Knot;
use crate::integrate::dormand_prince;

/// The run's fields and its coupling term at a state, for one step ([`FieldSum`]); a macro, so that the borrow is of
/// the fields it names, not of the whole run.
macro_rules! field_sum {
    ($run:ident, $diagnosis:expr) => {
        FieldSum::new(
            &mut $run.field,
            &mut $run.blend,
            &mut $run.cell_mates,
            $diagnosis,
            $run.tool.as_ref(),
            $run.chart.as_ref(),
        )
        .coupled($run.tau_rate)
    };
}

impl Execution {
    /// Computes the knot after `knot0` (one RK4 step of `step_points` output steps, an adaptive step, or the exact
    /// holding deceleration), and the accelerations at both knots under the current field and motion.
    ///
    /// A step that is not finite is redone while each obstacle's term is checked at the states it evaluates; the
    /// obstacles (or cell-mates) whose term is not finite are dropped for the rest of the run and reported, and the
    /// step is computed again without them. A step that is not finite without any obstacle is left as it is (the
    /// points are then refused as diverged).
    pub(super) fn next_knot(&mut self) {
        let mut k1 = self
            .knot1
            .take()
            .or_else(|| self.spare.take())
            .unwrap_or_else(|| Knot::zeros(self.primitive.dim));
        // The adaptive step's proposal, for a step computed again.
        let proposal = self.next_points;
        self.step(&mut k1, None);
        while !self.holding && !step_is_finite(&self.knot0, &self.scratch, &k1.xdd) {
            let start_finite = self.knot0.x.iter().chain(&self.knot0.xd).all(|v| v.is_finite());
            let mut diagnosis = Diagnosis::default();
            self.acc0_current = false;
            self.next_points = proposal;
            self.step(&mut k1, Some(&mut diagnosis));
            if !start_finite || !self.drop_culprits(&diagnosis) {
                break;
            }
            self.next_points = proposal;
            self.step(&mut k1, None);
        }
        if self.holding || self.stepping.tolerance.is_some() {
            // Holding does not reuse it; an adaptive step's is exact.
            self.knot1_acc = !self.holding;
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

    /// One step from `knot0` into the scratch state, with the accelerations at both ends (`knot0.xdd`, `k1.xdd`).
    fn step(&mut self, k1: &mut Knot, diagnosis: Option<&mut Diagnosis>) {
        let h = self.stepping.internal_step();
        self.start_from_knot0();
        let s = &mut self.scratch;
        if let (Some(tol), false) = (self.stepping.tolerance, self.holding) {
            self.adaptive_step(tol, k1, diagnosis);
        } else if self.holding {
            hold_step(&self.primitive, self.base_tau, s, h, &mut self.knot0.xdd);
            hold_acc(&self.primitive, self.base_tau, &s.xd, &mut k1.xdd);
        } else {
            let mut both = field_sum!(self, diagnosis);
            let known = self.acc0_current;
            // The end knot's acceleration: for the points interpolated before it on a coarse step, and at RK4 on
            // every point when the output runs a point ahead of knot0 (after a restart at a point handed out),
            // so that the point handed out is the end knot itself.
            let dt = self.stepping.dt;
            let end_needed = self.stepping.step_points > 1 || self.out_t > self.knot0.t + 0.5 * dt;
            self.integrator.step_from(&self.motion, &mut both, s, h, &mut self.knot0.xdd, known);
            self.cost.steps += 1;
            self.cost.evaluations += 3 + u64::from(!known) + u64::from(end_needed);
            self.knot1_acc = end_needed;
            if end_needed {
                s.t = (s.t / self.stepping.dt).round() * self.stepping.dt;
                self.integrator.acceleration(&self.motion, &mut both, s.t, s.s, &s.x, &s.xd, &mut k1.xdd);
            }
        }
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
    fn adaptive_step(&mut self, tol: f64, k1: &mut Knot, mut diagnosis: Option<&mut Diagnosis>) {
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
            let diagnosis = diagnosis.as_deref_mut();
            let mut both = field_sum!(self, diagnosis);
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
