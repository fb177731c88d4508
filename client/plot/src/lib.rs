//! SVG figures of a scenario run, in the style of the paper's plots: the demonstration (dashed), the obstacle-free
//! DMP (dashed), the trajectory adapted by the avoidance (solid) and the obstacles' outlines.
//!
//! - Robots moving in 2-D: one panel `x1`-`x2` with an equal aspect ratio (an ellipse looks like an ellipse).
//! - Robots moving in 3-D: three panels, the projections on `x1`-`x2`, `x1`-`x3` and `x2`-`x3`, each with an equal
//!   aspect ratio; an obstacle is drawn as the convex hull of its projected surface samples.
//! - Anything else (1-D, more than 3-D): each coordinate against time, one panel per DMP dimension (at most six,
//!   the rest named in the legend); an obstacle shows as the band its extent along that coordinate sweeps.
//!
//! With several robots (each owning some dimensions of one DMP), every robot's path has its own colour in the shared
//! robot-space panel(s), the obstacles are drawn once, and each robot's footprint is outlined where it is at
//! [`PlotInput::obstacle_time`].
//!
//! Every obstacle is drawn twice: its true shape (a box, ball, cylinder or point cloud, [`Solid`]; filled) and, lighter
//! and dashed, the isopotential the robot avoids (the inflated superquadric, [`PlotInput::obstacles`]). Where the run
//! touches a true shape (clearance at most 0) the path is marked. Under the robot-space panels a strip of panels
//! shows speed, acceleration, jerk and clearance to the nearest obstacle over time (and for a pose run, beside them,
//! the angular speed, acceleration and jerk and the rotation from the start), with the run's events as vertical
//! lines. The jerk, and the angular quantities, are finite differences of the setpoints at the output rate, as a
//! robot judges them. Moving obstacles and robots are outlined at several marked times, and the paths ticked at the
//! same times.
//!
//! With [`render_svg_with`], the limits the run kept ([`Safety`], the server's `LimitsInForce`) are drawn as dashed
//! lines on the panels they bound, with the profile they came from in the legend, and each true shape that keeps a
//! safety distance is outlined, dashed, that far out.
//!
//! Rendering goes through plotters into its own SVG backend (`draw/backend.rs`): coordinates with sub-pixel
//! precision, and the parts of the figure in `<g class="...">` groups (`obstacle-true`, `isopotential`, `contact`,
//! `event`, `time-mark`, `path-free`, `path-adapted`, `legend-free`, `legend-adapted`, `speed`, `acceleration`,
//! `jerk`, `clearance`, `limit`, `margin`, `legend-limits`, `legend-margin`). Text is emitted as SVG `<text>`
//! elements that the viewer lays out (plotters only estimates their width for spacing), so no font library is
//! needed. Text that fails to draw is dropped rather than failing the figure.
//!
//! The modules are layers, each using only the layers listed before it (and `error`, under all of them):
//!
//! 1. `data`: what a figure shows, before drawing (no plotters, no SVG);
//! 2. `draw`: the SVG backend, how things look, drawing primitives;
//! 3. `layout`: the figure's frame, a panel's chart, the legend;
//! 4. `panels`: each kind of panel;
//! 5. `figures`: whole figures, which [`render_svg`] picks from.
//!
//! | concept | file |
//! | --- | --- |
//! | entry point, the public API | `lib.rs` |
//! | why a figure cannot be drawn | `error.rs` |
//! | the input: runs, obstacles, robots, events, series | `data/input.rs` |
//! | checking the input for consistency | `data/validate.rs` |
//! | robots as groups of DMP dimensions | `data/group.rs` |
//! | decimated curves: positions, coordinates and norms against time | `data/curve.rs` |
//! | decimating long trajectories (every k-th row, or each bucket's peak) | `data/decimate.rs` |
//! | speed, acceleration and jerk as finite differences at the output rate | `data/differences.rs` |
//! | the limits and safety distances a run kept | `data/safety.rs` |
//! | a true shape's outline grown by its safety margin | `data/margin.rs` |
//! | the time strip's quantities: its grid of panels and their curves | `data/quantity.rs` |
//! | everything a figure shows, extracted from the input | `data/run.rs` |
//! | true shapes given: box, ball, cylinder, points; signed distance | `data/solid.rs` |
//! | true shapes as measured and drawn (given, or the obstacle itself) | `data/truth.rs` |
//! | clearance over time, contacts, marked times | `data/clearance.rs` |
//! | a pose run: orientation over time, the held tool's outline | `data/pose.rs` |
//! | outlines of obstacles on a plane, sampling | `data/outline.rs` |
//! | robot space projected on a panel's plane, zoomed on the motion | `data/plane.rs` |
//! | data ranges and equal aspect ratio | `data/bounds.rs` |
//! | points, clipping, convex hull | `data/geometry.rs` |
//! | the SVG backend: sub-pixel coordinates, groups | `draw/backend.rs` |
//! | colours, strokes, number formats | `draw/style.rs` |
//! | drawing primitives on a chart (curves, outlines, text, axes) | `draw/primitives.rs` |
//! | figure frame: title, panels, strip, legend column | `layout/frame.rs` |
//! | a panel's chart: caption, margins, fitted ranges | `layout/chart.rs` |
//! | legend | `layout/legend.rs` |
//! | a robot-space panel: one plane (2-D), or one projection (3-D) | `panels/plane.rs` |
//! | a coordinate against time | `panels/coordinate.rs` |
//! | the time strip: its panels against time, events and limit lines | `panels/strip.rs` |
//! | the figure of a robot moving in 2-D or 3-D | `figures/space.rs` |
//! | the figure of coordinates against time | `figures/time.rs` |

#![warn(missing_docs)]
#![warn(unreachable_pub)]

mod data;
mod draw;
mod error;
mod figures;
mod layout;
mod panels;
#[cfg(test)]
mod tests;

use self::data::group::groups;
use self::data::run::Run;
use self::data::validate;

pub use self::data::input::{Event, PlotInput, Series};
pub use self::data::pose::PoseTrace;
pub use self::data::safety::Safety;
pub use self::data::solid::{Solid, SolidShape};
pub use self::error::PlotError;

/// Renders the figure as a standalone SVG document, without limit lines or safety margins. Deterministic: the same
/// input gives the same bytes.
pub fn render_svg(input: &PlotInput<'_>) -> Result<String, PlotError> {
    render_svg_with(input, &Safety::default())
}

/// Renders the figure as a standalone SVG document, with the limits the run kept drawn on the time strip (a line
/// for each limit that applies, the profile named in the legend) and the obstacles' true shapes outlined at their
/// safety distance. Deterministic: the same input gives the same bytes.
pub fn render_svg_with(input: &PlotInput<'_>, safety: &Safety) -> Result<String, PlotError> {
    let d = validate::dmp_dimension(input)?;
    let groups = groups(input, d)?;
    validate::against_robots(input, &groups)?;
    let sub = groups[0].dims.len();
    let run = Run::new(input, groups, safety);
    match sub {
        2 | 3 => figures::space::render(input, &run),
        _ => figures::time::render(input, &run, d),
    }
}
