//! The recent output points of a run, kept for rollbacks. One record per [`Execution::advance`](super::Execution::advance)
//! (a stretch): its points' phases, positions and velocities in flat arrays, copied once per array rather than
//! once per point, into buffers that are recycled (no allocation once the history is full). The points lie on the
//! run's output grid, one step apart (the execution's invariant, which `contacts_along` also relies on): a record
//! keeps the grid index of its first point, and point `k` is at `(first + k) dt`, the very value the execution
//! computed.

use std::collections::VecDeque;

use crate::integrate::State;

/// The points of one `advance`, in time order.
#[derive(Debug, Default)]
struct Record {
    /// Grid index of the first point: its time over `dt`.
    first: i64,
    s: Vec<f64>,
    /// Row-major, `dim` per point.
    x: Vec<f64>,
    xd: Vec<f64>,
    /// The accelerations handed out.
    xdd: Vec<f64>,
    /// The filtered goal at each point.
    g: Vec<f64>,
    /// Whether each point came from the final stage's generator (not the DMP's own).
    generated: Vec<bool>,
}

impl Record {
    fn len(&self) -> usize {
        self.s.len()
    }

    /// Time of point `k`.
    fn time(&self, k: usize, dt: f64) -> f64 {
        (self.first + k as i64) as f64 * dt
    }

    /// The first point at or after `t - tol` (`len` if none).
    fn first_at_or_after(&self, t: f64, tol: f64, dt: f64) -> usize {
        let (mut lo, mut hi) = (0, self.len());
        while lo < hi {
            let mid = (lo + hi) / 2;
            if self.time(mid, dt) + tol < t { lo = mid + 1 } else { hi = mid }
        }
        lo
    }

    /// Point `k` into `out`, its filtered goal into `g`.
    fn write_point(&self, k: usize, dim: usize, dt: f64, out: &mut State, g: &mut Vec<f64>) {
        g.clear();
        g.extend_from_slice(&self.g[k * dim..(k + 1) * dim]);
        (out.t, out.s) = (self.time(k, dt), self.s[k]);
        out.x.clear();
        out.x.extend_from_slice(&self.x[k * dim..(k + 1) * dim]);
        out.xd.clear();
        out.xd.extend_from_slice(&self.xd[k * dim..(k + 1) * dim]);
    }

    fn truncate(&mut self, n: usize, dim: usize) {
        self.s.truncate(n);
        self.x.truncate(n * dim);
        self.xd.truncate(n * dim);
        self.xdd.truncate(n * dim);
        self.g.truncate(n * dim);
        self.generated.truncate(n);
    }
}

/// At least the last `keep` output points (whole records: up to one segment more).
#[derive(Debug)]
pub(super) struct History {
    dim: usize,
    /// The output step.
    dt: f64,
    keep: usize,
    records: VecDeque<Record>,
    /// Points in `records`.
    points: usize,
    /// Emptied records whose buffers the next pushes reuse.
    spare: Vec<Record>,
}

impl History {
    /// An empty history of `dim`-dimensional points `dt` apart that keeps at least `keep` of them.
    pub(super) fn new(dim: usize, dt: f64, keep: usize) -> Self {
        Self { dim, dt, keep, records: VecDeque::new(), points: 0, spare: Vec::new() }
    }

