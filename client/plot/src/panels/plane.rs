//! A robot-space panel: one plane of a robot moving in 2-D or 3-D (a [`Plane`]), with the obstacles' true shapes,
//! their safety margins and isopotentials, the paths with their contacts, and, where things move, outlines at the marked times with the
//! paths ticked at the same times; with an equal aspect ratio.

use plotters::prelude::*;

use crate::data::bounds::fit_equal_aspect;
use crate::data::geometry::{P2, finite};
use crate::data::plane::Plane;
use crate::data::run::Run;
use crate::draw::backend::{Doc, SharedDoc, px};
use crate::draw::primitives::{Area, Chart, draw_curve, draw_mesh, draw_outline, draw_patch, drawing_err};
use crate::draw::style::{
    CONTACT, FONT, MARKER, OBSTACLE_EDGE, Stroke, adapted_stroke, contact_stroke, demo_stroke, fmt_num,
    free_stroke, isopotential_fill, isopotential_stroke, margin_stroke, obstacle_fill, robot_color,
};
use crate::error::PlotError;
use crate::layout::chart::{CAPTION_H, PANEL_MARGIN, X_LABEL_AREA, Y_LABEL_AREA, captioned, chart_on};

/// Panel size: a plotting area shaped like the data (within limits; the ranges are then fitted exactly), plus the
/// margins, label areas and caption.
pub(crate) fn size(pl: &Plane, sub: usize) -> (u32, u32) {
    let ((x0, x1), (y0, y1)) = pl.ranges;
    let (w, h) = if sub == 2 {
        let a = ((x1 - x0) / (y1 - y0)).clamp(0.6, 2.0);
        if a >= 1.0 { (620.0, 620.0 / a) } else { (620.0 * a, 620.0) }
    } else {
        let a = ((x1 - x0) / (y1 - y0)).clamp(0.7, 1.6);
        (380.0 * a, 380.0)
    };
    let caption = if sub == 2 { 0 } else { CAPTION_H };
    (
        px(w.round() as u32) + 2 * PANEL_MARGIN + Y_LABEL_AREA,
        px(h.round() as u32) + 2 * PANEL_MARGIN + X_LABEL_AREA + caption,
    )
}

/// Draws the panel of the plane `pl` on `area`: its caption (in 3-D), axes with an equal aspect ratio, and its
/// content.
pub(crate) fn draw(
    doc: &SharedDoc,
    area: &Area,
    pl: &Plane,
    run: &Run<'_>,
    sub: usize,
) -> Result<(), PlotError> {
    let names = (format!("x{}", pl.axes.0 + 1), format!("x{}", pl.axes.1 + 1));
    let caption = (sub == 3).then(|| format!("{} - {}", names.0, names.1));
    let area = captioned(area, caption.as_deref());
    let mut chart =
        chart_on(&area, X_LABEL_AREA, |pw, ph| fit_equal_aspect(pl.ranges.0, pl.ranges.1, pw, ph))?;
    draw_mesh(&mut chart, &format!("{} (m)", names.0), &format!("{} (m)", names.1), 8, 8)?;
    draw_plane(doc, &mut chart, pl, run)
}

/// Labels of one obstacle's outlines closer than this on screen (device units) are left out.
const LABEL_GAP: i32 = px(40) as i32;

/// The time of an outline, above its highest point inside the panel, unless that is within [`LABEL_GAP`] of the
/// `last` label; returns where the last label now is.
fn time_label(
    chart: &mut Chart<'_>,
    poly: &[P2],
    t: f64,
    ((x0, x1), (y0, y1)): ((f64, f64), (f64, f64)),
    last: Option<(i32, i32)>,
) -> Result<Option<(i32, i32)>, PlotError> {
    let inside = poly.iter().filter(|p| finite(p) && p.0 >= x0 && p.0 <= x1 && p.1 >= y0 && p.1 <= y1);
    let Some(top) = inside.max_by(|a, b| a.1.total_cmp(&b.1)) else { return Ok(last) };
    let at = chart.backend_coord(top);
    if last.is_some_and(|l| (l.0 - at.0).abs().max((l.1 - at.1).abs()) < LABEL_GAP) {
        return Ok(last);
    }
    let style = (FONT, px(12)).into_font().color(&OBSTACLE_EDGE);
    let label = Text::new(format!("{} s", fmt_num(t)), (-(px(10) as i32), -(px(14) as i32)), style);
    chart.draw_series(std::iter::once(EmptyElement::at(*top) + label)).map_err(drawing_err)?;
    Ok(Some(at))
}

/// Fading with the marked time: later outlines are darker.
fn fade(run: &Run<'_>, t: Option<f64>) -> f64 {
    match t {
        None => 1.0,
        Some(t) => {
            let span = (run.t1 - run.t0).max(1e-12);
            0.3 + 0.7 * ((t - run.t0) / span).clamp(0.0, 1.0)
        }
    }
}

