//! Advancing a run: the next output points, their contacts and stalls, and what they came to.

use super::{Execution, LimitAction, Outcome, Stretch};
use crate::error::{DmpError, Result};
use crate::field::Contact;
use crate::stall::{StallConfig, StallDetector};

impl Execution {
    /// Computes the next `n` output points, advancing the run. Fails if the state stops being finite (which the
    /// stability check on the step and `tau` should prevent); nothing from that point on is handed out.
    ///
    /// The stretch's outcome is, in this order: [`Outcome::Stopped`] once a stop has come to rest;
    /// [`Outcome::GoalReached`] when every member is at its goal and at rest (within [`Execution::goal_tolerance`],
    /// since [`Execution::goal_met_since`]), and nothing below happened in the stretch; [`Outcome::EndTime`] when its last point is at the end time; otherwise [`Outcome::Collision`] (a
    /// contact in the stretch), [`Outcome::Stalled`], [`Outcome::Holding`] or [`Outcome::Running`].
    pub fn advance(&mut self, n: usize) -> Result<Stretch> {
        let d = self.primitive.dim;
        let dt = self.stepping.dt;
        let mut p = Stretch {
            start_time: self.out_t,
            x: vec![0.0; n * d],
            xd: vec![0.0; n * d],
            xdd: vec![0.0; n * d],
            ..Stretch::default()
        };
        self.stretch_s.clear();
        self.stretch_generated.clear();
        self.stretch_g.resize(n * d, 0.0);
        for k in 0..n {
            let t = self.out_t;
            if self.knot1.as_ref().is_none_or(|k1| t >= k1.t - 0.5 * dt) {
                if let Some(k1) = self.knot1.take() {
                    // Step to the next knot: the old one is done with.
                    let old = std::mem::replace(&mut self.knot0, k1);
                    self.knot1 = Some(old);
                    // Its acceleration was evaluated at its exact state (a coarse step) under the field and
                    // motion still in force (a change would have rebased and dropped it).
                    self.acc0_current = self.knot1_acc && !self.holding;
                }
                self.next_knot();
                let Some(k1) = self.knot1.as_ref() else { unreachable!("next_knot sets knot1") };
                self.interpolant.fit(&self.knot0, k1);
            }
            let Some(k1) = self.knot1.as_ref() else { unreachable!("knot1 is set above") };
            let range = k * d..(k + 1) * d;
            let s = self.interpolant.eval(
                &self.knot0,
                k1,
                t,
                &mut p.x[range.clone()],
                &mut p.xd[range.clone()],
                &mut p.xdd[range.clone()],
            );
            if !p.x[range.clone()]
                .iter()
                .chain(&p.xd[range.clone()])
                .chain(&p.xdd[range.clone()])
                .all(|v| v.is_finite())
            {
                return Err(DmpError::Diverged { t });
            }
            self.stretch_s.push(s);
            self.integrator.goal_filter().goal_at(
                &self.motion.goal,
                t,
                self.motion.tau,
                &mut self.stretch_g[range.clone()],
            );
            self.out_t = ((t + dt) / dt).round() * dt;
            let action = self.keep_limits(
                &mut p.x[range.clone()],
                &mut p.xd[range.clone()],
                &mut p.xdd[range.clone()],
            );
            p.limit = p.limit.max(action);
            self.stretch_generated
                .push(matches!(action, LimitAction::Limited | LimitAction::Braking | LimitAction::Blocked));

            // Stalls at the point handed out (checked at its time); contacts below, for all points.
            if self.holding || action == LimitAction::Blocked {
                // At rest on purpose (held, or before the safety distance): not a stall.
                for (det, m) in self.stall.iter_mut().zip(self.field.agents()) {
                    *det = StallDetector::new(StallConfig::default(), m.dims.clone());
                }
            } else {
                for (i, det) in self.stall.iter_mut().enumerate() {
                    if let Some(stall) =
                        det.update(t, &p.x[range.clone()], &p.xd[range.clone()], &self.motion.goal)
                    {
                        p.stalls.push((i, stall));
                    }
                }
            }
        }
        self.history.push(
            p.start_time,
            &self.stretch_s,
            &p.x,
            &p.xd,
            &p.xdd,
            &self.stretch_g,
            &self.stretch_generated,
        );
        self.track_goal(p.start_time, &p.x, &p.xd, n);
        if n > 0 {
            self.last_x.copy_from_slice(&p.x[(n - 1) * d..]);
            self.last_xd.copy_from_slice(&p.xd[(n - 1) * d..]);
            self.has_last = true;
        }
        // Contacts at every point handed out (each checked at its time); obstacles no point can reach are skipped
        // as a whole.
        self.field.contacts_along(p.start_time, dt, &p.x, n, &mut p.contacts);
        self.cell_mates.contacts_along(p.start_time, dt, &p.x, n, &mut p.cell_mate_contacts);
        #[cfg(feature = "orientation")]
        self.tool_contacts(p.start_time, &p.x, n, &mut p.contacts, &mut p.cell_mate_contacts);
        for (fi, contacts) in [&p.contacts, &p.cell_mate_contacts].into_iter().enumerate() {
            let f = if fi == 0 { &self.field } else { &self.cell_mates };
            for (_, c) in contacts {
                let id = match *c {
                    Contact::Obstacle { obstacle, .. } => f.scene().obstacles[obstacle].id(),
                    Contact::Robot { other, .. } => f.agents()[other].id.as_str(),
                };
                if !self.touched.contains(id) {
                    self.touched.insert(id.to_string());
                }
            }
        }
        p.ignored = self.ignored.take_pending();
        self.fill_clearance(&mut p);
        self.fill_orientations(&mut p);
        let worst = if !p.contacts.is_empty() || !p.cell_mate_contacts.is_empty() {
            Outcome::Collision
        } else if !p.stalls.is_empty() {
            Outcome::Stalled
        } else {
            Outcome::Running
        };
        let last_time = self.out_t - dt;
        p.outcome = if self.stopping && self.at_rest() {
            Outcome::Stopped
        } else if worst == Outcome::Running && !self.holding && self.goal_met_since.is_some() {
            Outcome::GoalReached
        } else if n > 0 && last_time >= self.end_time - 0.5 * dt {
            Outcome::EndTime
        } else if worst == Outcome::Running && self.holding {
            Outcome::Holding
        } else {
            worst
        };
        Ok(p)
    }
}
