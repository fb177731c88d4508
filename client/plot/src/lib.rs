//! SVG figures of a scenario run, in the style of the paper's plots: the demonstration (dashed), the obstacle-free
//! DMP (dashed), the trajectory adapted by the avoidance (solid) and the obstacles' outlines.
//!
//! - Robots moving in 2-D: one panel `x1`-`x2` with an equal aspect ratio (an ellipse looks like an ellipse).
//! - Robots moving in 3-D: three panels, the projections on `x1`-`x2`, `x1`-`x3` and `x2`-`x3`, each with an equal
//!   aspect ratio; an obstacle is drawn as the convex hull of its projected surface samples.
//! - Anything else (1-D, more than 3-D): each coordinate against time, one panel per DMP dimension (at most
//!   [`MAX_TIME_PANELS`]); an obstacle shows as the band its extent along that coordinate sweeps.
//!
//! With several robots (each owning some dimensions of one DMP), every robot's path has its own colour in the shared
//! robot-space panel(s), the obstacles are drawn once, and each robot's footprint is outlined where it is at
//! [`PlotInput::obstacle_time`].
//!
//! Every obstacle is drawn twice: its true shape (a box, ball, cylinder or point cloud, [`Solid`]; filled) and, lighter
//! and dashed, the isopotential the robot avoids (the inflated superquadric, [`PlotInput::obstacles`]). Where the run
//! touches a true shape (clearance at most 0) the path is marked. Under the robot-space panels a strip of three
//! panels shows speed, acceleration and clearance to the nearest obstacle over time, with the run's events as
//! vertical lines. Moving obstacles and robots are outlined at several marked times, and the paths ticked at the same
//! times.
//!
//! Rendering goes through plotters into its own SVG backend (`backend.rs`): coordinates with sub-pixel precision, and
//! the parts of the figure in `<g class="...">` groups (`obstacle-true`, `isopotential`, `contact`, `event`,
//! `time-mark`, `path-free`, `path-adapted`, `legend-free`, `legend-adapted`, `speed`, `acceleration`,
//! `clearance`). Text is emitted as SVG `<text>` elements that the viewer lays out (plotters only estimates their
//! width for spacing), so no font library is needed. Text that fails to draw is dropped rather than failing the
//! figure.
//!
//! | concept | file |
//! | --- | --- |
//! | input, errors, entry point | `lib.rs` |
//! | the SVG backend: sub-pixel coordinates, groups | `backend.rs` |
//! | figure layout: title, panels, strip, legend | `layout.rs` |
//! | what is drawn: robots, decimated curves, start and goal | `run.rs` |
//! | true shapes: outlines, signed distance | `solid.rs` |
//! | clearance over time, contacts, marked times | `clearance.rs` |
//! | speed, acceleration and clearance against time, events | `strip.rs` |
//! | a pose run: orientation over time, the held tool's outline | `pose.rs` |
//! | legend | `legend.rs` |
//! | thinning curves (rows, then pixels) | `decimate.rs` |
//! | data ranges and equal aspect ratio | `bounds.rs` |
//! | drawing primitives on a chart | `draw.rs` |
//! | colours, strokes, legend | `style.rs` |
//! | robot-space panels (2-D, and 3-D projections) | `space.rs` |
//! | projecting on a plane, convex hull | `projection.rs` |
//! | coordinates against time | `time.rs` |

mod backend;
mod bounds;
mod clearance;
mod decimate;
mod draw;
mod layout;
mod legend;
mod pose;
mod projection;
mod run;
mod solid;
mod space;
mod strip;
mod style;
#[cfg(test)]
mod tests;
mod time;

use dmp::{Agent, Obstacle, Trajectory};

use self::run::{Run, groups};

pub use self::backend::SCALE;
pub use self::decimate::MAX_POINTS;
pub use self::pose::PoseTrace;
pub use self::solid::{Solid, SolidShape};

/// Most panels of a plot against time; further dimensions are left out (the legend says so).
pub const MAX_TIME_PANELS: usize = 6;
/// Boundary samples of a 2-D outline (in order around the obstacle).
const OUTLINE_SAMPLES_2D: usize = 200;
/// Boundary samples of a 3-D (or higher) obstacle, before projection and convex hull / extent.
const OUTLINE_SAMPLES_ND: usize = 2000;

/// A point in a panel's data coordinates.
type P2 = (f64, f64);

fn finite(p: &P2) -> bool {
    p.0.is_finite() && p.1.is_finite()
}

/// What to draw.
#[derive(Debug, Clone, Copy)]
pub struct PlotInput<'a> {
    /// Figure title.
    pub title: &'a str,
    /// The demonstration's positions, a row per sample, `d` columns (the full DMP dimension).
    pub demonstration: &'a [Vec<f64>],
    /// The demonstration's sample times, one per row of [`Self::demonstration`], used in plots against time;
    /// shifted so that the first sample is drawn at the start of the rollouts. `None`: the rows are spread evenly
    /// over the obstacle-free rollout's time span (and the legend says the time is rescaled).
    pub demonstration_t: Option<&'a [f64]>,
    /// The obstacle-free rollout; its first row is drawn as the start.
    pub free: &'a Trajectory,
    /// The rollout with avoidance.
    pub adapted: &'a Trajectory,
    /// The goal of the rollouts, `d` entries, drawn as the goal marker. `None`: the last row of the obstacle-free
    /// rollout is drawn as the goal.
    pub goal: Option<&'a [f64]>,
    /// Obstacles in robot space (each of a robot's dimension).
    pub obstacles: &'a [Obstacle],
    /// Robots sharing the DMP; empty for one robot owning every dimension.
    pub robots: &'a [Agent],
    /// A time worth marking when obstacles or robots move (e.g. when two robots are closest): moving obstacles and
    /// robot footprints are outlined at it and at evenly spaced times of the run. Not finite: only the latter.
    pub obstacle_time: f64,
    /// The true shapes of the obstacles (what a contact is measured against). Empty: each obstacle of
    /// [`Self::obstacles`] is its own true shape (the scenario format, where the superquadric is the obstacle).
    pub solids: &'a [Solid],
    /// The avoidance method of the adapted run, as the scenario format names it (`none`, `dynamic_volumetric`, ...):
    /// the legend says which run avoided what. `none` is labelled as a run without avoidance.
    pub method: &'a str,
    /// Clearance of each robot to the nearest obstacle over time, as the caller measured it (e.g. with the robot's
    /// body), in the order of the robots (one series for a single robot). `None`: the distance from the robot's
    /// controlled point to the nearest true shape present, along the adapted trajectory.
    pub clearance: Option<&'a [Series]>,
    /// What happened during the run, drawn as vertical lines in the time strip.
    pub events: &'a [Event],
    /// A pose run's orientations (a panel of the time strip) and held tool (outlined along the path at the marked
    /// times); `None` for a position run. Only for a robot moving in 3-D.
    pub pose: Option<PoseTrace<'a>>,
}

