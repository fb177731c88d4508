//! How things look: font, colours, strokes, and the legend that explains them.

use plotters::prelude::*;

use super::backend::SCALE;

pub(super) const FONT: &str = "sans-serif";

const DEMO: RGBColor = RGBColor(110, 110, 110);
pub(super) const FREE: RGBColor = RGBColor(31, 119, 180);
pub(super) const ADAPTED: RGBColor = RGBColor(214, 39, 40);
const OBSTACLE_FILL: RGBColor = RGBColor(150, 150, 150);
pub(super) const OBSTACLE_EDGE: RGBColor = RGBColor(50, 50, 50);
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

/// Contact marks.
pub(super) const CONTACT: RGBColor = RGBColor(230, 0, 120);
/// Event lines.
pub(super) const EVENT: RGBColor = RGBColor(120, 60, 160);
/// Isopotentials (the inflated superquadrics the robot avoids).
pub(super) const ISOPOTENTIAL: RGBColor = RGBColor(90, 90, 90);

/// A line style: colour, width in pixels, and `(on, off)` dash lengths in pixels if dashed.
#[derive(Debug, Clone, Copy)]
pub(super) struct Stroke {
    pub(super) color: RGBAColor,
    pub(super) width: f64,
    pub(super) dash: Option<(u32, u32)>,
}

impl Stroke {
    pub(super) fn solid(color: RGBColor, width: f64) -> Self {
        Self { color: color.to_rgba(), width, dash: None }
    }

    pub(super) fn dashed(color: RGBColor, width: f64, dash: (u32, u32)) -> Self {
        Self { color: color.to_rgba(), width, dash: Some(dash) }
    }

    /// The plotters style, in device units.
    pub(super) fn style(&self) -> ShapeStyle {
        ShapeStyle {
            color: self.color,
            filled: false,
            stroke_width: (self.width * f64::from(SCALE)).round().max(1.0) as u32,
        }
    }
}

pub(super) fn demo_stroke() -> Stroke {
    Stroke::dashed(DEMO, 1.5, (4, 4))
}

/// Fill of an obstacle's true shape in robot space.
pub(super) fn obstacle_fill() -> RGBAColor {
    OBSTACLE_FILL.mix(0.6)
}

/// Outline of an isopotential: lighter than the true shape, dashed.
pub(super) fn isopotential_stroke() -> Stroke {
    Stroke { color: ISOPOTENTIAL.mix(0.7), width: 1.0, dash: Some((5, 3)) }
}

/// Fill of an isopotential: a faint wash.
pub(super) fn isopotential_fill() -> RGBAColor {
    OBSTACLE_FILL.mix(0.15)
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

/// A tick label: up to 6 decimals (ticks are round numbers; this drops the floating-point noise), no trailing
/// zeros, no `-0`.
pub(super) fn fmt_tick(v: f64) -> String {
    let s = format!("{v:.6}");
    let s = if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s };
    if s == "-0" { "0".into() } else { s }
}
