//! The figure of robots moving in robot space: in 2-D one panel `x1`-`x2`, in 3-D the three projections, each with
//! an equal aspect ratio; the time strip under them, and the legend of everything drawn.

use plotters::prelude::*;

use crate::data::input::PlotInput;
use crate::data::outline::{OUTLINE_SAMPLES_2D, OUTLINE_SAMPLES_ND};
use crate::data::plane::{Plane, planes};
use crate::data::run::Run;
use crate::draw::style::{
    MARKER, OBSTACLE_EDGE, Stroke, contact_stroke, isopotential_fill, isopotential_stroke, obstacle_fill,
};
use crate::error::PlotError;
use crate::layout::frame::{Frame, figure};
use crate::layout::legend::{Entry, Mark, path_entries, safety_entries};
use crate::panels::{plane, strip};

/// The figure of a robot moving in 2-D or 3-D.
pub(crate) fn render(input: &PlotInput<'_>, run: &Run<'_>) -> Result<String, PlotError> {
    let sub = run.groups[0].dims.len();
    let n = if sub == 2 { OUTLINE_SAMPLES_2D } else { OUTLINE_SAMPLES_ND };
    let planes: Vec<Plane> =
        planes(sub).into_iter().map(|axes| Plane::project(input, run, axes, n)).collect();
    let panels: Vec<(u32, u32)> = planes.iter().map(|pl| plane::size(pl, sub)).collect();
    let mut entries = legend(input, run, planes.iter().any(|p| p.prints.iter().any(|f| !f.is_empty())));
    entries.extend(safety_entries(run, planes.iter().any(|p| !p.margins.is_empty())));
    let frame = Frame {
        title: input.title,
        panels: &panels,
        vertical: false,
        legend: (&entries, &[]),
        strip_h: strip::height(input),
    };
    figure(
        &frame,
        |doc, k, area| plane::draw(doc, area, &planes[k], run, sub),
        |doc, area| strip::draw(doc, area, input, run),
    )
}

/// The legend: the paths, then what else the panels show (true shapes, points seen, isopotentials, contacts,
/// marked times, footprints or a held tool), then start and goal.
fn legend(input: &PlotInput<'_>, run: &Run<'_>, footprints: bool) -> Vec<Entry> {
    let mut entries =
        path_entries(run, (!input.demonstration.is_empty()).then_some("demonstration"), input.method);
    if !run.truths.is_empty() {
        let text = if input.solids.is_empty() {
            "obstacle (its isopotential C = 0)"
        } else {
            "obstacle (true shape)"
        };
        entries.push(
            Entry::new(Mark::Patch(obstacle_fill(), Stroke::solid(OBSTACLE_EDGE, 1.0)), text)
                .class("legend-true"),
        );
    }
    if run.truths.iter().any(|t| t.is_cloud()) {
        entries.push(
            Entry::new(
                Mark::Patch(OBSTACLE_EDGE.to_rgba(), Stroke::solid(OBSTACLE_EDGE, 1.0)),
                "points seen",
            )
            .class("legend-points"),
        );
    }
    if !input.obstacles.is_empty() && !input.solids.is_empty() {
        entries.push(
            Entry::new(Mark::Patch(isopotential_fill(), isopotential_stroke()), "isopotential avoided")
                .class("legend-isopotential"),
        );
    }
    if run.contacts.iter().any(|c| !c.is_empty()) {
        entries.push(Entry::new(Mark::Line(contact_stroke()), "contact").class("legend-contact"));
    }
    if !run.marks.is_empty() {
        entries.push(Entry::new(Mark::Dot, "path and obstacles at t (s)").class("legend-time-mark"));
    }
    if footprints {
        let (text, class) =
            if run.single() { ("tool at t (s)", "legend-tool") } else { ("footprints", "legend-footprints") };
        entries.push(
            Entry::new(Mark::Patch(TRANSPARENT.to_rgba(), Stroke::solid(MARKER, 1.0)), text).class(class),
        );
    }
    entries.push(Entry::new(Mark::Dot, "start"));
    entries.push(Entry::new(Mark::Cross, "goal"));
    entries
}
