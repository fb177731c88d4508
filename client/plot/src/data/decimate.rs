//! Decimating curves: long trajectories keep every k-th row, or each bucket's peak (the drawing then also skips
//! points closer than a few pixels on screen).

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

/// `pts` decimated to at most about [`MAX_POINTS`] keeping each bucket's largest value (at its time): the peaks
/// of a noisy curve, such as a jerk, stay in the figure.
pub(crate) fn peaks(pts: &[(f64, f64)]) -> Vec<(f64, f64)> {
    if pts.len() <= MAX_POINTS {
        return pts.to_vec();
    }
    let size = pts.len().div_ceil(MAX_POINTS);
    pts.chunks(size)
        .map(|c| {
            // A non-finite value breaks the curve: it wins its bucket.
            c.iter()
                .copied()
                .find(|p| !p.1.is_finite())
                .unwrap_or_else(|| c.iter().copied().max_by(|a, b| a.1.total_cmp(&b.1)).unwrap_or(c[0]))
        })
        .collect()
}
