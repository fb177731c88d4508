//! The goal of a run approached through a first-order filter, so that a new goal changes the acceleration
//! continuously instead of by a step.
//!
//! # Formula
//! Ijspeert, Nakanishi, Hoffmann, Pastor & Schaal (2013), *Dynamical Movement Primitives: Learning Attractor Models
//! for Motor Behaviors*, Neural Computation 25(2), section on changing the goal online:
//!
//! `tau dg/dt = alpha_g (g_new - g)`,
//!
//! integrated in closed form between two changes: from the value `g_c` at the time `t_c` of the last change,
//!
//! `g(t) = g_new + (g_c - g_new) exp(-alpha_g (t - t_c) / tau)`.
//!
//! The filtered `g(t)` enters the transformation system wherever `g` does (`K (g - x)` and `- K (g - x0) s` of
//! `eq:dmp_acc_obst`), evaluated exactly at every stage time of RK4 and Dormand–Prince. Every change of `tau`, of
//! the goal or of holding re-anchors the filter at the time it applies (`g_c` becomes the filter's value there), so
//! that the closed form stays exact under any sequence of changes; while holding the filtered goal stays where it
//! is (the phase is frozen too). `alpha_g = 0` switches the filter off: a new goal then applies at once, as a
//! step.
//!
//! With a pose run (the last three dimensions are the rotation vector `y` of the orientation in a chart anchored at
//! a fixed `q_ref`), the goal vector holds `y_g`, and filtering it is a filtered orientation goal: `exp(g(t)) ⊗
//! q_ref` moves from the old goal orientation to the new one along the chart's straight line, which for a goal
//! change about one axis through `q_ref` is the slerp, and near it to first order.

/// The default `alpha_g`: the filtered goal covers 63 % of a change in `tau / 10` and 99 % in about `tau / 2`.
pub const DEFAULT_GOAL_ALPHA: f64 = 10.0;

/// The filter's state: where it was anchored and how fast it moves. The target `g_new` is the run's goal
/// ([`crate::Motion::goal`]).
#[derive(Debug, Clone, PartialEq)]
pub struct GoalFilter {
    alpha: f64,
    /// `g_c`.
    from: Vec<f64>,
    /// `t_c`.
    t0: f64,
    /// False while `from` is the target (no change under way): the goal is then the target exactly.
    active: bool,
    /// Holding: the filtered goal stays at `from`.
    frozen: bool,
}

impl GoalFilter {
    /// A filter of `alpha_g` (0: off) resting at `goal`.
    pub fn new(alpha: f64, goal: &[f64]) -> Self {
        Self { alpha, from: goal.to_vec(), t0: 0.0, active: false, frozen: false }
    }

    /// `alpha_g` (0: off).
    pub fn alpha(&self) -> f64 {
        self.alpha
    }

    /// True while a goal change is being filtered.
    pub(crate) fn is_active(&self) -> bool {
        self.active
    }

    /// The filtered goal at time `t` under time scale `tau`, towards `target`, into `out`.
    pub(crate) fn goal_at(&self, target: &[f64], t: f64, tau: f64, out: &mut [f64]) {
        if !self.active {
            out.copy_from_slice(target);
            return;
        }
        if self.frozen {
            out.copy_from_slice(&self.from);
            return;
        }
        let decay = (-self.alpha * (t - self.t0) / tau).exp();
        for ((o, g), c) in out.iter_mut().zip(target).zip(&self.from) {
            *o = g + (c - g) * decay;
        }
    }

    /// Re-anchors at time `t` (where a change applies): `g_c` becomes the value there, under the `tau` and target
    /// in force until then. `frozen`: holding from `t` on.
    pub fn anchor(&mut self, target: &[f64], t: f64, tau: f64, frozen: bool) {
        if self.active && !self.frozen {
            let decay = (-self.alpha * (t - self.t0) / tau).exp();
            for (c, g) in self.from.iter_mut().zip(target) {
                *c = g + (*c - g) * decay;
            }
        }
        self.t0 = t;
        self.frozen = frozen;
    }

    /// The target changes from `old` to `new` at time `t` (call [`GoalFilter::anchor`] first): with `alpha_g > 0`
    /// the filtered goal moves from where it is; off, it jumps.
    pub fn retarget(&mut self, old: &[f64], new: &[f64]) {
        if !self.active {
            self.from.clear();
            self.from.extend_from_slice(old);
        }
        self.active = self.alpha > 0.0 && self.from.as_slice() != new;
    }

    /// Sets `alpha_g` from time `t` on (anchoring first).
    pub(crate) fn set_alpha(&mut self, alpha: f64, target: &[f64], t: f64, tau: f64) {
        let frozen = self.frozen;
        self.anchor(target, t, tau, frozen);
        self.alpha = alpha;
        self.active = alpha > 0.0 && self.active;
    }

    /// After a rollback to time `t`, where the filtered goal was `g`: when the anchor is later than `t` (a change
    /// after it), the filter restarts from `g` there; otherwise the anchor still describes the points from `t` on.
    pub(crate) fn restore(&mut self, t: f64, g: &[f64], target: &[f64]) {
        if self.t0 > t {
            self.from.clear();
            self.from.extend_from_slice(g);
            self.t0 = t;
            self.active = self.alpha > 0.0 && self.from.as_slice() != target;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn it_follows_the_closed_form_and_reanchoring_is_exact() {
        let mut f = GoalFilter::new(10.0, &[0.0]);
        f.anchor(&[0.0], 0.5, 2.0, false);
        f.retarget(&[0.0], &[1.0]);
        let mut g = [0.0];
        f.goal_at(&[1.0], 0.7, 2.0, &mut g);
        assert!((g[0] - (1.0 - (-10.0f64 * 0.2 / 2.0).exp())).abs() < 1e-15);
        // A tau change at 0.7: from there the filter runs at the new tau, continuously.
        f.anchor(&[1.0], 0.7, 2.0, false);
        let mut h = [0.0];
        f.goal_at(&[1.0], 0.7, 4.0, &mut h);
        assert!((h[0] - g[0]).abs() < 1e-15);
        f.goal_at(&[1.0], 0.9, 4.0, &mut h);
        assert!((h[0] - (1.0 - (1.0 - g[0]) * (-10.0f64 * 0.2 / 4.0).exp())).abs() < 1e-15);
        // Off: a step.
        let mut off = GoalFilter::new(0.0, &[0.0]);
        off.anchor(&[0.0], 0.5, 2.0, false);
        off.retarget(&[0.0], &[1.0]);
        off.goal_at(&[1.0], 0.5, 2.0, &mut h);
        assert_eq!(h[0], 1.0);
    }
}
