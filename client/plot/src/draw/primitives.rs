//! Drawing primitives on a chart: curves broken at non-finite points and thinned to what shows on screen, filled
//! outlines clipped to the chart, text, axes and grid.

use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::backend::{FineSvg, SCALE, dashed, px};
use super::style::{FONT, Stroke, fmt_tick};
use crate::data::geometry::{P2, clip_polygon, finite};
use crate::error::PlotError;

/// Smallest distance on screen, in device units (a pixel and a half), between consecutive drawn points of a curve.
const MIN_PIXEL_STEP: i64 = 3 * SCALE as i64 / 2;

/// A drawing area of the figure (device units).
pub(crate) type Area = DrawingArea<FineSvg, Shift>;
/// A chart with data coordinates on both axes.
pub(crate) type Chart<'c> = ChartContext<'c, FineSvg, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// A drawing error of plotters, as the figure's error.
pub(crate) fn drawing_err(e: impl std::fmt::Display) -> PlotError {
    PlotError::Drawing(e.to_string())
}

/// The chart's data ranges.
fn ranges(chart: &Chart<'_>) -> ((f64, f64), (f64, f64)) {
    let (x, y) = (chart.x_range(), chart.y_range());
    ((x.start, x.end), (y.start, y.end))
}

/// Draws `pts` as polylines, broken where a point is not finite.
pub(crate) fn draw_curve(chart: &mut Chart<'_>, pts: &[P2], stroke: Stroke) -> Result<(), PlotError> {
    for seg in pts.split(|p| !finite(p)).filter(|s| s.len() >= 2) {
        let seg = thinned(chart, seg);
        let mut draw = || chart.draw_series(LineSeries::new(seg.iter().copied(), stroke.style())).map(|_| ());
        match stroke.dash {
            None => draw(),
            Some((on, off)) => dashed((px(on), px(off)), draw),
        }
        .map_err(drawing_err)?;
    }
    Ok(())
}

/// The points of `seg` at least [`MIN_PIXEL_STEP`] apart on screen (and the last one): denser points only make the
/// file bigger.
fn thinned(chart: &Chart<'_>, seg: &[P2]) -> Vec<P2> {
    let mut out = Vec::with_capacity(seg.len());
    let mut last: Option<(i32, i32)> = None;
    for (k, p) in seg.iter().enumerate() {
        let q = chart.backend_coord(p);
        let far = last.is_none_or(|l| {
            let (dx, dy) = ((q.0 - l.0) as i64, (q.1 - l.1) as i64);
            dx * dx + dy * dy >= MIN_PIXEL_STEP * MIN_PIXEL_STEP
        });
        if far || k + 1 == seg.len() {
            out.push(*p);
            last = Some(q);
        }
    }
    out
}

/// A filled polygon with an outline (closed), clipped to the chart; non-finite vertices are dropped.
pub(crate) fn draw_patch(
    chart: &mut Chart<'_>,
    poly: &[P2],
    fill: RGBAColor,
    edge: Option<Stroke>,
) -> Result<(), PlotError> {
    let poly: Vec<P2> = poly.iter().copied().filter(finite).collect();
    let poly = clip_polygon(&poly, ranges(chart));
    let poly = thinned(chart, &poly);
    if poly.len() < 3 {
        return Ok(());
    }
    chart.draw_series(std::iter::once(Polygon::new(poly.clone(), fill.filled()))).map_err(drawing_err)?;
    if let Some(edge) = edge {
        draw_curve(chart, &closed(poly), edge)?;
    }
    Ok(())
}

/// An outline (closed, not filled), clipped to the chart.
pub(crate) fn draw_outline(chart: &mut Chart<'_>, poly: &[P2], edge: Stroke) -> Result<(), PlotError> {
    let poly: Vec<P2> = poly.iter().copied().filter(finite).collect();
    let poly = clip_polygon(&poly, ranges(chart));
    if poly.len() < 3 {
        return Ok(());
    }
    draw_curve(chart, &closed(poly), edge)
}

/// `poly` with its first vertex repeated at the end.
fn closed(mut poly: Vec<P2>) -> Vec<P2> {
    if let Some(&first) = poly.first() {
        poly.push(first);
    }
    poly
}

/// Text that may fail to draw is dropped: a figure without a label beats no figure. `size` and `pos` in pixels
/// and device units respectively.
pub(crate) fn put_text(area: &Area, text: &str, pos: (i32, i32), size: u32, h: HPos) {
    let style = TextStyle::from((FONT, px(size)).into_font()).color(&BLACK).pos(Pos::new(h, VPos::Center));
    let _ = area.draw(&Text::new(text.to_string(), pos, style));
}

/// Axes, grid, tick labels (no `-0`) and axis names with their units; without the text if the text cannot be
/// drawn.
pub(crate) fn draw_mesh(
    chart: &mut Chart<'_>,
    x_desc: &str,
    y_desc: &str,
    x_labels: usize,
    y_labels: usize,
) -> Result<(), PlotError> {
    let fmt = |v: &f64| fmt_tick(*v);
    let labelled = chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .x_labels(x_labels)
        .y_labels(y_labels)
        .x_label_formatter(&fmt)
        .y_label_formatter(&fmt)
        .max_light_lines(4)
        .label_style((FONT, px(15)))
        .axis_desc_style((FONT, px(17)))
        .set_all_tick_mark_size(px(4))
        .light_line_style(ShapeStyle::from(RGBColor(242, 242, 242)).stroke_width(px(1)))
        .bold_line_style(ShapeStyle::from(RGBColor(218, 218, 218)).stroke_width(px(1)))
        .axis_style(ShapeStyle::from(RGBColor(60, 60, 60)).stroke_width(px(1)))
        .draw();
    if labelled.is_ok() {
        return Ok(());
    }
    chart
        .configure_mesh()
        .x_labels(0)
        .y_labels(0)
        .light_line_style(ShapeStyle::from(RGBColor(242, 242, 242)).stroke_width(px(1)))
        .axis_style(ShapeStyle::from(RGBColor(60, 60, 60)).stroke_width(px(1)))
        .draw()
        .map_err(drawing_err)
}
