//! The last word on every setpoint: each limited group of dimensions (a robot's position, or the orientation of a
//! pose run) is checked against its [`Bounds`] as backward finite differences of the output positions, and a
//! point that would exceed them is replaced by the nearest one that does not and from which the limits can still
//! be kept.
//!
//! # Formula
//! With the last three output positions `p1, p2, p3` (`p1` the most recent) and output step `h`, the state is
//! `v = (p1 - p2) / h`, `a = (p1 - 2 p2 + p3) / h²`; a proposed point `p` has `v* = (p - p1) / h`,
//! `a* = (v* - v) / h`, `j* = (a* - a) / h`. The point is kept when `|v*| <= V`, `|a*| <= A`, `|j*| <= J` and it
//! stays in the safe set `|v* + a* (|a*| / (2 J) + h)| <= V` (the speed the motion reaches while its acceleration
//! is brought to zero at the largest jerk stays within `V`). Otherwise the acceleration is chosen on the segment
//! from the wanted one (`a*`, or a braking one) to the braking acceleration `a_b = P_A(a + clip_J(-A u - a))`,
//! `u` the direction of `v + a (|a| / (2 J) + h)`: the first point of the segment (by bisection) that is safe,
//! each candidate projected into the jerk ball around `a` and the acceleration ball (projection onto a ball is
//! non-expansive, so the jerk bound survives the second projection). Then `v' = v + a' h`, `p' = p1 + v' h`.
//!
//! The bounds are used shrunk by [`MARGIN`], so that rounding in the differences never crosses them.

use super::limits::Bounds;

/// Relative margin under the bounds that the limiter works to.
pub(crate) const MARGIN: f64 = 1e-4;

/// Bisection steps on the segment from the wanted to the braking acceleration.
const BISECTIONS: usize = 12;

/// A group of dimensions and its bounds.
#[derive(Debug, Clone)]
pub(super) struct Group {
    pub(super) dims: Vec<usize>,
    pub(super) bounds: Bounds,
}

/// What the limiter did to one point.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(super) struct Verdict {
    /// The largest use of a bound by the proposed point (1 = at a bound), before any change.
    pub(super) usage: f64,
    /// The same, of the speed bounds only.
    pub(super) speed_usage: f64,
    /// The proposed deceleration (the acceleration against the velocity) over the acceleration bound, the largest
    /// over the groups.
    pub(super) decel_usage: f64,
    /// The point was changed.
    pub(super) changed: bool,
}

/// The limiter's state: the last three output positions, and scratch for one group.
#[derive(Debug, Clone, Default)]
pub(super) struct Limiter {
    pub(super) groups: Vec<Group>,
    dim: usize,
    h: f64,
    /// `p1, p2, p3`, `dim` each.
    prev: [Vec<f64>; 3],
    v: Vec<f64>,
    a: Vec<f64>,
    want: Vec<f64>,
    brake: Vec<f64>,
    cand: Vec<f64>,
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Scales `v` into the ball of radius `r` (no-op inside).
fn clip(v: &mut [f64], r: f64) {
    let n = norm(v);
    if n > r {
        let k = r / n;
        v.iter_mut().for_each(|x| *x *= k);
    }
}

impl Limiter {
    /// A limiter of `groups` for `dim`-dimensional points `h` apart, at rest at `x`.
    pub(super) fn new(groups: Vec<Group>, dim: usize, h: f64, x: &[f64]) -> Self {
        let z = || vec![0.0; dim];
        let mut l =
            Self { groups, dim, h, prev: [z(), z(), z()], v: z(), a: z(), want: z(), brake: z(), cand: z() };
        l.set_recent(x, 1);
        l
    }

    /// True when nothing is limited.
    pub(super) fn is_off(&self) -> bool {
        self.groups.iter().all(|g| g.bounds.is_none())
    }

    /// The last output positions, the most recent first (`n` of them, at least one): the earlier ones are taken
    /// equal to the oldest given (at rest there, as a run is before its first point).
    pub(super) fn set_recent(&mut self, recent: &[f64], n: usize) {
        let d = self.dim;
        for (i, p) in self.prev.iter_mut().enumerate() {
            let k = i.min(n.max(1) - 1);
            p.copy_from_slice(&recent[k * d..(k + 1) * d]);
        }
    }

    /// The last three output positions, the most recent first (`dim` each): for a change of coordinates.
    #[cfg_attr(not(feature = "orientation"), allow(dead_code))]
    pub(super) fn recent_mut(&mut self) -> &mut [Vec<f64>; 3] {
        &mut self.prev
    }

    /// Records `p` as handed out.
    pub(super) fn push(&mut self, p: &[f64]) {
        self.prev.rotate_right(1);
        self.prev[0].copy_from_slice(p);
    }

