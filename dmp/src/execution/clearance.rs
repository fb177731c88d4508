//! The clearance a stretch reports: per member, the smallest distance over its points from the robot's point to an
//! obstacle's true shape (as the run holds it: with the obstacle's own margin, and a tool's axis inflation).
//!
//! Exact ([`crate::distance`]) where it is under [`EXACT_WITHIN`]; beyond, a lower bound from each obstacle's
//! bounding ball, `|x - c| - R` (a point that far from every obstacle is reported at least that far). A point's exact
//! distance is computed only when its ball bound, and the bound the last exact distance gives (the distance is
//! 1-Lipschitz), are both below the smallest distance found so far: about one exact distance per obstacle near a
//! stretch instead of one per point.

use super::{Execution, Stretch};
use crate::distance::signed_distance_world;

/// Clearances under this are exact, metres.
pub const EXACT_WITHIN: f64 = 0.25;

impl Execution {
    /// Fills `p.min_clearance`: one value per member, `f64::INFINITY` for a member without obstacles; nothing for
    /// a run with a tool (its clearance is the tool's, not its point's).
    pub(super) fn fill_clearance(&self, p: &mut Stretch) {
        p.min_clearance.clear();
        if self.tool.is_some() {
            return;
        }
        let d = self.primitive.dim;
        let n = p.x.len() / d.max(1);
        let dt = self.stepping.dt;
        let obstacles = &self.field.scene().obstacles;
        let mut x = Vec::new();
        let mut c = Vec::new();
        for m in self.field.agents() {
            let mut best = f64::INFINITY;
            let sub = m.dims.len();
            x.resize(sub, 0.0);
            c.resize(sub, 0.0);
            for o in obstacles.iter().filter(|o| o.dim() == sub) {
                let r = o.shape().bounding_radius_sq().sqrt();
                let w = o.velocity().iter().map(|v| v * v).sum::<f64>().sqrt();
                // The last exact distance, where and when: the distance is 1-Lipschitz in the point and moves at most
                // `w` per second with the obstacle, so it bounds the next points' from below.
                let mut exact: Option<(f64, usize, f64)> = None;
                for k in 0..n {
                    let t = p.start_time + k as f64 * dt;
                    for (xi, &i) in x.iter_mut().zip(&m.dims) {
                        *xi = p.x[k * d + i];
                    }
                    if let Some((e, j, te)) = exact {
                        let moved =
                            m.dims.iter().map(|&i| (p.x[k * d + i] - p.x[j * d + i]).powi(2)).sum::<f64>();
                        if e - moved.sqrt() - w * (t - te) >= best {
                            continue;
                        }
                    }
                    o.center_at(t, &mut c);
                    let ball = x.iter().zip(&c).map(|(a, b)| (a - b) * (a - b)).sum::<f64>().sqrt() - r;
                    if ball >= best {
                        continue;
                    }
                    if ball > EXACT_WITHIN {
                        best = ball;
                    } else {
                        let e = signed_distance_world(o, &x, t);
                        exact = Some((e, k, t));
                        best = best.min(e);
                    }
                }
            }
            p.min_clearance.push(best);
        }
    }
}
