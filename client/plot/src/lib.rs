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
//! Rendering uses plotters' SVG backend without its `ttf` feature: text is emitted as SVG `<text>` elements that the
//! viewer lays out (plotters only estimates their width for spacing), so no font library is needed. Text that fails to
//! draw is dropped rather than failing the figure.
//!
//! | concept | file |
//! | --- | --- |
//! | input, errors, entry point, figure layout | `lib.rs` |
//! | what is drawn: robots, decimated curves, start and goal | `run.rs` |
//! | thinning curves (rows, then pixels) | `decimate.rs` |
//! | data ranges and equal aspect ratio | `bounds.rs` |
//! | drawing primitives on a chart | `draw.rs` |
//! | colours, strokes, legend | `style.rs` |
//! | robot-space panels (2-D, and 3-D projections) | `space.rs` |
//! | projecting on a plane, convex hull | `projection.rs` |
//! | coordinates against time | `time.rs` |

mod bounds;
mod decimate;
mod draw;
mod projection;
mod run;
mod space;
mod style;
#[cfg(test)]
mod tests;
mod time;

use plotters::prelude::*;
use plotters::style::text_anchor::HPos;

use dmp::{Agent, Obstacle, Trajectory};

use self::draw::{Area, Chart, drawing_err, put_text};
use self::run::{Run, groups};
use self::style::{Entry, FONT, draw_legend, legend_height};

pub use self::decimate::MAX_POINTS;

/// Most panels of a plot against time; further dimensions are left out (the legend says so).
pub const MAX_TIME_PANELS: usize = 6;
/// Boundary samples of a 2-D outline (in order around the obstacle).
const OUTLINE_SAMPLES_2D: usize = 200;
/// Boundary samples of a 3-D (or higher) obstacle, before projection and convex hull / extent.
const OUTLINE_SAMPLES_ND: usize = 2000;

const TITLE_H: u32 = 40;
const LEGEND_W: u32 = 300;
const PANEL_MARGIN: u32 = 12;
const X_LABEL_AREA: u32 = 44;
const Y_LABEL_AREA: u32 = 64;
const CAPTION_H: u32 = 28;

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
    /// Time at which moving obstacles (and robot footprints) are drawn; moving obstacles are also outlined faintly
    /// at the start and at the end of the run.
    pub obstacle_time: f64,
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

// ------------------------------------------------------------------------------------------------------------------
// Layout.

/// The figure: title band on top, panels in a row or a column, legend on the right.
fn figure(
    title: &str,
    panels: &[(u32, u32)],
    vertical: bool,
    legend: (&[Entry], &[String]),
    mut draw_panel: impl FnMut(usize, &Area<'_>) -> Result<(), PlotError>,
) -> Result<String, PlotError> {
    let (pw, ph) = if vertical {
        (panels.iter().map(|p| p.0).max().unwrap_or(0), panels.iter().map(|p| p.1).sum::<u32>())
    } else {
        (panels.iter().map(|p| p.0).sum::<u32>(), panels.iter().map(|p| p.1).max().unwrap_or(0))
    };
    let size = (pw + LEGEND_W, TITLE_H + ph.max(legend_height(legend.0, legend.1)));
    let mut buf = String::new();
    {
        let root = SVGBackend::with_string(&mut buf, size).into_drawing_area();
        root.fill(&WHITE).map_err(drawing_err)?;
        let (top, rest) = root.split_vertically(TITLE_H);
        let (tw, _) = top.dim_in_pixel();
        put_text(&top, title, (tw as i32 / 2, TITLE_H as i32 / 2 + 2), 24, HPos::Center);
        let (panel_area, legend_area) = rest.split_horizontally(pw);
        let mut offset = 0;
        for (k, &(w, h)) in panels.iter().enumerate() {
            let area = if vertical {
                panel_area.clone().shrink((0, offset), (w, h))
            } else {
                panel_area.clone().shrink((offset, 0), (w, h))
            };
            offset += if vertical { h } else { w };
            draw_panel(k, &area)?;
        }
        draw_legend(&legend_area, legend.0, legend.1)?;
        root.present().map_err(drawing_err)?;
    }
    Ok(buf)
}

/// `area` below a caption (the caption is dropped if its text cannot be drawn).
fn captioned<'b>(area: &Area<'b>, caption: Option<&str>) -> Area<'b> {
    match caption {
        None => area.clone(),
        Some(c) => area.titled(c, (FONT, 19)).unwrap_or_else(|_| area.split_vertically(CAPTION_H).1),
    }
}

/// Chart on `area`, built twice: once to measure the plotting area, once with the ranges `fit` gives for its
/// size in pixels.
fn chart_on<'c, 'b>(
    area: &'c Area<'b>,
    fit: impl FnOnce(f64, f64) -> ((f64, f64), (f64, f64)),
) -> Result<Chart<'c, 'b>, PlotError> {
    let mut builder = ChartBuilder::on(area);
    builder.margin(PANEL_MARGIN).x_label_area_size(X_LABEL_AREA).y_label_area_size(Y_LABEL_AREA);
    // Building draws nothing (no caption here), so the builder can be used twice.
    let (pw, ph) =
        builder.build_cartesian_2d(0.0..1.0, 0.0..1.0).map_err(drawing_err)?.plotting_area().dim_in_pixel();
    let (x, y) = fit(pw.saturating_sub(1) as f64, ph.saturating_sub(1) as f64);
    builder.build_cartesian_2d(x.0..x.1, y.0..y.1).map_err(drawing_err)
}
