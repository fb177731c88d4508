//! Clearance over time, contacts, and the times marked on figures where things move.

use dmp::Trajectory;

use super::curve::Curve;
use super::input::Series;
use super::truth::Truth;

/// Most rows measured for a clearance computed here; longer trajectories are measured every k-th row (and the last).
const MAX_MEASURED: usize = 20_000;
/// Marked times of a figure where obstacles or robots move (evenly spaced over the run).
const MARKS: usize = 5;

/// Distance from the robot's point (dimensions `dims` of each row of `tr`) to the nearest true shape present, along
/// `tr`; infinite where no shape is present.
pub(crate) fn measured(tr: &Trajectory, dims: &[usize], truths: &[Truth<'_>]) -> Series {
    let n = tr.len();
    let stride = n.div_ceil(MAX_MEASURED).max(1);
    let mut rows: Vec<usize> = (0..n).step_by(stride).collect();
    if n > 0 && rows.last() != Some(&(n - 1)) {
        rows.push(n - 1);
    }
    let mut x = vec![0.0; dims.len()];
    let mut s = Series { t: Vec::with_capacity(rows.len()), v: Vec::with_capacity(rows.len()) };
    for k in rows {
        let t = tr.t[k];
        for (j, &d) in dims.iter().enumerate() {
            x[j] = tr.position(k)[d];
        }
        let d = if x.iter().all(|v| v.is_finite()) {
            truths
                .iter()
                .filter(|o| o.present_at(t))
                .map(|o| o.signed_distance(&x, t))
                .fold(f64::INFINITY, f64::min)
        } else {
            f64::NAN
        };
        s.t.push(t);
        s.v.push(d);
    }
    s
}

/// The stretches of `tr` where the clearance `s` is at most zero: a curve each, from the row at the start of the
/// contact to the row at its end.
pub(crate) fn contacts(tr: &Trajectory, s: &Series) -> Vec<Curve> {
    let mut out = Vec::new();
    if tr.is_empty() {
        return out;
    }
    let row = |t: f64| tr.t.partition_point(|v| *v < t - 1e-12).min(tr.len() - 1);
    let mut k = 0;
    while k < s.v.len() {
        if s.v[k] <= 0.0 {
            let start = k;
            while k + 1 < s.v.len() && s.v[k + 1] <= 0.0 {
                k += 1;
            }
            let (a, b) = (row(s.t[start]), row(s.t[k]));
            let idx: Vec<usize> = (a..=b.max(a)).step_by(((b - a) / 200).max(1)).collect();
            out.push(Curve::rows(tr, &idx));
        }
        k += 1;
    }
    out
}

/// [`MARKS`] times evenly spaced over `[t0, t1]`, and `extra` if it is finite and not near one of them.
pub(crate) fn marked_times(t0: f64, t1: f64, extra: f64) -> Vec<f64> {
    let span = t1 - t0;
    if !(span.is_finite() && span > 0.0) {
        return vec![t0];
    }
    let mut marks: Vec<f64> = (0..MARKS).map(|k| t0 + span * k as f64 / (MARKS - 1) as f64).collect();
    if extra.is_finite() && extra > t0 && extra < t1 && marks.iter().all(|m| (m - extra).abs() > 0.05 * span)
    {
        marks.push(extra);
        marks.sort_by(f64::total_cmp);
    }
    marks
}
