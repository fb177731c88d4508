//! The figure's layout: a title band on top, the panels in a row or a column, the time strip under them, the legend
//! on the right. Sizes are in device units ([`px`]).

use plotters::prelude::*;
use plotters::style::text_anchor::HPos;

use super::PlotError;
use super::backend::{Doc, FineSvg, SharedDoc, px};
use super::draw::{Area, Chart, drawing_err, put_text};
use super::legend::{Entry, draw_legend, legend_height};
use super::style::FONT;

pub(super) const TITLE_H: u32 = px(40);
pub(super) const LEGEND_W: u32 = px(330);
pub(super) const PANEL_MARGIN: u32 = px(12);
pub(super) const X_LABEL_AREA: u32 = px(44);
pub(super) const Y_LABEL_AREA: u32 = px(72);
pub(super) const CAPTION_H: u32 = px(28);

/// What a figure is made of, besides its panels.
pub(super) struct Frame<'a> {
    pub(super) title: &'a str,
    /// Panel sizes.
    pub(super) panels: &'a [(u32, u32)],
    /// Panels in a column (else in a row).
    pub(super) vertical: bool,
    /// Legend entries and notes.
    pub(super) legend: (&'a [Entry], &'a [String]),
    /// Height of the time strip under the panels (0: none).
    pub(super) strip_h: u32,
}

/// Draws the figure: `draw_panel(k, area)` for each panel, then `draw_strip(area)` under them.
pub(super) fn figure(
    frame: &Frame<'_>,
    mut draw_panel: impl FnMut(&SharedDoc, usize, &Area) -> Result<(), PlotError>,
    draw_strip: impl FnOnce(&SharedDoc, &Area) -> Result<(), PlotError>,
) -> Result<String, PlotError> {
    let panels = frame.panels;
    let (pw, ph) = if frame.vertical {
        (panels.iter().map(|p| p.0).max().unwrap_or(0), panels.iter().map(|p| p.1).sum::<u32>())
    } else {
        (panels.iter().map(|p| p.0).sum::<u32>(), panels.iter().map(|p| p.1).max().unwrap_or(0))
    };
    let body_h = ph + frame.strip_h;
    let size = (pw + LEGEND_W, TITLE_H + body_h.max(legend_height(frame.legend.0, frame.legend.1)));
    let doc = Doc::shared();
    {
        let root = FineSvg::new(doc.clone(), size).into_drawing_area();
        root.fill(&WHITE).map_err(drawing_err)?;
        let (top, rest) = root.split_vertically(TITLE_H);
        let (tw, _) = top.dim_in_pixel();
        Doc::group(&doc, "title", || {
            put_text(&top, frame.title, (tw as i32 / 2, TITLE_H as i32 / 2 + px(2) as i32), 24, HPos::Center)
        });
        let (body, legend_area) = rest.split_horizontally(pw);
        let (panel_area, strip_area) = body.split_vertically(ph);
        let mut offset = 0;
        for (k, &(w, h)) in panels.iter().enumerate() {
            let area = if frame.vertical {
                panel_area.clone().shrink((0, offset), (w, h))
            } else {
                panel_area.clone().shrink((offset, 0), (w, h))
            };
            offset += if frame.vertical { h } else { w };
            Doc::begin(&doc, &[("class", "panel"), ("id", &format!("panel-{k}"))]);
            draw_panel(&doc, k, &area)?;
            Doc::end(&doc);
        }
        if frame.strip_h > 0 {
            let strip = strip_area.shrink((0, 0), (pw, frame.strip_h));
            Doc::begin(&doc, &[("class", "time-strip"), ("id", "time-strip")]);
            draw_strip(&doc, &strip)?;
            Doc::end(&doc);
        }
        Doc::group(&doc, "legend", || draw_legend(&doc, &legend_area, frame.legend.0, frame.legend.1))?;
        root.present().map_err(drawing_err)?;
    }
    Ok(Doc::finish(&doc, size))
}

/// `area` below a caption (the caption is dropped if its text cannot be drawn).
pub(super) fn captioned(area: &Area, caption: Option<&str>) -> Area {
    match caption {
        None => area.clone(),
        Some(c) => area.titled(c, (FONT, px(19))).unwrap_or_else(|_| area.split_vertically(CAPTION_H).1),
    }
}

/// Chart on `area`, built twice: once to measure the plotting area, once with the ranges `fit` gives for its
/// size in device units.
pub(super) fn chart_on<'c>(
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
