//! Keeping a robot's [`Limits`]: the DMP way first, then the limiter.
//!
//! 1. **Temporal coupling.** While the DMP's next point uses more than [`COUPLE_ABOVE`] of a bound (speed,
//!    acceleration or jerk, as backward differences), its time scale grows, `tau = tau_user c`, with
//!    `dc/dt = COUPLE_RATE c`; once it uses less than [`RELAX_BELOW`], `c` relaxes back to 1 at
//!    `dc/dt = -RELAX_RATE c`. The phase slows, so the forcing term and the attractor ask less of the robot, and
//!    the motion's path is kept. `c` is applied (a change of `tau` from the next output point, continuous in
//!    position and velocity) every [`COUPLE_PERIOD`] rounded to whole output steps (every point when `dt` is
//!    longer), at the output points whose index is a multiple of it: the same points on every internal grid, and,
//!    with 10 ms segments (the server's default, the load's), those where a segment, and so a new internal step,
//!    starts.
//!
//!    A time scale that changes also scales the velocity. In the DMP's first-order form (Ijspeert et al. 2013,
//!    Neural Computation 25(2), eq. 2.1: `tau z' = K (g - x) - D z + f`, `tau x' = z`) a growing `tau` slows the
//!    robot at once, since `x' = z / tau`; temporal coupling works through this (Ijspeert et al. 2013, on temporal coupling;
//!    Dahlin and Karayiannidis, "Temporal coupling of dynamical movement primitives for constrained velocities and
//!    accelerations", IEEE RA-L 6(2), 2021). The engine's state is `x'` itself, which stays continuous; its
//!    acceleration carries the term of `tau' != 0`, `x'' = z' / tau - (tau' / tau) x'`, that is `-tau' v` added to
//!    `tau v'` (`v = tau x'`), while `c` grows because of a speed bound (`tau' / tau = COUPLE_RATE`). Without it a
//!    slowed phase leaves the speed as it was, and weakens the damping and the obstacles' terms (both divide by
//!    `tau`): a robot held at its speed limit coasts on with its time scale stretched tenfold, into what it should
//!    avoid. A stretch for an acceleration or jerk bound leaves the velocity to the DMP (the attractor's and the
//!    forcing term's accelerations fall as `1 / c²` at once, the damping's as `1 / c`, and the term would ask for
//!    more deceleration, `COUPLE_RATE |x'|`), and so does the relaxation. The rate in force changes with `c`, by
//!    at most `COUPLE_RATE` / [`COUPLE_RATE_PERIODS`] a period, so that the term never jumps the acceleration by
//!    more than a quarter of `COUPLE_RATE |x'|`; a rollback sets it to 0.
//! 2. **The final stage** ([`super::tracking`]): a point of the DMP that keeps the bounds (as backward
//!    differences, [`super::limiter`]) is handed out as it is; where it does not, a jerk-limited online trajectory
//!    generator (Ruckig) tracks the DMP from the last output state within the bounds, time-optimally and never past
//!    the goal, until it has caught up. The DMP is not restarted from the generator's points: it stays the
//!    reference. The coupling above then follows the generator's lag behind the DMP instead of the DMP's own
//!    use of the bounds: the phase waits where the lag would cut the reference's curve by more than its path
//!    tolerance, and is free on a straight way (the time-optimal motion).
//! 3. **Braking.** Where the DMP asks to decelerate (an acceleration against the velocity) at more than
//!    [`BRAKE_ABOVE`] times the acceleration bound (an obstacle appears right in front), the generator brakes
//!    time-optimally, and the stretch says so ([`LimitAction::Braking`]).
//!
//! No point handed out exceeds a bound, measured as backward finite differences of the positions at the output
//! rate, across stretches, changes and rollbacks (the limiter's last points are taken from the history after a
//! rollback).

use super::Execution;
use super::guard::{Guard, Guarded};
use super::limiter::{Group, Limiter};
use super::tracking::{Tracker, generator_bounds};
use crate::error::InvalidInput;

pub use super::limits::Limits;

