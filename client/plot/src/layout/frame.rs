//! The figure's frame: a title band on top, the panels in a row or a column, the time strip under them, the legend
//! on the right. Sizes are in device units ([`px`]).

use plotters::prelude::*;
use plotters::style::text_anchor::HPos;

use super::legend::{Entry, draw_legend, legend_height};
use crate::draw::backend::{Doc, FineSvg, SharedDoc, px};
use crate::draw::primitives::{Area, drawing_err, put_text};
use crate::error::PlotError;

/// Height of the title band.
const TITLE_H: u32 = px(40);
/// Width of the legend column.
const LEGEND_W: u32 = px(330);

/// What a figure is made of, besides its panels.
pub(crate) struct Frame<'a> {
    pub(crate) title: &'a str,
    /// Panel sizes.
    pub(crate) panels: &'a [(u32, u32)],
    /// Panels in a column (else in a row).
    pub(crate) vertical: bool,
    /// Legend entries and notes.
    pub(crate) legend: (&'a [Entry], &'a [String]),
    /// Height of the time strip under the panels (0: none).
    pub(crate) strip_h: u32,
}

/// Draws the figure: `draw_panel(k, area)` for each panel, then `draw_strip(area)` under them.
pub(crate) fn figure(
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
