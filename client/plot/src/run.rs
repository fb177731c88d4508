//! What a figure shows, extracted from a [`PlotInput`] and decimated: the robots, the curves, start and goal.

use plotters::prelude::*;

use dmp::{Shape, Trajectory};

use super::clearance::{contacts, marked_times, measured};
use super::decimate::decimated;
use super::solid::{Truth, truths};
use super::style::{ADAPTED, FREE, PALETTE, Stroke};
use super::{P2, PlotError, PlotInput, Series};

/// A robot: the DMP dimensions it owns and how it is drawn.
#[derive(Debug)]
pub(super) struct Group<'a> {
    pub(super) label: String,
    pub(super) dims: Vec<usize>,
    pub(super) color: RGBColor,
    pub(super) footprint: Option<&'a Shape>,
}

/// The robots of `input` (one owning all `d` dimensions if none is given), checked against each other and `d`.
pub(super) fn groups<'a>(input: &PlotInput<'a>, d: usize) -> Result<Vec<Group<'a>>, PlotError> {
    if input.robots.is_empty() {
        return Ok(vec![Group {
            label: "robot".into(),
            dims: (0..d).collect(),
            color: ADAPTED,
            footprint: None,
        }]);
    }
    let sub = input.robots[0].dims.len();
    for (index, r) in input.robots.iter().enumerate() {
        if r.dims.is_empty() {
            return Err(PlotError::Robot { index, reason: "owns no dimension".into() });
        }
        if r.dims.len() != sub {
            return Err(PlotError::Robot {
                index,
                reason: format!("owns {} dimensions, robots[0] owns {sub}", r.dims.len()),
            });
        }
        if let Some(k) = r.dims.iter().find(|&&k| k >= d) {
            return Err(PlotError::Robot {
                index,
                reason: format!("dimension {k} is outside the DMP's {d}"),
            });
        }
    }
    Ok(input
        .robots
        .iter()
        .enumerate()
        .map(|(i, r)| Group {
            label: r.id.clone(),
            dims: r.dims.clone(),
            color: PALETTE[i % PALETTE.len()],
            footprint: r.footprint.as_ref(),
        })
        .collect())
}

/// A decimated curve: times and full-dimensional positions (and, for rollouts, velocities and accelerations).
#[derive(Debug, Default)]
pub(super) struct Curve {
    pub(super) t: Vec<f64>,
    pub(super) x: Vec<Vec<f64>>,
    pub(super) v: Vec<Vec<f64>>,
    pub(super) a: Vec<Vec<f64>>,
}

impl Curve {
    fn of(tr: &Trajectory) -> Self {
        Self::rows(tr, &decimated(tr.len()))
    }

    /// Rows `idx` of `tr`.
    pub(super) fn rows(tr: &Trajectory, idx: &[usize]) -> Self {
        Self {
            t: idx.iter().map(|&k| tr.t[k]).collect(),
            x: idx.iter().map(|&k| tr.position(k).to_vec()).collect(),
            v: idx.iter().map(|&k| tr.velocity(k).to_vec()).collect(),
            a: idx.iter().map(|&k| tr.acceleration(k).to_vec()).collect(),
        }
    }

    /// The norm over `dims` of `rows` (velocities or accelerations) against time.
    pub(super) fn norm_against_time(&self, rows: &[Vec<f64>], dims: &[usize]) -> Vec<P2> {
        self.t
            .iter()
            .zip(rows)
            .map(|(t, r)| (*t, dims.iter().map(|&k| r[k] * r[k]).sum::<f64>().sqrt()))
            .collect()
    }

    /// The demonstration, its rows spread evenly over `[t0, t1]`.
    fn spread(rows: &[Vec<f64>], t0: f64, t1: f64) -> Self {
        let idx = decimated(rows.len());
        let n = rows.len().saturating_sub(1).max(1) as f64;
        Self {
            t: idx.iter().map(|&k| t0 + (t1 - t0) * k as f64 / n).collect(),
            x: idx.iter().map(|&k| rows[k].clone()).collect(),
            ..Self::default()
        }
    }

    /// The demonstration at its own times `times` (one per row), shifted so that its first sample is at `t0`.
    fn timed(rows: &[Vec<f64>], times: &[f64], t0: f64) -> Self {
        let idx = decimated(rows.len());
        let first = times.first().copied().unwrap_or(0.0);
        Self {
            t: idx.iter().map(|&k| times[k] - first + t0).collect(),
            x: idx.iter().map(|&k| rows[k].clone()).collect(),
            ..Self::default()
        }
    }

