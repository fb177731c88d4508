//! Obstacles that appear, move or vanish are blended in, so that the acceleration stays continuous.
//!
//! # Formula
//! A new obstacle set `F_n` replaces the previous mix `M_{n-1}` over the blend time `T` from the output point
//! `s_n` where it applies:
//!
//! `M_n(t) = w((t - s_n) / T) F_n + (1 - w((t - s_n) / T)) M_{n-1}(t)`, `w(u) = 10 u³ - 15 u⁴ + 6 u⁵` on
//! `[0, 1]` (0 before, 1 after),
//!
//! the quintic smoothstep: `w`, `w'` and `w''` are continuous (zero at both ends), so the repulsive term, and with
//! it the acceleration, changes continuously even when an obstacle appears right at the robot, and the jerk
//! stays bounded (by `1.875 / T` times the change of the term, in units of `tau dv/dt / tau²`). An obstacle kept
//! unchanged contributes the same term to both sides of the mix. A change during a blend nests: the mix being
//! blended is itself the one replaced, so no change is ever a jump. The mix is evaluated from the newest field
//! down, and stops where the weight left is zero, so a finished blend costs nothing.
//!
//! What it costs: the term of a new obstacle reaches half its strength `T / 2` after it applies
//! ([`DEFAULT_OBSTACLE_BLEND`]`/ 2 = 50 ms`); the measured delay of the reaction is in BENCHMARKS.md. A blend time
//! of 0 applies every change at once, as before.
//!
//! The replaced fields are kept while a rollback may still return before their blend ended (the history's span),
//! then dropped.

use crate::field::RepulsiveField;
use crate::integrate::Perturbation;

/// The default blend time of an obstacle change, seconds.
pub const DEFAULT_OBSTACLE_BLEND: f64 = 0.1;

/// Most blends kept nested; beyond, the oldest field is dropped.
const MAX_LEVELS: usize = 16;

/// The quintic smoothstep of `u`, clamped to `[0, 1]`.
pub(crate) fn smoothstep(u: f64) -> f64 {
    let u = u.clamp(0.0, 1.0);
    u * u * u * (10.0 + u * (-15.0 + 6.0 * u))
}

/// The fields being replaced and when each replacement started.
#[derive(Debug, Default)]
pub(super) struct Blend {
    /// Blend time `T`, seconds (0: changes apply at once).
    pub(super) duration: f64,
    /// `F_0 .. F_{n-1}`: the fields replaced, oldest first (the newest, `F_n`, is the run's field).
    fields: Vec<RepulsiveField>,
    /// `s_1 .. s_n`: `starts[i]` is when `F_{i+1}` started to replace the mix up to `F_i`.
    starts: Vec<f64>,
    /// Scratch term of one field.
    tmp: Vec<f64>,
}

impl Blend {
    pub(super) fn new(duration: f64, dim: usize) -> Self {
        Self { duration, fields: Vec::new(), starts: Vec::new(), tmp: vec![0.0; dim] }
    }

    /// `old` is being replaced from time `start` on.
    pub(super) fn push(&mut self, old: RepulsiveField, start: f64) {
        if self.duration <= 0.0 {
            return;
        }
        if self.fields.len() == MAX_LEVELS {
            self.fields.remove(0);
            self.starts.remove(0);
        }
        self.fields.push(old);
        self.starts.push(start);
    }

    /// Drops the fields whose replacement had ended before time `t`.
    pub(super) fn forget_before(&mut self, t: f64) {
        if let Some(i) = self.starts.iter().rposition(|s| s + self.duration < t) {
            self.fields.drain(..=i);
            self.starts.drain(..=i);
        }
    }

    /// Drops every field being replaced: the run's field applies alone.
    pub(super) fn clear(&mut self) {
        self.fields.clear();
        self.starts.clear();
    }

    /// Adds the mix at `(t, x, v)` to `out`, `current` being the newest field.
    pub(super) fn add(
        &mut self,
        current: &mut RepulsiveField,
        t: f64,
        x: &[f64],
        v: &[f64],
        tau: f64,
        out: &mut [f64],
    ) {
        let n = self.fields.len();
        if n == 0 {
            current.add(t, x, v, tau, out);
            return;
        }
        let mut weight = 1.0;
        for i in (0..=n).rev() {
            let w = if i == 0 { 1.0 } else { smoothstep((t - self.starts[i - 1]) / self.duration) };
            let c = weight * w;
            if c > 0.0 {
                let f = if i == n { &mut *current } else { &mut self.fields[i] };
                if c == 1.0 {
                    f.add(t, x, v, tau, out);
                } else {
                    self.tmp.fill(0.0);
                    f.add(t, x, v, tau, &mut self.tmp);
                    for (o, p) in out.iter_mut().zip(&self.tmp) {
                        *o += c * p;
                    }
                }
            }
            weight *= 1.0 - w;
            if weight <= 0.0 {
                break;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_weight_and_its_two_derivatives_are_continuous_at_both_ends() {
        let h = 1e-4;
        for (u, w) in [(0.0, 0.0), (1.0, 1.0)] {
            assert_eq!(smoothstep(u), w);
            let d1 = (smoothstep(u + h) - smoothstep(u - h)) / (2.0 * h);
            let d2 = (smoothstep(u + h) - 2.0 * smoothstep(u) + smoothstep(u - h)) / (h * h);
            assert!(d1.abs() < 1e-6 && d2.abs() < 1e-2, "{u}: {d1} {d2}");
        }
        assert!((smoothstep(0.5) - 0.5).abs() < 1e-15);
    }
}
