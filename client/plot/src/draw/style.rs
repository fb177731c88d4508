//! How things look: font, colours, strokes, and the look of each robot's runs; number formats for labels.

use plotters::prelude::*;

use super::backend::SCALE;
use crate::data::group::Group;
use crate::data::run::Run;

pub(crate) const FONT: &str = "sans-serif";

const DEMO: RGBColor = RGBColor(110, 110, 110);
const FREE: RGBColor = RGBColor(31, 119, 180);
const ADAPTED: RGBColor = RGBColor(214, 39, 40);
const OBSTACLE_FILL: RGBColor = RGBColor(150, 150, 150);
pub(crate) const OBSTACLE_EDGE: RGBColor = RGBColor(50, 50, 50);
pub(crate) const MARKER: RGBColor = RGBColor(0, 0, 0);
/// Robot colours (matplotlib's tab10 without its grey, which the demonstration uses).
const PALETTE: [RGBColor; 9] = [
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

/// Contact marks.
pub(crate) const CONTACT: RGBColor = RGBColor(230, 0, 120);
/// Event lines.
pub(crate) const EVENT: RGBColor = RGBColor(120, 60, 160);
/// Isopotentials (the inflated superquadrics the robot avoids).
pub(crate) const ISOPOTENTIAL: RGBColor = RGBColor(90, 90, 90);
/// Limit lines.
pub(crate) const LIMIT: RGBColor = RGBColor(205, 115, 0);
/// Safety margins around the true shapes.
const MARGIN: RGBColor = RGBColor(170, 40, 110);

/// A line style: colour, width in pixels, and `(on, off)` dash lengths in pixels if dashed.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Stroke {
    pub(crate) color: RGBAColor,
    pub(crate) width: f64,
    pub(crate) dash: Option<(u32, u32)>,
}

impl Stroke {
    pub(crate) fn solid(color: RGBColor, width: f64) -> Self {
        Self { color: color.to_rgba(), width, dash: None }
    }

    pub(crate) fn dashed(color: RGBColor, width: f64, dash: (u32, u32)) -> Self {
        Self { color: color.to_rgba(), width, dash: Some(dash) }
    }

    /// The plotters style, in device units.
    pub(crate) fn style(&self) -> ShapeStyle {
        ShapeStyle {
            color: self.color,
            filled: false,
            stroke_width: (self.width * f64::from(SCALE)).round().max(1.0) as u32,
        }
    }
}

/// The demonstration's line.
pub(crate) fn demo_stroke() -> Stroke {
    Stroke::dashed(DEMO, 1.5, (4, 4))
}

/// The colour of robot `g`: the adapted run's colour for the one robot owning every dimension, else the palette's
/// colour for its index.
pub(crate) fn robot_color(g: &Group<'_>) -> RGBColor {
    g.index.map_or(ADAPTED, |i| PALETTE[i % PALETTE.len()])
}

/// The line of robot `g`'s obstacle-free run.
pub(crate) fn free_stroke(run: &Run<'_>, g: &Group<'_>) -> Stroke {
    if run.single() {
        Stroke::dashed(FREE, 1.8, (9, 5))
    } else {
        Stroke { color: robot_color(g).mix(0.7), width: 1.5, dash: Some((8, 5)) }
    }
}

/// The line of robot `g`'s adapted run.
pub(crate) fn adapted_stroke(run: &Run<'_>, g: &Group<'_>) -> Stroke {
    Stroke::solid(if run.single() { ADAPTED } else { robot_color(g) }, 2.0)
}

/// The mark of a contact: a wide translucent line along the path.
pub(crate) fn contact_stroke() -> Stroke {
    Stroke { color: CONTACT.mix(0.55), width: 7.0, dash: None }
}

/// Fill of an obstacle's true shape in robot space.
pub(crate) fn obstacle_fill() -> RGBAColor {
    OBSTACLE_FILL.mix(0.6)
}

/// Outline of an isopotential: lighter than the true shape, dashed.
pub(crate) fn isopotential_stroke() -> Stroke {
    Stroke { color: ISOPOTENTIAL.mix(0.7), width: 1.0, dash: Some((5, 3)) }
}

/// A limit line: dashed, in its own colour.
pub(crate) fn limit_stroke() -> Stroke {
    Stroke::dashed(LIMIT, 1.5, (8, 4))
}

/// The outline of a true shape grown by its safety margin: dashed, not filled.
pub(crate) fn margin_stroke() -> Stroke {
    Stroke::dashed(MARGIN, 1.2, (3, 3))
}

/// Fill of an isopotential: a faint wash.
pub(crate) fn isopotential_fill() -> RGBAColor {
    OBSTACLE_FILL.mix(0.15)
}

/// Fill of an obstacle's extent in a plot against time.
pub(crate) fn band_fill() -> RGBAColor {
    OBSTACLE_FILL.mix(0.3)
}

/// A number for a label: at most 3 decimals, no trailing zeros, no `-0`.
pub(crate) fn fmt_num(v: f64) -> String {
    let s = format!("{v:.3}");
    let s = if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s };
    if s == "-0" { "0".into() } else { s }
}

/// A tick label: up to 6 decimals (ticks are round numbers; this drops the floating-point noise), no trailing
/// zeros, no `-0`.
pub(crate) fn fmt_tick(v: f64) -> String {
    let s = format!("{v:.6}");
    let s = if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s };
    if s == "-0" { "0".into() } else { s }
}
