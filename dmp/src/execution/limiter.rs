//! The check of the DMP's points against a robot's bounds, the way a robot judges them: each limited group of
//! dimensions (a robot's position, or the orientation of a pose run) as backward finite differences of the output
//! positions. A point that keeps them is handed out as it is; one that does not goes to the final stage
//! ([`super::tracking`]).
//!
//! # Formula
//! With the last three output positions `p1, p2, p3` (`p1` the most recent) and output step `h`, the state is
//! `v = (p1 - p2) / h`, `a = (p1 - 2 p2 + p3) / h²`; a proposed point `p` has `v* = (p - p1) / h`,
//! `a* = (v* - v) / h`, `j* = (a* - a) / h`. The point keeps the bounds when `|v*| <= V`, `|a*| <= A`,
//! `|j*| <= J` and it stays in the safe set `|v* + a* (|a*| / (2 J) + h)| <= V` (the speed the motion reaches
//! while its acceleration is brought to zero at the largest jerk stays within `V`).
//!
//! The bounds are used shrunk by [`CHECK_MARGIN`]: the DMP's points are samples of a curve whose jerk between
//! them can exceed what their differences show, and a point the final stage takes over from must leave it room.
//! The final stage keeps its own room under the bounds ([`super::tracking`]).

use super::limits::Bounds;

/// Relative margin under the bounds that the DMP's own points must keep to be handed out as they are.
pub(crate) const CHECK_MARGIN: f64 = 0.05;

/// A group of dimensions and its bounds.
#[derive(Debug, Clone)]
pub(super) struct Group {
    pub(super) dims: Vec<usize>,
    pub(super) bounds: Bounds,
}

/// What the check found at one point.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(super) struct Verdict {
    /// The largest use of a bound by the proposed point (1 = at a bound), before any change.
    pub(super) usage: f64,
    /// The same, of the speed bounds only.
    pub(super) speed_usage: f64,
    /// The proposed deceleration (the acceleration against the velocity) over the acceleration bound, the largest
    /// over the groups.
    pub(super) decel_usage: f64,
    /// Some group's point does not keep its bounds.
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
    /// The velocity and acceleration handed out with `p1`, when they are known (not after a rollback or a change
    /// of coordinates, where the positions' differences stand in).
    handed_v: Vec<f64>,
    handed_a: Vec<f64>,
    handed: bool,
    /// The motion of the output positions at the point last checked (`v* + a* h / 2`, `a*`), every dimension.
    out_v: Vec<f64>,
    out_a: Vec<f64>,
    v: Vec<f64>,
    a: Vec<f64>,
    want: Vec<f64>,
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

impl Limiter {
    /// A limiter of `groups` for `dim`-dimensional points `h` apart, at rest at `x`.
    pub(super) fn new(groups: Vec<Group>, dim: usize, h: f64, x: &[f64]) -> Self {
        let z = || vec![0.0; dim];
        let mut l = Self {
            groups,
            dim,
            h,
            prev: [z(), z(), z()],
            handed_v: z(),
            handed_a: z(),
            handed: false,
            out_v: z(),
            out_a: z(),
            v: z(),
            a: z(),
            want: z(),
        };
        l.set_recent(x, 1);
        l
    }

    /// The last output positions, the most recent first (`n` of them, at least one): the earlier ones are taken
    /// equal to the oldest given (at rest there, as a run is before its first point).
    pub(super) fn set_recent(&mut self, recent: &[f64], n: usize) {
        let d = self.dim;
        for (i, p) in self.prev.iter_mut().enumerate() {
            let k = i.min(n.max(1) - 1);
            p.copy_from_slice(&recent[k * d..(k + 1) * d]);
        }
        self.handed = false;
    }

    /// The velocity and acceleration handed out with the last position (after [`Limiter::set_recent`]).
    pub(super) fn set_handed(&mut self, xd: &[f64], xdd: &[f64]) {
        self.handed_v.copy_from_slice(xd);
        self.handed_a.copy_from_slice(xdd);
        self.handed = true;
    }

    /// The last three output positions, the most recent first (`dim` each): for a change of coordinates.
    #[cfg_attr(not(feature = "orientation"), allow(dead_code))]
    pub(super) fn recent_mut(&mut self) -> &mut [Vec<f64>; 3] {
        self.handed = false;
        &mut self.prev
    }

