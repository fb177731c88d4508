//! A panel's chart: its caption, margins and label areas, and data ranges fitted to the plotting area's size.
//! Sizes are in device units ([`px`]).

use plotters::prelude::*;

use crate::draw::backend::px;
use crate::draw::primitives::{Area, Chart, drawing_err};
use crate::draw::style::FONT;
use crate::error::PlotError;

/// Margin around a panel's chart.
pub(crate) const PANEL_MARGIN: u32 = px(12);
/// Height of the area under a chart for the x tick labels and the axis name.
pub(crate) const X_LABEL_AREA: u32 = px(44);
/// Width of the area left of a chart for the y tick labels and the axis name.
pub(crate) const Y_LABEL_AREA: u32 = px(72);
/// Height of a panel's caption.
pub(crate) const CAPTION_H: u32 = px(28);

/// `area` below a caption (the caption is dropped if its text cannot be drawn).
pub(crate) fn captioned(area: &Area, caption: Option<&str>) -> Area {
    match caption {
        None => area.clone(),
        Some(c) => area.titled(c, (FONT, px(19))).unwrap_or_else(|_| area.split_vertically(CAPTION_H).1),
    }
}

/// Chart on `area`, built twice: once to measure the plotting area, once with the ranges `fit` gives for its
/// size in device units.
pub(crate) fn chart_on<'c>(
    area: &'c Area,
    x_label_area: u32,
    fit: impl FnOnce(f64, f64) -> ((f64, f64), (f64, f64)),
) -> Result<Chart<'c>, PlotError> {
    let mut builder = ChartBuilder::on(area);
    builder.margin(PANEL_MARGIN).x_label_area_size(x_label_area).y_label_area_size(Y_LABEL_AREA);
    // Building draws nothing (no caption here), so the builder can be used twice.
    let (pw, ph) =
        builder.build_cartesian_2d(0.0..1.0, 0.0..1.0).map_err(drawing_err)?.plotting_area().dim_in_pixel();
    let (x, y) = fit(pw.saturating_sub(1) as f64, ph.saturating_sub(1) as f64);
    builder.build_cartesian_2d(x.0..x.1, y.0..y.1).map_err(drawing_err)
}
