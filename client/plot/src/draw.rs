//! Drawing primitives on a chart: curves broken at non-finite points, filled outlines, text, axes and grid.

use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::decimate::thinned;
use super::style::{FONT, Stroke};
use super::{P2, PlotError, finite};

pub(super) type Area<'b> = DrawingArea<SVGBackend<'b>, Shift>;
pub(super) type Chart<'c, 'b> = ChartContext<'c, SVGBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

pub(super) fn drawing_err(e: impl std::fmt::Display) -> PlotError {
    PlotError::Drawing(e.to_string())
}

/// Draws `pts` as polylines, broken where a point is not finite.
pub(super) fn draw_curve(chart: &mut Chart<'_, '_>, pts: &[P2], stroke: Stroke) -> Result<(), PlotError> {
    for seg in pts.split(|p| !finite(p)).filter(|s| s.len() >= 2) {
        let seg = thinned(chart, seg);
        match stroke.dash {
            None => chart.draw_series(LineSeries::new(seg, stroke.style())).map(|_| ()),
            Some((on, off)) => {
                chart.draw_series(DashedLineSeries::new(seg, on, off, stroke.style())).map(|_| ())
            }
        }
        .map_err(drawing_err)?;
    }
    Ok(())
}

/// A filled polygon with an outline (closed); non-finite vertices are dropped.
pub(super) fn draw_patch(
    chart: &mut Chart<'_, '_>,
    poly: &[P2],
    fill: RGBAColor,
    edge: Option<Stroke>,
) -> Result<(), PlotError> {
    let poly: Vec<P2> = poly.iter().copied().filter(finite).collect();
    if poly.len() < 3 {
        return Ok(());
    }
    chart.draw_series(std::iter::once(Polygon::new(poly.clone(), fill.filled()))).map_err(drawing_err)?;
    if let Some(edge) = edge {
        draw_curve(chart, &closed(poly), edge)?;
    }
    Ok(())
}

/// `poly` with its first vertex repeated at the end.
pub(super) fn closed(mut poly: Vec<P2>) -> Vec<P2> {
    if let Some(&first) = poly.first() {
        poly.push(first);
    }
    poly
}

/// Text that may fail to draw is dropped: a figure without a label beats no figure.
pub(super) fn put_text(area: &Area<'_>, text: &str, pos: (i32, i32), size: u32, h: HPos) {
    let style = TextStyle::from((FONT, size).into_font()).color(&BLACK).pos(Pos::new(h, VPos::Center));
    let _ = area.draw(&Text::new(text.to_string(), pos, style));
}

/// Axes, grid, tick labels and axis names; without the text if the text cannot be drawn.
pub(super) fn draw_mesh(
    chart: &mut Chart<'_, '_>,
    x_desc: &str,
    y_desc: &str,
    x_labels: usize,
    y_labels: usize,
) -> Result<(), PlotError> {
    let labelled = chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .x_labels(x_labels)
        .y_labels(y_labels)
        .max_light_lines(4)
        .label_style((FONT, 15))
        .axis_desc_style((FONT, 18))
        .light_line_style(RGBColor(242, 242, 242))
        .bold_line_style(RGBColor(218, 218, 218))
        .axis_style(RGBColor(60, 60, 60))
        .draw();
    if labelled.is_ok() {
        return Ok(());
    }
    chart
        .configure_mesh()
        .x_labels(0)
        .y_labels(0)
        .light_line_style(RGBColor(242, 242, 242))
        .axis_style(RGBColor(60, 60, 60))
        .draw()
        .map_err(drawing_err)
}
