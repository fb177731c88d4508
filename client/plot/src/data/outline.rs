//! Outlines on a panel's plane: an obstacle's outline at a time, how finely outlines are sampled, and an outline
//! as it is drawn (at a marked time, or still).

use dmp::Obstacle;

use super::geometry::{P2, convex_hull, finite};

/// Boundary samples of a 2-D outline (in order around the obstacle).
pub(crate) const OUTLINE_SAMPLES_2D: usize = 200;
/// Boundary samples of a 3-D (or higher) obstacle, before projection and convex hull / extent.
pub(crate) const OUTLINE_SAMPLES_ND: usize = 2000;

/// An outline drawn at a time (`None`: it does not move).
#[derive(Debug)]
pub(crate) struct Outline {
    pub(crate) t: Option<f64>,
    pub(crate) poly: Vec<P2>,
    /// A point cloud: drawn as dots.
    pub(crate) cloud: bool,
}

/// The outline of `o` at time `t` on the local axes `(i, j)`: its boundary samples in order in 2-D, the convex hull
/// of its projected surface samples in 3-D.
pub(crate) fn obstacle_outline(o: &Obstacle, t: f64, (i, j): (usize, usize), n: usize) -> Vec<P2> {
    let d = o.dim();
    let mut c = vec![0.0; d];
    o.center_at(t, &mut c);
    let pts: Vec<P2> =
        o.boundary_offsets(n).chunks(d).map(|off| (off[i] + c[i], off[j] + c[j])).filter(finite).collect();
    if d == 2 { pts } else { convex_hull(pts) }
}
