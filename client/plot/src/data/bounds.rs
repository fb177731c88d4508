//! Data ranges of a panel: bounds of what is drawn, margins, and the equal aspect ratio of robot-space panels.

use super::geometry::{P2, finite};

/// Margin around the data in geometric panels, as a fraction of the larger data span.
const MARGIN_FRAC: f64 = 0.06;

/// A data range `lo..hi` with nonzero width.
pub(crate) fn padded(lo: f64, hi: f64, frac: f64) -> (f64, f64) {
    if !(lo.is_finite() && hi.is_finite()) || lo > hi {
        return (-1.0, 1.0);
    }
    let span = hi - lo;
    let pad = if span > 0.0 { frac * span } else { 0.1 * lo.abs().max(1.0) };
    (lo - pad, hi + pad)
}

/// The bounding box of the finite points added.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Bounds {
    pub(crate) x0: f64,
    pub(crate) x1: f64,
    pub(crate) y0: f64,
    pub(crate) y1: f64,
}

impl Bounds {
    pub(crate) fn new() -> Self {
        Self { x0: f64::INFINITY, x1: f64::NEG_INFINITY, y0: f64::INFINITY, y1: f64::NEG_INFINITY }
    }

    pub(crate) fn add(&mut self, p: P2) {
        if finite(&p) {
            self.x0 = self.x0.min(p.0);
            self.x1 = self.x1.max(p.0);
            self.y0 = self.y0.min(p.1);
            self.y1 = self.y1.max(p.1);
        }
    }

    pub(crate) fn add_all(&mut self, pts: &[P2]) {
        pts.iter().for_each(|p| self.add(*p));
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.x0 > self.x1
    }

    /// The bounds grown by a margin of [`MARGIN_FRAC`] of the larger span on every side: `(x range, y range)`.
    pub(crate) fn with_margin(&self) -> ((f64, f64), (f64, f64)) {
        if self.is_empty() {
            return ((-1.0, 1.0), (-1.0, 1.0));
        }
        let span = (self.x1 - self.x0).max(self.y1 - self.y0);
        let scale = self.x0.abs().max(self.x1.abs()).max(self.y0.abs()).max(self.y1.abs()).max(1e-9);
        let m = if span > 0.0 { MARGIN_FRAC * span } else { 0.1 * scale };
        ((self.x0 - m, self.x1 + m), (self.y0 - m, self.y1 + m))
    }
}

/// Grows the narrower of the two ranges (about its centre) so that one data unit has the same length in pixels on
/// both axes of a `px_w` x `px_h` plotting area.
pub(crate) fn fit_equal_aspect(
    x: (f64, f64),
    y: (f64, f64),
    px_w: f64,
    px_h: f64,
) -> ((f64, f64), (f64, f64)) {
    let (mut xs, mut ys) = (x.1 - x.0, y.1 - y.0);
    let (cx, cy) = (0.5 * (x.0 + x.1), 0.5 * (y.0 + y.1));
    let r = px_w.max(1.0) / px_h.max(1.0);
    if xs / ys < r {
        xs = ys * r;
    } else {
        ys = xs / r;
    }
    ((cx - 0.5 * xs, cx + 0.5 * xs), (cy - 0.5 * ys, cy + 0.5 * ys))
}