    /// Checks the proposed point `p` (all dimensions), changes it where a group would exceed its bounds, and
    /// records it. In every limited group, changed or not, `xd` and `xdd` become the motion of the output positions
    /// at the point (`v' + a' h / 2` and `a'`, from the backward differences), so that they agree with the positions
    /// on both sides of a limited stretch (the integrator's own derivatives run ahead of positions held back). With
    /// `brake`, every limited group brakes towards rest instead of following `p`.
    pub(super) fn limit(&mut self, p: &mut [f64], xd: &mut [f64], xdd: &mut [f64], brake: bool) -> Verdict {
        let mut verdict = Verdict::default();
        for gi in 0..self.groups.len() {
            let b = self.groups[gi].bounds;
            if b.is_none() {
                continue;
            }
            let (v_max, a_max, j_max) = (b.v * (1.0 - MARGIN), b.a * (1.0 - MARGIN), b.j * (1.0 - MARGIN));
            let h = self.h;
            let dims = std::mem::take(&mut self.groups[gi].dims);
            let n = dims.len();
            for (k, &i) in dims.iter().enumerate() {
                let (p1, p2, p3) = (self.prev[0][i], self.prev[1][i], self.prev[2][i]);
                self.v[k] = (p1 - p2) / h;
                self.a[k] = ((p1 - p2) - (p2 - p3)) / (h * h);
                let vs = (p[i] - p1) / h;
                self.want[k] = (vs - self.v[k]) / h;
            }
            let (v, a, want) = (&self.v[..n], &self.a[..n], &mut self.want[..n]);
            let (speed, acc) = {
                let mut s2 = 0.0;
                for k in 0..n {
                    let vk = v[k] + want[k] * h;
                    s2 += vk * vk;
                }
                (s2.sqrt(), norm(want))
            };
            let mut jerk2 = 0.0;
            for k in 0..n {
                jerk2 += ((want[k] - a[k]) / h).powi(2);
            }
            let jerk = jerk2.sqrt();
            let usage = (speed / b.v).max(acc / b.a).max(jerk / b.j);
            verdict.usage = verdict.usage.max(usage);
            verdict.speed_usage = verdict.speed_usage.max(speed / b.v);
            let s = norm(v);
            if s > 0.0 {
                let against = -v.iter().zip(want.iter()).map(|(v, a)| v * a).sum::<f64>() / s;
                verdict.decel_usage = verdict.decel_usage.max(against / b.a);
            }
            if !brake && speed <= v_max && acc <= a_max && jerk <= j_max && safe(v, want, h, v_max, j_max) {
                for (k, &i) in dims.iter().enumerate() {
                    xd[i] = (p[i] - self.prev[0][i]) / h + 0.5 * want[k] * h;
                    xdd[i] = want[k];
                }
                self.groups[gi].dims = dims;
                continue;
            }
            verdict.changed = true;
            // The braking acceleration: against the speed the motion is heading for.
            let brake_acc = &mut self.brake[..n];
            let tau_a = norm(a) / (2.0 * j_max) + h;
            for k in 0..n {
                brake_acc[k] = v[k] + a[k] * tau_a;
            }
            let w = norm(brake_acc);
            let target = if a_max.is_finite() { a_max } else { w / h };
            for k in 0..n {
                brake_acc[k] = if w > 0.0 { -target * brake_acc[k] / w } else { 0.0 };
            }
            if brake {
                // Towards rest: the deceleration along which the acceleration reaches zero with the speed.
                let s = norm(v);
                let decel = a_max.min((2.0 * j_max * s).sqrt()).min(s / h);
                for k in 0..n {
                    want[k] = if s > 0.0 { -decel * v[k] / s } else { 0.0 };
                }
            }
            let cand = &mut self.cand[..n];
            let pick = |lambda: f64, out: &mut [f64]| {
                for k in 0..n {
                    out[k] = (1.0 - lambda) * want[k] + lambda * brake_acc[k] - a[k];
                }
                clip(out, j_max * h);
                for k in 0..n {
                    out[k] += a[k];
                }
                clip(out, a_max);
            };
            pick(0.0, cand);
            if !safe(v, cand, h, v_max, j_max) {
                let (mut lo, mut hi) = (0.0, 1.0);
                for _ in 0..BISECTIONS {
                    let mid = 0.5 * (lo + hi);
                    pick(mid, cand);
                    if safe(v, cand, h, v_max, j_max) { hi = mid } else { lo = mid }
                }
                pick(hi, cand);
            }
            for (k, &i) in dims.iter().enumerate() {
                let vn = v[k] + cand[k] * h;
                p[i] = self.prev[0][i] + vn * h;
                xd[i] = vn + 0.5 * cand[k] * h;
                xdd[i] = cand[k];
            }
            self.groups[gi].dims = dims;
        }
        self.push(p);
        verdict
    }
}

/// The state after acceleration `a2` from velocity `v` keeps its speed within `v_max`, now and while the
/// acceleration is brought to zero at jerk `j_max`.
fn safe(v: &[f64], a2: &[f64], h: f64, v_max: f64, j_max: f64) -> bool {
    if v_max.is_infinite() {
        return true;
    }
    let tau = norm(a2) / (2.0 * j_max) + h;
    let (mut s2, mut w2) = (0.0, 0.0);
    for k in 0..v.len() {
        let vn = v[k] + a2[k] * h;
        s2 += vn * vn;
        w2 += (vn + a2[k] * tau).powi(2);
    }
    s2.sqrt() <= v_max && w2.sqrt() <= v_max
}
