//! What a figure shows, extracted from a [`PlotInput`] and decimated: the robots, the curves, start and goal, the
//! true shapes with the clearance to them and the contacts, and the marked times.

use super::clearance::{contacts, marked_times, measured};
use super::curve::Curve;
use super::group::Group;
use super::input::{PlotInput, Series};
use super::safety::Safety;
use super::truth::{Truth, truths};

/// Everything extracted from the input, decimated.
#[derive(Debug)]
pub(crate) struct Run<'a> {
    pub(crate) groups: Vec<Group<'a>>,
    pub(crate) demo: Curve,
    /// Whether [`Self::demo`] has its own times (else it is spread over the rollout's span).
    pub(crate) demo_timed: bool,
    pub(crate) free: Curve,
    pub(crate) adapted: Curve,
    pub(crate) start: Vec<f64>,
    pub(crate) goal: Vec<f64>,
    pub(crate) t0: f64,
    pub(crate) t1: f64,
    /// The time axis of plots against time: `[t0, t1]`, widened to the demonstration's own times.
    pub(crate) time_span: (f64, f64),
    pub(crate) obstacle_time: f64,
    /// The true shapes.
    pub(crate) truths: Vec<Truth<'a>>,
    /// Clearance to the nearest true shape over time, per robot.
    pub(crate) clearance: Vec<Series>,
    /// Where each robot touches a true shape: its adapted path during each contact.
    pub(crate) contacts: Vec<Vec<Curve>>,
    /// Times at which moving obstacles and footprints are outlined and the paths ticked (empty: nothing moves).
    pub(crate) marks: Vec<f64>,
    /// The limits and safety distances the run kept.
    pub(crate) safety: &'a Safety,
}

impl<'a> Run<'a> {
    pub(crate) fn new(input: &PlotInput<'a>, groups: Vec<Group<'a>>, safety: &'a Safety) -> Self {
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
            safety,
        }
    }

    pub(crate) fn single(&self) -> bool {
        self.groups.len() == 1
    }

    /// Row of the adapted trajectory closest in time to `t`.
    pub(crate) fn adapted_row_at(&self, t: f64) -> usize {
        let k = self.adapted.t.partition_point(|s| *s < t);
        k.min(self.adapted.t.len() - 1)
    }
}
