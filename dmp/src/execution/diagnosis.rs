//! Which obstacle made a step not finite: the step is redone while each obstacle's term is checked first, at every
//! finite state the step evaluates, until one is found that is not finite (its culprits are then dropped,
//! `ignored.rs`).

use crate::dense::Knot;
use crate::field::RepulsiveField;
use crate::integrate::State;

/// Which obstacles' terms were found not finite while a step was redone, and when.
#[derive(Debug, Default)]
pub(super) struct Diagnosis {
    /// Indices into the run's field.
    pub(super) obstacles: Vec<usize>,
    /// Indices into the cell-mates' field.
    pub(super) robots: Vec<usize>,
    /// Run time of the first evaluation that found one.
    pub(super) t: f64,
}

impl Diagnosis {
    /// Checks each term of the run's `field` and of the cell-mates' `mates` at the state `x`, `v = tau dx/dt` at
    /// time `t`, until a first one is found that is not finite; states that are not finite themselves prove
    /// nothing and are passed over.
    pub(super) fn check(
        &mut self,
        field: &mut RepulsiveField,
        mates: &mut RepulsiveField,
        (t, x, v, tau): (f64, &[f64], &[f64], f64),
    ) {
        if self.obstacles.is_empty() && self.robots.is_empty() && x.iter().chain(v).all(|v| v.is_finite()) {
            field.nonfinite_obstacles(t, x, v, tau, &mut self.obstacles);
            mates.nonfinite_obstacles(t, x, v, tau, &mut self.robots);
            self.t = t;
        }
    }
}

/// True when the step from `knot0` to the state `s` (with the accelerations at both ends) is finite.
pub(super) fn step_is_finite(knot0: &Knot, s: &State, acc1: &[f64]) -> bool {
    knot0.xdd.iter().chain(&s.x).chain(&s.xd).chain(acc1).all(|v| v.is_finite())
}
