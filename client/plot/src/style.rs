//! How things look: font, colours, strokes, and the legend that explains them.

use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::HPos;

use super::PlotError;
use super::draw::{Area, drawing_err, put_text};
use super::run::Run;

pub(super) const FONT: &str = "sans-serif";
const LEGEND_ROW: i32 = 24;

const DEMO: RGBColor = RGBColor(110, 110, 110);
pub(super) const FREE: RGBColor = RGBColor(31, 119, 180);
pub(super) const ADAPTED: RGBColor = RGBColor(214, 39, 40);
const OBSTACLE_FILL: RGBColor = RGBColor(150, 150, 150);
pub(super) const OBSTACLE_EDGE: RGBColor = RGBColor(50, 50, 50);
pub(super) const GHOST: RGBColor = RGBColor(120, 120, 120);
pub(super) const MARKER: RGBColor = RGBColor(0, 0, 0);
/// Robot colours (matplotlib's tab10 without its grey, which the demonstration uses).
pub(super) const PALETTE: [RGBColor; 9] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// A line style: colour, width in pixels, and `(on, off)` dash lengths if dashed.
#[derive(Debug, Clone, Copy)]
pub(super) struct Stroke {
    pub(super) color: RGBAColor,
    pub(super) width: u32,
    pub(super) dash: Option<(u32, u32)>,
}

impl Stroke {
    pub(super) fn solid(color: RGBColor, width: u32) -> Self {
        Self { color: color.to_rgba(), width, dash: None }
    }

    pub(super) fn dashed(color: RGBColor, width: u32, dash: (u32, u32)) -> Self {
        Self { color: color.to_rgba(), width, dash: Some(dash) }
    }

    pub(super) fn style(&self) -> ShapeStyle {
        ShapeStyle { color: self.color, filled: false, stroke_width: self.width }
    }
}

pub(super) fn demo_stroke() -> Stroke {
    Stroke::dashed(DEMO, 2, (4, 4))
}

/// Outline of a moving obstacle at the start and at the end of the run.
pub(super) fn ghost_stroke() -> Stroke {
    Stroke { color: GHOST.mix(0.8), width: 1, dash: Some((4, 4)) }
}

/// Fill of an obstacle in robot space.
pub(super) fn obstacle_fill() -> RGBAColor {
    OBSTACLE_FILL.mix(0.45)
}

/// Fill of an obstacle's extent in a plot against time.
pub(super) fn band_fill() -> RGBAColor {
    OBSTACLE_FILL.mix(0.3)
}

/// A number for a label: at most 3 decimals, no trailing zeros, no `-0`.
pub(super) fn fmt_num(v: f64) -> String {
    let s = format!("{v:.3}");
    let s = if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s };
    if s == "-0" { "0".into() } else { s }
}

// ------------------------------------------------------------------------------------------------------------------
// Legend.

/// The symbol of a legend entry.
#[derive(Debug, Clone, Copy)]
pub(super) enum Mark {
    Line(Stroke),
    Patch(RGBAColor, Stroke),
    Dot,
    Cross,
}

/// A legend entry: a symbol and its text (shortened to 30 characters).
#[derive(Debug, Clone)]
pub(super) struct Entry {
    mark: Mark,
    text: String,
}

impl Entry {
    pub(super) fn new(mark: Mark, text: impl Into<String>) -> Self {
        let text: String = text.into();
        let text = if text.chars().count() > 30 {
            format!("{}…", text.chars().take(29).collect::<String>())
        } else {
            text
        };
        Self { mark, text }
    }
}

/// Entries of the curves: the demonstration (with the text `demo`, if drawn), then the obstacle-free and the
/// adapted paths, a pair per robot when there are several.
pub(super) fn path_entries(run: &Run<'_>, demo: Option<&str>) -> Vec<Entry> {
    let mut entries = Vec::new();
    if let Some(text) = demo {
        entries.push(Entry::new(Mark::Line(demo_stroke()), text));
    }
    if run.single() {
        entries.push(Entry::new(Mark::Line(run.free_stroke(&run.groups[0])), "DMP without obstacles"));
        entries.push(Entry::new(Mark::Line(run.adapted_stroke(&run.groups[0])), "DMP with avoidance"));
    } else {
        for g in &run.groups {
            entries.push(Entry::new(Mark::Line(run.adapted_stroke(g)), g.label.clone()));
            entries.push(Entry::new(Mark::Line(run.free_stroke(g)), format!("{}, no obstacles", g.label)));
        }
    }
    entries
}

pub(super) fn legend_height(entries: &[Entry], notes: &[String]) -> u32 {
    (24 + LEGEND_ROW * (entries.len() + notes.len()) as i32 + 12) as u32
}

/// The legend in a frame: a row per entry, then a row per note.
pub(super) fn draw_legend(area: &Area<'_>, entries: &[Entry], notes: &[String]) -> Result<(), PlotError> {
    let area = area.margin(8, 8, 8, 8);
    let (w, _) = area.dim_in_pixel();
    let h = LEGEND_ROW * (entries.len() + notes.len()) as i32 + 16;
    area.draw(&Rectangle::new(
        [(0, 0), (w as i32 - 1, h)],
        ShapeStyle::from(RGBColor(200, 200, 200)).stroke_width(1),
    ))
    .map_err(drawing_err)?;
    for (k, e) in entries.iter().enumerate() {
        let y = 8 + LEGEND_ROW / 2 + LEGEND_ROW * k as i32;
        let (x0, x1) = (12, 52);
        match e.mark {
            Mark::Line(s) => match s.dash {
                None => area.draw(&PathElement::new(vec![(x0, y), (x1, y)], s.style())),
                Some((on, off)) => {
                    area.draw(&DashedPathElement::new(vec![(x0, y), (x1, y)], on, off, s.style()))
                }
            },
            Mark::Patch(fill, edge) => area
                .draw(&Rectangle::new([(x0 + 4, y - 7), (x1 - 4, y + 7)], fill.filled()))
                .and_then(|_| match edge.dash {
                    None => area.draw(&Rectangle::new([(x0 + 4, y - 7), (x1 - 4, y + 7)], edge.style())),
                    Some((on, off)) => area.draw(&DashedPathElement::new(
                        vec![
                            (x0 + 4, y - 7),
                            (x1 - 4, y - 7),
                            (x1 - 4, y + 7),
                            (x0 + 4, y + 7),
                            (x0 + 4, y - 7),
                        ],
                        on,
                        off,
                        edge.style(),
                    )),
                }),
            Mark::Dot => area.draw(&Circle::new(((x0 + x1) / 2, y), 4, MARKER.filled())),
            Mark::Cross => area.draw(&Cross::new(((x0 + x1) / 2, y), 5, MARKER.stroke_width(2))),
        }
        .map_err(drawing_err)?;
        put_text(&area, &e.text, (x1 + 10, y), 16, HPos::Left);
    }
    for (k, note) in notes.iter().enumerate() {
        let y = 8 + LEGEND_ROW / 2 + LEGEND_ROW * (entries.len() + k) as i32;
        put_text(&area, note, (12, y), 15, HPos::Left);
    }
    Ok(())
}