    /// The state of dimension `i` for the final stage to take over from: the last position `p1` with the velocity
    /// and acceleration handed out with it (checked within the bounds), or, where those are not known, as the
    /// positions give them: `a = (p1 - 2 p2 + p3) / h²` and `(p1 - p2) / h + a h / 2`.
    pub(super) fn last_state(&self, i: usize) -> (f64, f64, f64) {
        let (p1, p2, p3) = (self.prev[0][i], self.prev[1][i], self.prev[2][i]);
        if self.handed {
            return (p1, self.handed_v[i], self.handed_a[i]);
        }
        let h = self.h;
        let a = ((p1 - p2) - (p2 - p3)) / (h * h);
        (p1, (p1 - p2) / h + 0.5 * a * h, a)
    }

    /// Writes the motion of the output positions at the point last checked into `xd` and `xdd` for group `g`: the
    /// velocity and acceleration a point of the DMP is handed out with.
    pub(super) fn hand_out_measured(&self, g: usize, xd: &mut [f64], xdd: &mut [f64]) {
        for &i in &self.groups[g].dims {
            xd[i] = self.out_v[i];
            xdd[i] = self.out_a[i];
        }
    }

    /// The point `p` of dimension `i` with the motion of the output positions there: `(p, v* + a* h / 2, a*)`,
    /// `v* = (p - p1) / h`, `a* = (v* - (p1 - p2) / h) / h`.
    pub(super) fn motion_to(&self, i: usize, p: f64) -> (f64, f64, f64) {
        let h = self.h;
        let (p1, p2) = (self.prev[0][i], self.prev[1][i]);
        let vs = (p - p1) / h;
        let a = (vs - (p1 - p2) / h) / h;
        (p, vs + 0.5 * a * h, a)
    }

    /// Records the point `p`, with its velocity `xd` and acceleration `xdd`, as handed out.
    pub(super) fn push(&mut self, p: &[f64], xd: &[f64], xdd: &[f64]) {
        self.prev.rotate_right(1);
        self.prev[0].copy_from_slice(p);
        self.handed_v.copy_from_slice(xd);
        self.handed_a.copy_from_slice(xdd);
        self.handed = true;
    }

    /// Checks the reference's point `p` (all dimensions) against each group's bounds, as backward finite
    /// differences after the last output positions, without changing it. Returns what it found, with `keeps[k]`
    /// telling whether group `k` keeps its bounds (shrunk by [`CHECK_MARGIN`]) and stays in the safe set, with the
    /// velocity it would be handed out with ([`Limiter::hand_out_measured`]).
    pub(super) fn check(&mut self, p: &[f64], keeps: &mut Vec<bool>) -> Verdict {
        let mut verdict = Verdict::default();
        keeps.clear();
        for gi in 0..self.groups.len() {
            let b = self.groups[gi].bounds;
            let keep_below = 1.0 - CHECK_MARGIN;
            let (v_max, a_max, j_max) = (b.v * keep_below, b.a * keep_below, b.j * keep_below);
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
            let (v, a, want) = (&self.v[..n], &self.a[..n], &self.want[..n]);
            let mut s2 = 0.0;
            let mut jerk2 = 0.0;
            for k in 0..n {
                s2 += (v[k] + want[k] * h).powi(2);
                jerk2 += ((want[k] - a[k]) / h).powi(2);
            }
            let (speed, acc, jerk) = (s2.sqrt(), norm(want), jerk2.sqrt());
            let usage = (speed / b.v).max(acc / b.a).max(jerk / b.j);
            verdict.usage = verdict.usage.max(usage);
            verdict.speed_usage = verdict.speed_usage.max(speed / b.v);
            let s = norm(v);
            if s > 0.0 {
                let against = -v.iter().zip(want.iter()).map(|(v, a)| v * a).sum::<f64>() / s;
                verdict.decel_usage = verdict.decel_usage.max(against / b.a);
            }
            // Handed out as it is, the point carries the motion of the output positions (`v* + a* h / 2`, `a*`),
            // not the DMP's own derivatives, so that what the robot is told agrees with where it goes.
            let mut out2 = 0.0;
            for (k, &i) in dims.iter().enumerate() {
                self.out_v[i] = v[k] + want[k] * h + 0.5 * want[k] * h;
                self.out_a[i] = want[k];
                out2 += self.out_v[i].powi(2);
            }
            let keep = speed <= v_max
                && acc <= a_max
                && jerk <= j_max
                && out2.sqrt() <= v_max
                && safe(v, want, h, v_max, j_max);
            verdict.changed |= !keep;
            keeps.push(keep);
            self.groups[gi].dims = dims;
        }
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