/// Values over time.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Series {
    /// Times, seconds.
    pub t: Vec<f64>,
    /// One value per time.
    pub v: Vec<f64>,
}

/// Something that happened at a time of the run: an obstacle appears or goes, the goal changes, a new scene version.
#[derive(Debug, Clone, PartialEq)]
pub struct Event {
    /// Time, seconds (the trajectories' clock).
    pub t: f64,
    /// What, short (drawn beside the line).
    pub label: String,
}

impl Event {
    /// An event.
    pub fn new(t: f64, label: impl Into<String>) -> Self {
        Self { t, label: label.into() }
    }
}

/// Why a figure could not be drawn.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// Something has the wrong number of dimensions.
    #[error("{what} has {found} dimensions, expected {expected}")]
    Dimension {
        /// What.
        what: String,
        /// Expected dimension.
        expected: usize,
        /// Its dimension.
        found: usize,
    },
    /// A list of the wrong length.
    #[error("{what} has {found} entries, expected {expected}")]
    Length {
        /// What.
        what: String,
        /// Expected length.
        expected: usize,
        /// Its length.
        found: usize,
    },
    /// A trajectory without rows.
    #[error("the {0} trajectory is empty")]
    EmptyTrajectory(&'static str),
    /// An inconsistent robot.
    #[error("robots[{index}]: {reason}")]
    Robot {
        /// Index in [`PlotInput::robots`].
        index: usize,
        /// What is wrong.
        reason: String,
    },
    /// The backend failed.
    #[error("drawing the SVG failed: {0}")]
    Drawing(String),
}

/// Renders the figure as a standalone SVG document. Deterministic: the same input gives the same bytes.
pub fn render_svg(input: &PlotInput<'_>) -> Result<String, PlotError> {
    let d = validate(input)?;
    let groups = groups(input, d)?;
    let sub = groups[0].dims.len();
    for o in input.obstacles {
        if o.dim() != sub {
            return Err(PlotError::Dimension {
                what: format!("obstacle `{}`", o.id()),
                expected: sub,
                found: o.dim(),
            });
        }
    }
    for s in input.solids {
        if s.center.len() != sub {
            return Err(PlotError::Dimension {
                what: format!("solid `{}`", s.id),
                expected: sub,
                found: s.center.len(),
            });
        }
    }
    if let Some(series) = input.clearance {
        if series.len() != groups.len() {
            return Err(PlotError::Length {
                what: "the clearance series".into(),
                expected: groups.len(),
                found: series.len(),
            });
        }
        for (k, s) in series.iter().enumerate() {
            if s.t.len() != s.v.len() {
                return Err(PlotError::Length {
                    what: format!("clearance series {k}'s values"),
                    expected: s.t.len(),
                    found: s.v.len(),
                });
            }
        }
    }
    if let Some(pose) = &input.pose {
        if sub != 3 || groups.len() != 1 {
            return Err(PlotError::Dimension { what: "a pose run's robot".into(), expected: 3, found: sub });
        }
        pose.validate(input.adapted.len(), input.free.len())?;
    }
    let run = Run::new(input, groups);
    match sub {
        2 | 3 => space::render(input, &run),
        _ => time::render(input, &run, d),
    }
}

/// Checks the trajectories, the demonstration and the goal against each other; returns the DMP dimension `d`.
fn validate(input: &PlotInput<'_>) -> Result<usize, PlotError> {
    if input.adapted.is_empty() {
        return Err(PlotError::EmptyTrajectory("adapted"));
    }
    let d = input.adapted.dim();
    if d == 0 {
        return Err(PlotError::Dimension { what: "the adapted trajectory".into(), expected: 1, found: 0 });
    }
    if input.free.dim() != d {
        return Err(PlotError::Dimension {
            what: "the obstacle-free trajectory".into(),
            expected: d,
            found: input.free.dim(),
        });
    }
    for (k, row) in input.demonstration.iter().enumerate() {
        if row.len() != d {
            return Err(PlotError::Dimension {
                what: format!("demonstration row {k}"),
                expected: d,
                found: row.len(),
            });
        }
    }
    if let Some(t) = input.demonstration_t
        && t.len() != input.demonstration.len()
    {
        return Err(PlotError::Length {
            what: "the demonstration's times".into(),
            expected: input.demonstration.len(),
            found: t.len(),
        });
    }
    if let Some(goal) = input.goal
        && goal.len() != d
    {
        return Err(PlotError::Dimension { what: "the goal".into(), expected: d, found: goal.len() });
    }
    Ok(d)
}
