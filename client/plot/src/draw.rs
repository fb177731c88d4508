//! Drawing primitives on a chart: curves broken at non-finite points, filled outlines clipped to the chart, text,
//! axes and grid.

use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::backend::{FineSvg, dashed, px};
use super::decimate::thinned;
use super::style::{FONT, Stroke, fmt_tick};
use super::{P2, PlotError, finite};

pub(super) type Area = DrawingArea<FineSvg, Shift>;
pub(super) type Chart<'c> = ChartContext<'c, FineSvg, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

pub(super) fn drawing_err(e: impl std::fmt::Display) -> PlotError {
    PlotError::Drawing(e.to_string())
}

/// The chart's data ranges.
fn ranges(chart: &Chart<'_>) -> ((f64, f64), (f64, f64)) {
    let (x, y) = (chart.x_range(), chart.y_range());
    ((x.start, x.end), (y.start, y.end))
}

/// Draws `pts` as polylines, broken where a point is not finite.
pub(super) fn draw_curve(chart: &mut Chart<'_>, pts: &[P2], stroke: Stroke) -> Result<(), PlotError> {
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

/// A filled polygon with an outline (closed), clipped to the chart; non-finite vertices are dropped.
pub(super) fn draw_patch(
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
pub(super) fn draw_outline(chart: &mut Chart<'_>, poly: &[P2], edge: Stroke) -> Result<(), PlotError> {
    let poly: Vec<P2> = poly.iter().copied().filter(finite).collect();
    let poly = clip_polygon(&poly, ranges(chart));
    if poly.len() < 3 {
        return Ok(());
    }
    draw_curve(chart, &closed(poly), edge)
}

/// `poly` with its first vertex repeated at the end.
pub(super) fn closed(mut poly: Vec<P2>) -> Vec<P2> {
    if let Some(&first) = poly.first() {
        poly.push(first);
    }
    poly
}

/// The part of the polygon `poly` inside the rectangle `((x0, x1), (y0, y1))` (Sutherland-Hodgman).
pub(super) fn clip_polygon(poly: &[P2], ((x0, x1), (y0, y1)): ((f64, f64), (f64, f64))) -> Vec<P2> {
    let (x0, x1) = (x0.min(x1), x0.max(x1));
    let (y0, y1) = (y0.min(y1), y0.max(y1));
    let mut out: Vec<P2> = poly.to_vec();
    let edges: [(usize, f64, bool); 4] = [(0, x0, true), (0, x1, false), (1, y0, true), (1, y1, false)];
    for (axis, bound, keep_above) in edges {
        let inside = |p: &P2| {
            let v = if axis == 0 { p.0 } else { p.1 };
            if keep_above { v >= bound } else { v <= bound }
        };
        let cross = |a: &P2, b: &P2| {
            let (va, vb) = if axis == 0 { (a.0, b.0) } else { (a.1, b.1) };
            let s = (bound - va) / (vb - va);
            (a.0 + s * (b.0 - a.0), a.1 + s * (b.1 - a.1))
        };
        let input = std::mem::take(&mut out);
        for (k, b) in input.iter().enumerate() {
            let a = &input[(k + input.len() - 1) % input.len()];
            match (inside(a), inside(b)) {
                (true, true) => out.push(*b),
                (true, false) => out.push(cross(a, b)),
                (false, true) => {
                    out.push(cross(a, b));
                    out.push(*b);
                }
                (false, false) => {}
            }
        }
    }
    out
}

/// Text that may fail to draw is dropped: a figure without a label beats no figure. `size` and `pos` in pixels
/// and device units respectively.
pub(super) fn put_text(area: &Area, text: &str, pos: (i32, i32), size: u32, h: HPos) {
    let style = TextStyle::from((FONT, px(size)).into_font()).color(&BLACK).pos(Pos::new(h, VPos::Center));
    let _ = area.draw(&Text::new(text.to_string(), pos, style));
}

/// Axes, grid, tick labels (no `-0`) and axis names with their units; without the text if the text cannot be
/// drawn.
pub(super) fn draw_mesh(
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
