//! Robot space seen on a panel's plane: the planes of a 2-D or 3-D robot, everything projected on one of them
//! (paths, obstacles' outlines, footprints), and the data ranges, zoomed on the motion.

use dmp::Obstacle;

use super::bounds::Bounds;
use super::geometry::{P2, clip_polygon};
use super::input::PlotInput;
use super::margin::grown;
use super::outline::{Outline, obstacle_outline};
use super::run::Run;

/// The local axes `(i, j)` of the panels of a robot moving in `sub` (2 or 3) dimensions.
pub(crate) fn planes(sub: usize) -> Vec<(usize, usize)> {
    if sub == 2 { vec![(0, 1)] } else { vec![(0, 1), (0, 2), (1, 2)] }
}

/// Everything drawn on one plane, projected, and the data ranges.
#[derive(Debug)]
pub(crate) struct Plane {
    pub(crate) axes: (usize, usize),
    /// Per robot.
    pub(crate) demo: Vec<Vec<P2>>,
    pub(crate) free: Vec<Vec<P2>>,
    pub(crate) adapted: Vec<Vec<P2>>,
    pub(crate) starts: Vec<P2>,
    pub(crate) goals: Vec<P2>,
    /// Per robot, its contact stretches.
    pub(crate) contacts: Vec<Vec<Vec<P2>>>,
    /// Per robot, the path at the marked times.
    pub(crate) ticks: Vec<Vec<(f64, P2)>>,
    /// The isopotentials.
    pub(crate) iso: Vec<Outline>,
    /// The true shapes.
    pub(crate) truth: Vec<Outline>,
    /// The true shapes grown by their safety distance (those that keep one).
    pub(crate) margins: Vec<Outline>,
    /// Per robot, its footprint at the marked times (empty without a footprint).
    pub(crate) prints: Vec<Vec<Outline>>,
    pub(crate) ranges: ((f64, f64), (f64, f64)),
}

impl Plane {
    /// Everything of `run` projected on the plane of the local axes `axes`, obstacles outlined with `n` boundary
    /// samples: the paths, the isopotentials, the true shapes, and the robots' footprints (or a held tool).
    pub(crate) fn project(input: &PlotInput<'_>, run: &Run<'_>, axes: (usize, usize), n: usize) -> Self {
        let at = |is_moving: bool| -> Vec<Option<f64>> {
            if is_moving { run.marks.iter().map(|t| Some(*t)).collect() } else { vec![None] }
        };
        let mut iso = Vec::new();
        // Without true shapes given, the obstacles are their own: the isopotential is the outline drawn as the
        // shape.
        let isopotentials = if input.solids.is_empty() { &[][..] } else { input.obstacles };
        for o in isopotentials {
            for t in at(moving(o)) {
                let poly = obstacle_outline(o, t.unwrap_or(run.obstacle_time), axes, n);
                iso.push(Outline { t, poly, cloud: false });
            }
        }
        let mut truth = Vec::new();
        let mut margins = Vec::new();
        for s in &run.truths {
            let margin = if s.is_cloud() { 0.0 } else { run.safety.margin_of(s.id()) };
            for t in at(s.moving()) {
                if t.is_some_and(|t| !s.present_at(t)) {
                    continue;
                }
                let poly = s.outline(t.unwrap_or(run.obstacle_time), axes, n);
                if margin > 0.0 {
                    margins.push(Outline { t, poly: grown(&poly, margin), cloud: false });
                }
                truth.push(Outline { t, poly, cloud: s.is_cloud() });
            }
        }
        let prints = run
            .groups
            .iter()
            .map(|g| match g.footprint {
                Some(shape) if run.groups.len() > 1 => run
                    .marks
                    .iter()
                    .filter_map(|&t| {
                        let row = run.adapted_row_at(t);
                        let center: Vec<f64> = g.dims.iter().map(|&k| run.adapted.x[row][k]).collect();
                        let o = Obstacle::new(&g.label, shape.clone(), center, None, None).ok()?;
                        Some(Outline { t: Some(t), poly: obstacle_outline(&o, 0.0, axes, n), cloud: false })
                    })
                    .collect(),
                // One robot holding a tool: the tool where it is at each marked time.
                _ => match input.pose {
                    Some(pose) if run.single() => {
                        let (adapted, orientations) = (input.adapted, pose.orientations);
                        run.marks
                            .iter()
                            .filter_map(|&t| {
                                let k = adapted.t.partition_point(|s| *s < t).min(adapted.len() - 1);
                                let poly = pose.tool_outline(adapted.position(k), orientations.get(k)?, axes);
                                (!poly.is_empty()).then_some(Outline { t: Some(t), poly, cloud: false })
                            })
                            .collect()
                    }
                    _ => Vec::new(),
                },
            })
            .collect();
        Self::new(run, axes, iso, (truth, margins), prints)
    }

    /// Projects on the local axes `axes`; `iso`, `truth` (with the `margins`) and `prints` are already projected.
    fn new(
        run: &Run<'_>,
        axes: (usize, usize),
        iso: Vec<Outline>,
        (truth, margins): (Vec<Outline>, Vec<Outline>),
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
            margins,
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
        for o in self.iso.iter().chain(&self.truth).chain(&self.margins) {
            let clipped = clip_polygon(&o.poly, near);
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

/// Whether `o` moves (a nonzero velocity).
fn moving(o: &Obstacle) -> bool {
    o.velocity().iter().any(|v| *v != 0.0)
}
