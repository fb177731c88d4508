//! The figure of plots against time, for robots that are neither 2-D nor 3-D: each coordinate in its own panel (at
//! most [`MAX_TIME_PANELS`]), the time strip under them, and the legend.

use crate::data::input::PlotInput;
use crate::data::run::Run;
use crate::draw::style::{OBSTACLE_EDGE, Stroke, band_fill};
use crate::error::PlotError;
use crate::layout::frame::{Frame, figure};
use crate::layout::legend::{Entry, Mark, path_entries, safety_entries};
use crate::panels::coordinate::{self, Panel};
use crate::panels::strip;

/// Most panels of a plot against time; further dimensions are left out (the legend says so).
pub(crate) const MAX_TIME_PANELS: usize = 6;

/// The figure of the first [`MAX_TIME_PANELS`] of the `d` coordinates against time.
pub(crate) fn render(input: &PlotInput<'_>, run: &Run<'_>, d: usize) -> Result<String, PlotError> {
    let shown = d.min(MAX_TIME_PANELS);
    let extents: Vec<Vec<(f64, f64)>> = input.obstacles.iter().map(coordinate::extent).collect();
    let (lo, hi) = run.time_span;
    let time = if hi > lo { (lo, hi) } else { (lo - 0.5, lo + 0.5) };
    let panels_data: Vec<Panel> = (0..shown).map(|j| Panel::new(input, run, j, &extents, time)).collect();

    let panels = vec![coordinate::SIZE; shown];
    let demo_text = if run.demo_timed { "demonstration" } else { "demonstration (time rescaled)" };
    let mut entries = path_entries(run, (!input.demonstration.is_empty()).then_some(demo_text), input.method);
    if !input.obstacles.is_empty() {
        entries
            .push(Entry::new(Mark::Patch(band_fill(), Stroke::solid(OBSTACLE_EDGE, 1.0)), "obstacle extent"));
    }
    entries.extend(safety_entries(run, false));
    let mut notes = Vec::new();
    if d > shown {
        notes.push(format!("showing {shown} of {d} coordinates"));
    }

    let frame = Frame {
        title: input.title,
        panels: &panels,
        vertical: true,
        legend: (&entries, &notes),
        strip_h: strip::height(input),
    };
    figure(
        &frame,
        |doc, k, area| panels_data[k].draw(doc, area, run, time),
        |doc, area| strip::draw(doc, area, input, run),
    )
}
