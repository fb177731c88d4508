//! The legend: a symbol and a text per entry, in a frame; each entry in its own group (`legend-free`,
//! `legend-adapted`, ...) so that a reader can tell which line is which run.

use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::HPos;

use crate::data::run::Run;
use crate::draw::backend::{Doc, SharedDoc, px};
use crate::draw::primitives::{Area, drawing_err, put_text};
use crate::draw::style::{
    MARKER, Stroke, adapted_stroke, demo_stroke, fmt_num, free_stroke, limit_stroke, margin_stroke,
};
use crate::error::PlotError;

const LEGEND_ROW: i32 = px(24) as i32;
/// Longest legend text, in characters (longer ones are shortened with an ellipsis).
const MAX_CHARS: usize = 36;

/// The symbol of a legend entry.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Mark {
    Line(Stroke),
    Patch(RGBAColor, Stroke),
    Dot,
    Cross,
}

/// A legend entry: a symbol, its text, and the class of its group.
#[derive(Debug, Clone)]
pub(crate) struct Entry {
    mark: Mark,
    text: String,
    class: &'static str,
}

impl Entry {
    pub(crate) fn new(mark: Mark, text: impl Into<String>) -> Self {
        let text: String = text.into();
        let text = if text.chars().count() > MAX_CHARS {
            format!("{}…", text.chars().take(MAX_CHARS - 1).collect::<String>())
        } else {
            text
        };
        Self { mark, text, class: "legend-entry" }
    }

    pub(crate) fn class(mut self, class: &'static str) -> Self {
        self.class = class;
        self
    }
}

/// What the method's run is called: a run with method `none` has no avoidance.
fn adapted_text(method: &str) -> String {
    match method {
        "none" => "run without avoidance (none)".into(),
        "" => "run with avoidance".into(),
        m => format!("with avoidance: {}", m.replace('_', " ")),
    }
}

/// Entries of the curves: the demonstration (with the text `demo`, if drawn), then the obstacle-free and the
/// adapted paths, a pair per robot when there are several.
pub(crate) fn path_entries(run: &Run<'_>, demo: Option<&str>, method: &str) -> Vec<Entry> {
    let mut entries = Vec::new();
    if let Some(text) = demo {
        entries.push(Entry::new(Mark::Line(demo_stroke()), text).class("legend-demonstration"));
    }
    if run.single() {
        let g = &run.groups[0];
        entries.push(Entry::new(Mark::Line(free_stroke(run, g)), "obstacle-free DMP").class("legend-free"));
        entries.push(
            Entry::new(Mark::Line(adapted_stroke(run, g)), adapted_text(method)).class("legend-adapted"),
        );
    } else {
        let short = if method == "none" { "no avoidance" } else { "with avoidance" };
        for g in &run.groups {
            entries.push(
                Entry::new(Mark::Line(adapted_stroke(run, g)), format!("{}, {short}", g.label))
                    .class("legend-adapted"),
            );
            entries.push(
                Entry::new(Mark::Line(free_stroke(run, g)), format!("{}, obstacle-free", g.label))
                    .class("legend-free"),
            );
        }
        if !method.is_empty() && method != "none" {
            entries.push(Entry::new(
                Mark::Line(Stroke::solid(MARKER, 0.0)),
                format!("method: {}", method.replace('_', " ")),
            ));
        }
    }
    entries
}

/// Entries of what the run was to keep: the limit lines with the profile they came from (if any limit applies),
/// and the safety margin around the true shapes (if `margins` are drawn), with its distance when it is one for all.
pub(crate) fn safety_entries(run: &Run<'_>, margins: bool) -> Vec<Entry> {
    let s = run.safety;
    let mut entries = Vec::new();
    if s.any_limit() {
        let profile = s.profile.trim();
        let text = if profile.is_empty() { "limits".to_string() } else { format!("limits: {profile}") };
        entries.push(Entry::new(Mark::Line(limit_stroke()), text).class("legend-limits"));
    }
    if margins {
        let distances: Vec<f64> =
            run.truths.iter().map(|t| s.margin_of(t.id())).filter(|m| *m > 0.0).collect();
        let one = distances.first().filter(|m| distances.iter().all(|d| d == *m));
        let text = one.map_or("safety margin".to_string(), |m| format!("safety margin {} m", fmt_num(*m)));
        entries.push(
            Entry::new(Mark::Patch(TRANSPARENT.to_rgba(), margin_stroke()), text).class("legend-margin"),
        );
    }
    entries
}

/// Height of the legend of `entries` and `notes`.
pub(crate) fn legend_height(entries: &[Entry], notes: &[String]) -> u32 {
    (px(24) as i32 + LEGEND_ROW * (entries.len() + notes.len()) as i32 + px(12) as i32) as u32
}

/// The legend in a frame: a row per entry, then a row per note.
pub(crate) fn draw_legend(
    doc: &SharedDoc,
    area: &Area,
    entries: &[Entry],
    notes: &[String],
) -> Result<(), PlotError> {
    let m = px(8);
    let area = area.margin(m, m, m, m);
    let (w, _) = area.dim_in_pixel();
    let h = LEGEND_ROW * (entries.len() + notes.len()) as i32 + px(16) as i32;
    area.draw(&Rectangle::new(
        [(0, 0), (w as i32 - 1, h)],
        ShapeStyle::from(RGBColor(200, 200, 200)).stroke_width(px(1)),
    ))
    .map_err(drawing_err)?;
    let p = |v: u32| px(v) as i32;
    for (k, e) in entries.iter().enumerate() {
        Doc::begin(doc, &[("class", e.class)]);
        let y = p(8) + LEGEND_ROW / 2 + LEGEND_ROW * k as i32;
        let (x0, x1) = (p(12), p(52));
        let line = vec![(x0, y), (x1, y)];
        let rect = [(x0 + p(4), y - p(7)), (x1 - p(4), y + p(7))];
        match e.mark {
            Mark::Line(s) if s.width == 0.0 => Ok(()),
            Mark::Line(s) => match s.dash {
                None => area.draw(&PathElement::new(line, s.style())),
                Some((on, off)) => area.draw(&DashedPathElement::new(line, px(on), px(off), s.style())),
            },
            Mark::Patch(fill, edge) => {
                area.draw(&Rectangle::new(rect, fill.filled())).and_then(|_| match edge.dash {
                    None => area.draw(&Rectangle::new(rect, edge.style())),
                    Some((on, off)) => area.draw(&DashedPathElement::new(
                        vec![rect[0], (rect[1].0, rect[0].1), rect[1], (rect[0].0, rect[1].1), rect[0]],
                        px(on),
                        px(off),
                        edge.style(),
                    )),
                })
            }
            Mark::Dot => area.draw(&Circle::new(((x0 + x1) / 2, y), px(4), MARKER.filled())),
            Mark::Cross => area.draw(&Cross::new(((x0 + x1) / 2, y), px(5), MARKER.stroke_width(px(2)))),
        }
        .map_err(drawing_err)?;
        put_text(&area, &e.text, (x1 + p(10), y), 16, HPos::Left);
        Doc::end(doc);
    }
    for (k, note) in notes.iter().enumerate() {
        let y = p(8) + LEGEND_ROW / 2 + LEGEND_ROW * (entries.len() + k) as i32;
        put_text(&area, note, (p(12), y), 15, HPos::Left);
    }
    Ok(())
}
