//! Decimating curves: long trajectories keep every k-th row (the drawing then also skips points closer than a few
//! pixels on screen).

/// Longest polyline drawn per curve: longer trajectories are decimated (every k-th row, plus the last).
pub(crate) const MAX_POINTS: usize = 2000;

/// Row indices kept when decimating `n` rows to at most about [`MAX_POINTS`]: every k-th row and the last one.
pub(crate) fn decimated(n: usize) -> Vec<usize> {
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
