//! Thinning curves: long trajectories keep every k-th row, and drawn points closer than a few pixels are skipped.

use super::P2;
use super::draw::Chart;

/// Longest polyline drawn per curve: longer trajectories are decimated (every k-th row, plus the last).
pub const MAX_POINTS: usize = 2000;
/// Smallest distance on screen, in device units (a pixel and a half), between consecutive drawn points of a curve.
const MIN_PIXEL_STEP: i64 = 3 * super::backend::SCALE as i64 / 2;

/// Row indices kept when decimating `n` rows to at most about [`MAX_POINTS`]: every k-th row and the last one.
pub(super) fn decimated(n: usize) -> Vec<usize> {
    if n <= MAX_POINTS {
        return (0..n).collect();
    }
    let stride = (n - 1).div_ceil(MAX_POINTS - 2);
    let mut idx: Vec<usize> = (0..n).step_by(stride).collect();
    if idx.last() != Some(&(n - 1)) {
        idx.push(n - 1);
    }
    idx
}

/// The points of `seg` at least [`MIN_PIXEL_STEP`] apart on screen (and the last one): denser points only make the
/// file bigger.
pub(super) fn thinned(chart: &Chart<'_>, seg: &[P2]) -> Vec<P2> {
    let mut out = Vec::with_capacity(seg.len());
    let mut last: Option<(i32, i32)> = None;
    for (k, p) in seg.iter().enumerate() {
        let q = chart.backend_coord(p);
        let far = last.is_none_or(|l| {
            let (dx, dy) = ((q.0 - l.0) as i64, (q.1 - l.1) as i64);
            dx * dx + dy * dy >= MIN_PIXEL_STEP * MIN_PIXEL_STEP
        });
        if far || k + 1 == seg.len() {
            out.push(*p);
            last = Some(q);
        }
    }
    out
}