/// Temporal coupling starts above this use of a bound.
pub(crate) const COUPLE_ABOVE: f64 = 0.9;
/// Temporal coupling relaxes below this use of a bound.
pub(crate) const RELAX_BELOW: f64 = 0.6;
/// Growth rate of the time scale while coupling, 1/s.
pub(crate) const COUPLE_RATE: f64 = 4.0;
/// Relaxation rate of the time scale, 1/s.
pub(crate) const RELAX_RATE: f64 = 1.0;
/// Largest time scale factor.
pub(crate) const MAX_TAU_SCALE: f64 = 10.0;
/// The coupling's time scale and rate are applied every this many seconds (rounded to whole output steps).
pub(crate) const COUPLE_PERIOD: f64 = 0.01;
/// The speed coupling's term reaches its rate, or leaves it, over this many periods ([`COUPLE_PERIOD`]).
pub(crate) const COUPLE_RATE_PERIODS: f64 = 4.0;
/// Braking to rest starts when the DMP asks to decelerate at this many times the acceleration bound.
pub(crate) const BRAKE_ABOVE: f64 = 4.0;
/// The potentials act on the obstacles inflated by this many times the safety distance: where the field can keep
/// the robot away, it keeps it beyond the margin, and the guard acts only where the field cannot.
pub const KEEP_OFF: f64 = 2.0;

/// What keeping the limits did in a stretch (the most that happened).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, PartialOrd, Ord)]
pub enum LimitAction {
    /// Nothing: the DMP's points were within the limits.
    #[default]
    None,
    /// The phase was slowed (temporal coupling: `tau` scaled up).
    Slowed,
    /// Points came from the final stage's generator, tracking the DMP within the limits.
    Limited,
    /// The generator braked: the DMP asked to decelerate far harder than the limits allow.
    Braking,
    /// Braking to rest, or held at rest, before the safety distance ([`Execution::set_margin`]) that the field
    /// could not keep.
    Blocked,
}

impl Execution {
    /// Keeps `limits` from the next output point on. With `orientation`, the last three dimensions are the
    /// rotation vector of a pose run (pose convention): the angular limits apply to them (their speed bounds `ω`,
    /// since `|ω| = |J(y) ẏ| <= |ẏ|`; their acceleration and jerk are those of `ẏ`, which equal `ω̇` and `ω̈` up to
    /// the terms in `J̇`), and the linear limits to each robot's other dimensions. Without, the linear limits apply
    /// to each robot's dimensions. Refused, naming the field, when a value is not finite or negative, or
    /// `orientation` with fewer than four dimensions.
    pub fn set_limits(&mut self, limits: Limits, orientation: bool) -> Result<(), InvalidInput> {
        limits.validate().map_err(|e| e.within("limits"))?;
        let dim = self.primitive.dim;
        if orientation && dim < 4 {
            return Err(InvalidInput::new(
                "limits",
                "orientation needs a position and three rotation dimensions",
            ));
        }
        let position_end = if orientation { dim - 3 } else { dim };
        let mut groups: Vec<Group> = self
            .members()
            .iter()
            .map(|m| Group {
                dims: m.dims.iter().copied().filter(|&i| i < position_end).collect(),
                bounds: limits.linear(),
            })
            .filter(|g| !g.dims.is_empty())
            .collect();
        if orientation {
            groups.push(Group { dims: (dim - 3..dim).collect(), bounds: limits.angular() });
        }
        groups.retain(|g| !g.bounds.is_none());
        self.limits = limits;
        let tracked: Vec<_> = groups.iter().map(|g| (g.dims.clone(), g.bounds)).collect();
        self.tracker = Tracker::new(&tracked, self.stepping.dt);
        self.guard_positions(&tracked, position_end);
        if orientation {
            self.tracker.set_angular(&(dim - 3..dim).collect::<Vec<_>>());
        }
        self.limiter = Limiter::new(groups, dim, self.stepping.dt, &self.knot0.x);
        self.restore_limiter();
        Ok(())
    }

