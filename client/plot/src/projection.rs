//! Robot space seen on a panel's plane: the planes of a 2-D or 3-D robot, everything projected on one of them, and
//! outlines as ordered samples (2-D) or convex hulls of projected surface samples (3-D).

use super::bounds::Bounds;
use super::run::Run;
use super::space::Outlines;
use super::{P2, finite};

/// The local axes `(i, j)` of the panels of a robot moving in `sub` (2 or 3) dimensions.
pub(super) fn planes(sub: usize) -> Vec<(usize, usize)> {
    if sub == 2 { vec![(0, 1)] } else { vec![(0, 1), (0, 2), (1, 2)] }
}

/// Everything drawn on one plane, projected, and the data ranges with their margin.
#[derive(Debug)]
pub(super) struct Plane {
    pub(super) axes: (usize, usize),
    /// Per robot.
    pub(super) demo: Vec<Vec<P2>>,
    pub(super) free: Vec<Vec<P2>>,
    pub(super) adapted: Vec<Vec<P2>>,
    pub(super) starts: Vec<P2>,
    pub(super) goals: Vec<P2>,
    /// Per obstacle, at the obstacle time.
    pub(super) now: Vec<Vec<P2>>,
    /// Moving obstacles at the start and at the end.
    pub(super) ghosts: Vec<Vec<P2>>,
    /// Moving obstacles' centres from start to end.
    pub(super) paths: Vec<[P2; 2]>,
    /// Per robot (empty without a footprint).
    pub(super) prints: Vec<Vec<P2>>,
    pub(super) ranges: ((f64, f64), (f64, f64)),
}

impl Plane {
    /// Projects on the local axes `axes`; `ordered`: outlines are samples in order around the shape (2-D), else
    /// their convex hull is taken.
    pub(super) fn new(
        run: &Run<'_>,
        axes: (usize, usize),
        obstacles: &[Outlines],
        prints: &[Vec<Vec<f64>>],
        ordered: bool,
    ) -> Self {
        let local = |p: &[f64], dims: &[usize]| (p[dims[axes.0]], p[dims[axes.1]]);
        let mut pl = Self {
            axes,
            demo: run.groups.iter().map(|g| run.demo.plane(&g.dims, axes)).collect(),
            free: run.groups.iter().map(|g| run.free.plane(&g.dims, axes)).collect(),
            adapted: run.groups.iter().map(|g| run.adapted.plane(&g.dims, axes)).collect(),
            starts: run.groups.iter().map(|g| local(&run.start, &g.dims)).collect(),
            goals: run.groups.iter().map(|g| local(&run.goal, &g.dims)).collect(),
            now: obstacles.iter().map(|o| project_outline(&o.now, axes, ordered)).collect(),
            ghosts: obstacles
                .iter()
                .flat_map(|o| o.ghosts.iter().map(|g| project_outline(g, axes, ordered)))
                .collect(),
            paths: obstacles
                .iter()
                .filter_map(|o| {
                    o.path.as_ref().map(|(a, b)| [(a[axes.0], a[axes.1]), (b[axes.0], b[axes.1])])
                })
                .collect(),
            prints: prints.iter().map(|f| project_outline(f, axes, ordered)).collect(),
            ranges: ((0.0, 1.0), (0.0, 1.0)),
        };
        let mut b = Bounds::new();
        for set in [&pl.demo, &pl.free, &pl.adapted, &pl.now, &pl.ghosts, &pl.prints] {
            set.iter().for_each(|c| b.add_all(c));
        }
        b.add_all(&pl.starts);
        b.add_all(&pl.goals);
        pl.ranges = b.with_margin();
        pl
    }
}

/// Projected outline on local axes `(i, j)`: in 2-D the samples go around in order; in 3-D their convex hull.
fn project_outline(pts: &[Vec<f64>], (i, j): (usize, usize), ordered: bool) -> Vec<P2> {
    let p: Vec<P2> = pts.iter().map(|p| (p[i], p[j])).filter(finite).collect();
    if ordered { p } else { convex_hull(p) }
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
