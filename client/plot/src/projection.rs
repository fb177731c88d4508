//! Robot space seen on a panel's plane: the planes of a 2-D or 3-D robot, everything projected on one of them, the
//! data ranges (zoomed on the motion), and the convex hull of projected outlines.

use super::bounds::Bounds;
use super::run::Run;
use super::{P2, finite};

/// The local axes `(i, j)` of the panels of a robot moving in `sub` (2 or 3) dimensions.
pub(super) fn planes(sub: usize) -> Vec<(usize, usize)> {
    if sub == 2 { vec![(0, 1)] } else { vec![(0, 1), (0, 2), (1, 2)] }
}

/// An outline drawn at a time (`None`: it does not move).
#[derive(Debug)]
pub(super) struct Outline {
    pub(super) t: Option<f64>,
    pub(super) poly: Vec<P2>,
    /// A point cloud: drawn as dots.
    pub(super) cloud: bool,
}

/// Everything drawn on one plane, projected, and the data ranges.
#[derive(Debug)]
pub(super) struct Plane {
    pub(super) axes: (usize, usize),
    /// Per robot.
    pub(super) demo: Vec<Vec<P2>>,
    pub(super) free: Vec<Vec<P2>>,
    pub(super) adapted: Vec<Vec<P2>>,
    pub(super) starts: Vec<P2>,
    pub(super) goals: Vec<P2>,
    /// Per robot, its contact stretches.
    pub(super) contacts: Vec<Vec<Vec<P2>>>,
    /// Per robot, the path at the marked times.
    pub(super) ticks: Vec<Vec<(f64, P2)>>,
    /// The isopotentials.
    pub(super) iso: Vec<Outline>,
    /// The true shapes.
    pub(super) truth: Vec<Outline>,
    /// Per robot, its footprint at the marked times (empty without a footprint).
    pub(super) prints: Vec<Vec<Outline>>,
    pub(super) ranges: ((f64, f64), (f64, f64)),
}

impl Plane {
    /// Projects on the local axes `axes`; `iso`, `truth` and `prints` are already projected.
    pub(super) fn new(
        run: &Run<'_>,
        axes: (usize, usize),
        iso: Vec<Outline>,
        truth: Vec<Outline>,
        prints: Vec<Vec<Outline>>,
    ) -> Self {
        let local = |p: &[f64], dims: &[usize]| (p[dims[axes.0]], p[dims[axes.1]]);
        let ticks = run
            .groups
            .iter()
            .map(|g| {
                run.marks
                    .iter()
                    .map(|&t| (t, local(&run.adapted.x[run.adapted_row_at(t)], &g.dims)))
                    .collect()
            })
            .collect();
        let mut pl = Self {
            axes,
            demo: run.groups.iter().map(|g| run.demo.plane(&g.dims, axes)).collect(),
            free: run.groups.iter().map(|g| run.free.plane(&g.dims, axes)).collect(),
            adapted: run.groups.iter().map(|g| run.adapted.plane(&g.dims, axes)).collect(),
            starts: run.groups.iter().map(|g| local(&run.start, &g.dims)).collect(),
            goals: run.groups.iter().map(|g| local(&run.goal, &g.dims)).collect(),
            contacts: run
                .groups
                .iter()
                .zip(&run.contacts)
                .map(|(g, cs)| cs.iter().map(|c| c.plane(&g.dims, axes)).collect())
                .collect(),
            ticks,
            iso,
            truth,
            prints,
            ranges: ((0.0, 1.0), (0.0, 1.0)),
        };
        pl.ranges = pl.zoomed();
        pl
    }

    /// The ranges: the motion (paths, start, goal, footprints), grown to take in the obstacles near it but not the
    /// far parts of large ones (a table under the arms does not shrink the motion to a corner).
    fn zoomed(&self) -> ((f64, f64), (f64, f64)) {
        let mut motion = Bounds::new();
        for set in [&self.demo, &self.free, &self.adapted] {
            set.iter().for_each(|c| motion.add_all(c));
        }
        motion.add_all(&self.starts);
        motion.add_all(&self.goals);
        self.prints.iter().flatten().for_each(|o| motion.add_all(&o.poly));
        if motion.is_empty() {
            return Bounds::new().with_margin();
        }
        // The neighbourhood: the motion's box grown by 40 % of its larger span on every side.
        let span = (motion.x1 - motion.x0).max(motion.y1 - motion.y0).max(1e-9);
        let grow = 0.4 * span;
        let near = ((motion.x0 - grow, motion.x1 + grow), (motion.y0 - grow, motion.y1 + grow));
        let mut all = motion;
        for o in self.iso.iter().chain(&self.truth) {
            let clipped = super::draw::clip_polygon(&o.poly, near);
            all.add_all(if o.cloud { &o.poly } else { &clipped });
        }
        let ((x0, x1), (y0, y1)) = near;
        all.x0 = all.x0.max(x0);
        all.x1 = all.x1.min(x1);
        all.y0 = all.y0.max(y0);
        all.y1 = all.y1.min(y1);
        all.with_margin()
    }
}

/// Convex hull (Andrew's monotone chain), counter-clockwise, without repeating the first vertex.
pub(super) fn convex_hull(mut p: Vec<P2>) -> Vec<P2> {
    p.retain(finite);
    p.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let cross = |o: P2, a: P2, b: P2| (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0);
    let mut hull: Vec<P2> = Vec::with_capacity(p.len() + 1);
    for q in p.iter() {
        while hull.len() >= 2 && cross(hull[hull.len() - 2], hull[hull.len() - 1], *q) <= 0.0 {
            hull.pop();
        }
        hull.push(*q);
    }
    let lower = hull.len() + 1;
    for q in p.iter().rev().skip(1) {
        while hull.len() >= lower && cross(hull[hull.len() - 2], hull[hull.len() - 1], *q) <= 0.0 {
            hull.pop();
        }
        hull.push(*q);
    }
    hull.pop();
    hull
}