/// The content of one panel, back to front: isopotentials, true shapes, safety margins, footprints, reference paths, adapted paths,
/// contacts, marks.
fn draw_plane(doc: &SharedDoc, chart: &mut Chart<'_>, pl: &Plane, run: &Run<'_>) -> Result<(), PlotError> {
    Doc::group(doc, "isopotential", || -> Result<(), PlotError> {
        for o in &pl.iso {
            let f = fade(run, o.t);
            let stroke = Stroke { color: isopotential_stroke().color.mix(f), ..isopotential_stroke() };
            if o.t.is_none() {
                draw_patch(chart, &o.poly, isopotential_fill(), Some(stroke))?;
            } else {
                draw_outline(chart, &o.poly, stroke)?;
            }
        }
        Ok(())
    })?;
    Doc::group(doc, "obstacle-true", || -> Result<(), PlotError> {
        // Where the last time label of the current obstacle went: labels closer than this are left out.
        let mut last: Option<(i32, i32)> = None;
        for o in &pl.truth {
            if o.t.is_some() && o.t == run.marks.first().copied() {
                last = None;
            }
            let f = fade(run, o.t);
            if o.cloud {
                let style = OBSTACLE_EDGE.mix(f).filled();
                let ((x0, x1), (y0, y1)) = pl.ranges;
                let inside = o.poly.iter().filter(|p| p.0 >= x0 && p.0 <= x1 && p.1 >= y0 && p.1 <= y1);
                chart.draw_series(inside.map(|p| Circle::new(*p, px(2), style))).map_err(drawing_err)?;
            } else {
                let fill = if o.t.is_none() { obstacle_fill() } else { obstacle_fill().mix(0.5 * f) };
                draw_patch(chart, &o.poly, fill, Some(Stroke::solid(OBSTACLE_EDGE, 1.0)))?;
            }
            if let Some(t) = o.t {
                last = time_label(chart, &o.poly, t, pl.ranges, last)?;
            }
        }
        Ok(())
    })?;
    Doc::group(doc, "margin", || -> Result<(), PlotError> {
        for o in &pl.margins {
            let stroke = margin_stroke();
            draw_outline(chart, &o.poly, Stroke { color: stroke.color.mix(fade(run, o.t)), ..stroke })?;
        }
        Ok(())
    })?;
    Doc::group(doc, "footprint", || -> Result<(), PlotError> {
        for (gi, g) in run.groups.iter().enumerate() {
            for o in pl.prints.get(gi).into_iter().flatten() {
                let color = robot_color(g).mix(0.9 * fade(run, o.t));
                draw_outline(chart, &o.poly, Stroke { color, width: 1.0, dash: None })?;
            }
        }
        Ok(())
    })?;
    for (gi, g) in run.groups.iter().enumerate() {
        Doc::group(doc, "demonstration", || draw_curve(chart, &pl.demo[gi], demo_stroke()))?;
        Doc::group(doc, "path-free", || draw_curve(chart, &pl.free[gi], free_stroke(run, g)))?;
    }
    for (gi, g) in run.groups.iter().enumerate() {
        Doc::group(doc, "path-adapted", || draw_curve(chart, &pl.adapted[gi], adapted_stroke(run, g)))?;
    }
    Doc::group(doc, "contact", || -> Result<(), PlotError> {
        for c in pl.contacts.iter().flatten() {
            draw_curve(chart, c, contact_stroke())?;
            if let Some(p) = c.first().filter(|p| finite(p)) {
                chart
                    .draw_series(std::iter::once(Cross::new(*p, px(6), CONTACT.stroke_width(px(2)))))
                    .map_err(drawing_err)?;
            }
        }
        Ok(())
    })?;
    Doc::group(doc, "time-mark", || -> Result<(), PlotError> {
        for (gi, g) in run.groups.iter().enumerate() {
            for (t, p) in pl.ticks[gi].iter().filter(|(_, p)| finite(p)) {
                let color = if run.single() { MARKER } else { robot_color(g) };
                chart
                    .draw_series(std::iter::once(
                        EmptyElement::at(*p)
                            + Circle::new((0, 0), px(3), color.filled())
                            + Text::new(
                                format!("{} s", fmt_num(*t)),
                                (px(5) as i32, -(px(9) as i32)),
                                (FONT, px(12)).into_font().color(&color),
                            ),
                    ))
                    .map_err(drawing_err)?;
            }
        }
        Ok(())
    })?;
    Doc::group(doc, "markers", || -> Result<(), PlotError> {
        for s in pl.starts.iter().filter(|p| finite(p)) {
            chart
                .draw_series(std::iter::once(Circle::new(*s, px(4), MARKER.filled())))
                .map_err(drawing_err)?;
        }
        for g in pl.goals.iter().filter(|p| finite(p)) {
            chart
                .draw_series(std::iter::once(Cross::new(*g, px(5), MARKER.stroke_width(px(2)))))
                .map_err(drawing_err)?;
        }
        Ok(())
    })
}