    /// Keeps the safety distance `margin` (metres; 0: none) from every obstacle's true shape from the next output
    /// point on (`execution/guard.rs`): the potentials act on the shapes inflated by [`KEEP_OFF`] times it, and
    /// no point brings a robot with finite acceleration and jerk limits closer than it where it can still brake
    /// (it brakes to rest before, [`LimitAction::Blocked`]). The contacts stay those with the true shapes.
    /// Refused (naming `margin`) unless finite and not negative.
    pub fn set_margin(&mut self, margin: f64) -> crate::error::Result<()> {
        if !(margin.is_finite() && margin >= 0.0) {
            return Err(InvalidInput::new(
                "margin",
                format!("must be finite and not negative, not {margin}"),
            )
            .into());
        }
        self.margin = margin;
        self.rebase();
        let field = crate::field::RepulsiveField::new(self.field.scene().clone(), self.primitive.dim)?;
        self.field = field.keeping_off(self.keep_off())?;
        let (tracked, position_end) = self.linear_groups();
        self.guard_positions(&tracked, position_end);
        Ok(())
    }

    /// Whether the last point handed out was braking, or held at rest, before the safety distance
    /// ([`LimitAction::Blocked`]).
    pub fn is_blocked(&self) -> bool {
        self.guard.is_blocked()
    }

    /// The safety distance kept.
    pub fn margin(&self) -> f64 {
        self.margin
    }

    /// How far beyond the true shapes the potentials act.
    pub(super) fn keep_off(&self) -> f64 {
        KEEP_OFF * self.margin
    }

    /// The members' position groups with their linear bounds, and where the position ends.
    fn linear_groups(&self) -> (Vec<(Vec<usize>, super::limits::Bounds)>, usize) {
        let dim = self.primitive.dim;
        let position_end = if self.chart.is_some() { dim - 3 } else { dim };
        let groups = self
            .members()
            .iter()
            .map(|m| {
                (
                    m.dims.iter().copied().filter(|&i| i < position_end).collect::<Vec<_>>(),
                    self.limits.linear(),
                )
            })
            .filter(|(d, b)| !d.is_empty() && !b.is_none())
            .collect();
        (groups, position_end)
    }

    /// A guard for each robot's position among `tracked` (the final stage's groups).
    fn guard_positions(&mut self, tracked: &[(Vec<usize>, super::limits::Bounds)], position_end: usize) {
        let h = self.stepping.dt;
        let positions: Vec<_> = tracked
            .iter()
            .filter(|(dims, _)| dims.iter().all(|&i| i < position_end))
            .map(|(dims, b)| (dims.clone(), generator_bounds(*b, h)))
            .collect();
        self.guard = Guard::new(&positions, self.margin, h);
        self.guard.reset();
    }

    /// The limits kept.
    pub fn limits(&self) -> Limits {
        self.limits
    }

    /// The temporal coupling's factor on `tau` (1 when the limits ask nothing).
    pub fn tau_scale(&self) -> f64 {
        self.tau_scale
    }

    /// The limiter's last points and the final stage's state from the history (after a rollback, or new limits).
    pub(super) fn restore_limiter(&mut self) {
        let d = self.primitive.dim;
        self.recent.resize(3 * d, 0.0);
        let mut n = self.history.recent_positions(&mut self.recent[..3 * d]);
        if n == 0 {
            // Before the first point: the run's start, and the two points before it at its start velocity (at
            // rest, as most runs start, all three are the start).
            let h = self.stepping.dt;
            for k in 0..3 {
                for i in 0..d {
                    self.recent[k * d + i] = self.knot0.x[i] - k as f64 * h * self.knot0.xd[i];
                }
            }
            n = 3;
        }
        self.limiter.set_recent(&self.recent, n);
        if let Some((xd, xdd)) = self.history.last_motion() {
            self.limiter.set_handed(xd, xdd);
        }
        // The generator goes on from the last point kept where it gave that point; where the DMP did, the DMP
        // restarts from it, and goes on giving the points it gave before (a robot that already carried them out
        // sees no change) while they keep the bounds.
        self.tracker.reset(n > 0 && self.history.last().is_some() && self.history.last_generated());
    }