    /// Appends the points from time `t0` on, one output step apart, with phases `s`, positions `x`, velocities
    /// `xd`, accelerations `xdd` and filtered goals `g` (`dim` per point), whether each came from the final stage's
    /// generator (`generated`, one per point, or empty: none did), and forgets the oldest records that are no longer
    /// needed to hold `keep` points.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn push(
        &mut self,
        t0: f64,
        s: &[f64],
        x: &[f64],
        xd: &[f64],
        xdd: &[f64],
        g: &[f64],
        generated: &[bool],
    ) {
        debug_assert!(
            x.len() == s.len() * self.dim
                && xd.len() == x.len()
                && xdd.len() == x.len()
                && g.len() == x.len()
        );
        if s.is_empty() || self.keep == 0 {
            return;
        }
        let mut r = self.spare.pop().unwrap_or_default();
        r.first = (t0 / self.dt).round() as i64;
        for (buf, from) in [(&mut r.s, s), (&mut r.x, x), (&mut r.xd, xd), (&mut r.xdd, xdd), (&mut r.g, g)] {
            buf.clear();
            buf.extend_from_slice(from);
        }
        r.generated.clear();
        r.generated.extend_from_slice(generated);
        r.generated.resize(s.len(), false);
        self.points += s.len();
        self.records.push_back(r);
        while let Some(front) = self.records.front()
            && self.points - front.len() >= self.keep
        {
            self.points -= front.len();
            if let Some(old) = self.records.pop_front() {
                self.spare.push(old);
            }
        }
    }

    /// Position and velocity of the last point.
    pub(super) fn last(&self) -> Option<(&[f64], &[f64])> {
        let r = self.records.back()?;
        let from = (r.len() - 1) * self.dim;
        Some((&r.x[from..], &r.xd[from..]))
    }

    /// Velocity and acceleration handed out with the last point.
    pub(super) fn last_motion(&self) -> Option<(&[f64], &[f64])> {
        let r = self.records.back()?;
        let from = (r.len() - 1) * self.dim;
        Some((&r.xd[from..], &r.xdd[from..]))
    }

    /// Whether the last point came from the final stage's generator.
    pub(super) fn last_generated(&self) -> bool {
        self.records.back().and_then(|r| r.generated.last().copied()).unwrap_or(false)
    }

    /// Every recorded point's position, velocity and filtered goal (`dim` each), oldest first: for a change of
    /// coordinates.
    #[cfg_attr(not(feature = "orientation"), allow(dead_code))]
    pub(super) fn points_mut(&mut self) -> impl Iterator<Item = (&mut [f64], &mut [f64], &mut [f64])> {
        let d = self.dim;
        self.records.iter_mut().flat_map(move |r| {
            r.x.chunks_exact_mut(d)
                .zip(r.xd.chunks_exact_mut(d))
                .zip(r.g.chunks_exact_mut(d))
                .map(|((x, v), g)| (x, v, g))
        })
    }

    /// Writes the positions of the last points, the most recent first, into `out` (`dim` each, as many as fit);
    /// returns how many were written (fewer when the history holds fewer).
    pub(super) fn recent_positions(&self, out: &mut [f64]) -> usize {
        let d = self.dim;
        let want = out.len() / d;
        let mut n = 0;
        for r in self.records.iter().rev() {
            for k in (0..r.len()).rev() {
                if n == want {
                    return n;
                }
                out[n * d..(n + 1) * d].copy_from_slice(&r.x[k * d..(k + 1) * d]);
                n += 1;
            }
        }
        n
    }

    /// Removes every point from the first one whose time is at or after `t - tol` on, and writes that point into
    /// `out` (its filtered goal into `g`); false (and nothing removed) when there is none.
    pub(super) fn rollback_into(&mut self, t: f64, tol: f64, out: &mut State, g: &mut Vec<f64>) -> bool {
        // Whole records from that time on go; the point is the first of the last one to go, unless the record
        // before it also reaches that time.
        let mut dropped: Option<Record> = None;
        while let Some(r) = self.records.back_mut() {
            // The first point of this record at or after the time (the times increase).
            let k = r.first_at_or_after(t, tol, self.dt);
            if k == r.len() {
                break;
            }
            if k > 0 {
                self.points -= r.len() - k;
                r.write_point(k, self.dim, self.dt, out, g);
                r.truncate(k, self.dim);
                self.spare.extend(dropped);
                return true;
            }
            if let Some(r) = self.records.pop_back() {
                self.points -= r.len();
                self.spare.extend(dropped.replace(r));
            }
        }
        let Some(r) = dropped else { return false };
        r.write_point(0, self.dim, self.dt, out, g);
        self.spare.push(r);
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DT: f64 = 0.001;

    /// Pushes `n` 2-D points from index `from`: t = k dt, s = 1 - k/1000, x = (k, -k), xd = (10 k, 1).
    fn push(h: &mut History, from: usize, n: usize) {
        let ks: Vec<f64> = (from..from + n).map(|k| k as f64).collect();
        let s: Vec<f64> = ks.iter().map(|k| 1.0 - k / 1000.0).collect();
        let x: Vec<f64> = ks.iter().flat_map(|&k| [k, -k]).collect();
        let xd: Vec<f64> = ks.iter().flat_map(|&k| [10.0 * k, 1.0]).collect();
        h.push(from as f64 * DT, &s, &x, &xd, &xd, &x, &[]);
    }

    fn rollback(h: &mut History, t: f64) -> Option<State> {
        let mut st = State::at_rest(&[0.0, 0.0]);
        let mut g = Vec::new();
        h.rollback_into(t, 0.5 * DT, &mut st, &mut g).then_some(st).inspect(|st| assert_eq!(g, st.x))
    }

    #[test]
    fn it_keeps_at_least_the_asked_points_in_whole_records() {
        let mut h = History::new(2, DT, 25);
        assert_eq!(h.last(), None);
        for seg in 0..10 {
            push(&mut h, seg * 10, 10);
            assert!(h.points >= 25.min(10 * (seg + 1)) && h.points < 35, "{}", h.points);
        }
        assert_eq!(h.records.len(), 3, "30 points hold 25, 20 do not");
        assert_eq!(h.last(), Some((&[99.0, -99.0][..], &[990.0, 1.0][..])));
    }

    #[test]
    fn a_rollback_restores_the_first_point_at_or_after_the_time_and_drops_the_rest() {
        let mut h = History::new(2, DT, 100);
        for seg in 0..5 {
            push(&mut h, seg * 10, 10);
        }
        // Inside a record: point 23 (t = 0.0228 rounds to it within half a step) is restored, 23.. are gone.
        let st = rollback(&mut h, 0.0228).unwrap();
        assert_eq!(
            (st.t, st.s, st.x.as_slice(), st.xd.as_slice()),
            (23.0 * DT, 1.0 - 0.023, &[23.0, -23.0][..], &[230.0, 1.0][..])
        );
        assert_eq!(h.points, 23);
        assert_eq!(h.last().unwrap().0, &[22.0, -22.0]);
        // At a record's first point: the whole record goes.
        let st = rollback(&mut h, 0.020).unwrap();
        assert_eq!(st.x, vec![20.0, -20.0]);
        assert_eq!((h.points, h.records.len()), (20, 2));
        // Past the end: nothing.
        assert!(rollback(&mut h, 0.5).is_none());
        assert_eq!(h.points, 20);
        // Before the start: the oldest point, and the history is empty.
        assert_eq!(rollback(&mut h, -1.0).unwrap().x, vec![0.0, 0.0]);
        assert_eq!((h.points, h.last()), (0, None));
        // The emptied records' buffers are reused.
        let spare = h.spare.len();
        assert_eq!(spare, 5);
        push(&mut h, 0, 10);
        assert_eq!(h.spare.len(), spare - 1);
    }
}