    /// Positions restricted to `dims`, then projected on the local axes `(i, j)`.
    pub(super) fn plane(&self, dims: &[usize], (i, j): (usize, usize)) -> Vec<P2> {
        self.x.iter().map(|p| (p[dims[i]], p[dims[j]])).collect()
    }

    /// Coordinate `k` against time.
    pub(super) fn against_time(&self, k: usize) -> Vec<P2> {
        self.t.iter().zip(&self.x).map(|(t, p)| (*t, p[k])).collect()
    }
}

/// Everything extracted from the input, decimated.
#[derive(Debug)]
pub(super) struct Run<'a> {
    pub(super) groups: Vec<Group<'a>>,
    pub(super) demo: Curve,
    /// Whether [`Self::demo`] has its own times (else it is spread over the rollout's span).
    pub(super) demo_timed: bool,
    pub(super) free: Curve,
    pub(super) adapted: Curve,
    pub(super) start: Vec<f64>,
    pub(super) goal: Vec<f64>,
    pub(super) t0: f64,
    pub(super) t1: f64,
    /// The time axis of plots against time: `[t0, t1]`, widened to the demonstration's own times.
    pub(super) time_span: (f64, f64),
    pub(super) obstacle_time: f64,
    /// The true shapes.
    pub(super) truths: Vec<Truth<'a>>,
    /// Clearance to the nearest true shape over time, per robot.
    pub(super) clearance: Vec<Series>,
    /// Where each robot touches a true shape: its adapted path during each contact.
    pub(super) contacts: Vec<Vec<Curve>>,
    /// Times at which moving obstacles and footprints are outlined and the paths ticked (empty: nothing moves).
    pub(super) marks: Vec<f64>,
}

impl<'a> Run<'a> {
    pub(super) fn new(input: &PlotInput<'a>, groups: Vec<Group<'a>>) -> Self {
        let reference = if input.free.is_empty() { input.adapted } else { input.free };
        let t0 = reference.t[0];
        let t1 =
            input.free.t.last().copied().unwrap_or(t0).max(input.adapted.t.last().copied().unwrap_or(t0));
        let obstacle_time = if input.obstacle_time.is_finite() { input.obstacle_time } else { t0 };
        let demo = match input.demonstration_t {
            Some(times) => Curve::timed(input.demonstration, times, t0),
            None => Curve::spread(input.demonstration, t0, reference.t.last().copied().unwrap_or(t0)),
        };
        let mut time_span = (t0, t1);
        if input.demonstration_t.is_some() {
            for t in demo.t.iter().filter(|t| t.is_finite()) {
                time_span = (time_span.0.min(*t), time_span.1.max(*t));
            }
        }
        let goal = match input.goal {
            Some(goal) => goal.to_vec(),
            None => reference.position(reference.len() - 1).to_vec(),
        };
        let truths = truths(input.solids, input.obstacles);
        let moving = input.obstacles.iter().any(|o| o.velocity().iter().any(|v| *v != 0.0))
            || truths.iter().any(|t| t.moving());
        let clearance = match input.clearance {
            Some(series) => series.to_vec(),
            None => groups.iter().map(|g| measured(input.adapted, &g.dims, &truths)).collect(),
        };
        let contacts = clearance.iter().map(|s| contacts(input.adapted, s)).collect();
        let footprints = groups.len() > 1 && groups.iter().any(|g| g.footprint.is_some());
        let tool = input.pose.is_some_and(|p| !p.tool_surface.is_empty());
        let marks =
            if moving || footprints || tool { marked_times(t0, t1, obstacle_time) } else { Vec::new() };
        Self {
            groups,
            demo,
            demo_timed: input.demonstration_t.is_some(),
            free: Curve::of(input.free),
            adapted: Curve::of(input.adapted),
            start: reference.position(0).to_vec(),
            goal,
            t0,
            t1,
            time_span,
            obstacle_time,
            truths,
            clearance,
            contacts,
            marks,
        }
    }

    pub(super) fn single(&self) -> bool {
        self.groups.len() == 1
    }

    pub(super) fn free_stroke(&self, g: &Group<'_>) -> Stroke {
        if self.single() {
            Stroke::dashed(FREE, 1.8, (9, 5))
        } else {
            Stroke { color: g.color.mix(0.7), width: 1.5, dash: Some((8, 5)) }
        }
    }

    pub(super) fn adapted_stroke(&self, g: &Group<'_>) -> Stroke {
        Stroke::solid(if self.single() { ADAPTED } else { g.color }, 2.0)
    }

    /// Row of the adapted trajectory closest in time to `t`.
    pub(super) fn adapted_row_at(&self, t: f64) -> usize {
        let k = self.adapted.t.partition_point(|s| *s < t);
        k.min(self.adapted.t.len() - 1)
    }
}