    /// Keeps the limits at the DMP's point just computed (rewritten in place by the final stage where it does not
    /// keep them), before it is handed out; the next output point is at `self.out_t`. Returns what it did.
    pub(super) fn keep_limits(&mut self, x: &mut [f64], xd: &mut [f64], xdd: &mut [f64]) -> LimitAction {
        if self.tracker.is_off() {
            if self.tau_scale != 1.0 || self.tau_rate != 0.0 {
                // Limits taken off mid-run: the time scale relaxes back, and the speed coupling's term is off.
                self.couple(0.0, 0.0);
            }
            return LimitAction::None;
        }
        let mut keeps = std::mem::take(&mut self.keeps);
        let verdict = self.limiter.check(x, &mut keeps);
        let tracking = self.tracker.track(x, xd, xdd, &self.motion.goal, &keeps, &self.limiter);
        let mut blocked = false;
        if !self.guard.is_off() {
            // Before the measured motion is handed out with the DMP's point: the guard judges what the robot would
            // be told.
            for g in 0..keeps.len() {
                if !self.tracker.generated(g) {
                    self.limiter.hand_out_measured(g, xd, xdd);
                }
            }
            let t = self.out_t - self.stepping.dt;
            let obstacles = &self.field.scene().obstacles;
            if self.guard.guard(t, x, xd, xdd, obstacles, &self.limiter) == Guarded::Braking {
                blocked = true;
                // The final stage goes on from the brake's point at the next one.
                self.tracker.reset(true);
            }
        } else {
            for g in 0..keeps.len() {
                if !self.tracker.generated(g) {
                    self.limiter.hand_out_measured(g, xd, xdd);
                }
            }
        }
        self.keeps = keeps;
        self.limiter.push(x, xd, xdd);
        let mut action = if blocked {
            LimitAction::Blocked
        } else if !tracking.generated {
            LimitAction::None
        } else if verdict.decel_usage > BRAKE_ABOVE {
            LimitAction::Braking
        } else {
            LimitAction::Limited
        };
        if tracking.generated || blocked {
            self.cost.limited += 1;
        }
        if !self.holding {
            self.couple(tracking.lag_usage, tracking.lag_usage);
        }
        if self.tau_scale > 1.0 && action == LimitAction::None {
            action = LimitAction::Slowed;
        }
        action
    }

    /// Restarts the DMP at the robot, one output step after the last point handed out, when the final stage is
    /// tracking it from behind: a stop, a pause or a new goal then starts from where the robot is, not from where
    /// the DMP ran ahead to.
    pub(super) fn restart_at_output(&mut self) {
        if !self.tracker.is_active() || !self.has_last {
            return;
        }
        self.rebase();
        let dt = self.stepping.dt;
        for i in 0..self.primitive.dim {
            self.knot0.x[i] = self.last_x[i] + dt * self.last_xd[i];
            self.knot0.xd[i] = self.last_xd[i];
        }
        self.acc0_current = false;
    }

    /// Temporal coupling after a point that used `usage` of the bounds, `speed_usage` of the speed bounds.
    fn couple(&mut self, usage: f64, speed_usage: f64) {
        let dt = self.stepping.dt;
        let wanted = if usage > COUPLE_ABOVE {
            (self.tau_scale_target * (COUPLE_RATE * dt).exp()).min(MAX_TAU_SCALE)
        } else if usage < RELAX_BELOW {
            (self.tau_scale_target * (-RELAX_RATE * dt).exp()).max(1.0)
        } else {
            self.tau_scale_target
        };
        // The relative rate tau' / tau of a stretch for speed: COUPLE_RATE (less where c meets its cap), else 0.
        let rate = if speed_usage > COUPLE_ABOVE { (wanted / self.tau_scale_target).ln() / dt } else { 0.0 };
        self.tau_scale_target = wanted;
        // Applied on the period's grid of times, the same whatever the internal step (the server's segments start
        // there, and a new step with them).
        let period = (COUPLE_PERIOD / dt).round().max(1.0);
        let on_period = (self.out_t / dt).round() % period == 0.0;
        // The term's rate moves towards `rate` by a step a period: switched at once, it would jump the
        // acceleration by COUPLE_RATE |x'| each time the speed crosses the threshold.
        let step = COUPLE_RATE / COUPLE_RATE_PERIODS;
        let applied = self.tau_rate + (rate - self.tau_rate).clamp(-step, step);
        if on_period && (wanted != self.tau_scale || applied != self.tau_rate) {
            self.rebase();
            self.anchor_goal(self.holding);
            self.tau_scale = wanted;
            self.motion.tau = self.base_tau * wanted;
            self.tau_rate = applied;
        }
    }
}
