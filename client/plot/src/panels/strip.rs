//! The time strip under the path panels: speed, acceleration, jerk and clearance to the nearest obstacle against
//! time, and for a pose run the angular speed, acceleration and jerk and the rotation from the start orientation in
//! a second column; on a shared time axis, with the run's events as vertical lines and the limits the run kept as
//! dashed horizontal lines.

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::data::bounds::{Bounds, padded};
use crate::data::geometry::P2;
use crate::data::input::PlotInput;
use crate::data::quantity::Quantity;
use crate::data::run::Run;
use crate::draw::backend::{Doc, SharedDoc, px};
use crate::draw::primitives::{Area, Chart, draw_curve, draw_mesh, drawing_err, put_text};
use crate::draw::style::{
    CONTACT, EVENT, FONT, LIMIT, Stroke, adapted_stroke, fmt_num, free_stroke, limit_stroke,
};
use crate::error::PlotError;
use crate::layout::chart::{PANEL_MARGIN, X_LABEL_AREA, chart_on};

/// Height of one panel's plotting area, pixels.
const PANEL_H: u32 = 110;
/// A limit above this many times the curves' peak is not drawn to scale: the panel says where it is instead.
const OFF_SCALE: f64 = 4.0;

/// The smallest top of a panel's axis: a curve that is zero up to rounding (the jerk of a steady motion) stays at
/// the bottom instead of filling the panel with noise.
const FLOOR: f64 = 1e-3;

/// Room for the tick labels of the upper panels (only the lowest one names the time axis).
const TICKS_ONLY: u32 = px(24);

fn panel_h(last: bool) -> u32 {
    px(PANEL_H) + 2 * PANEL_MARGIN + if last { X_LABEL_AREA } else { TICKS_ONLY }
}

/// Height of the strip of `input`.
pub(crate) fn height(input: &PlotInput<'_>) -> u32 {
    let n = Quantity::grid(input).len();
    (0..n).map(|r| panel_h(r + 1 == n)).sum()
}

/// The time axis: the run's, widened to its events.
fn time_range(input: &PlotInput<'_>, run: &Run<'_>) -> (f64, f64) {
    let (mut lo, mut hi) = (run.t0, run.t1);
    for e in input.events.iter().filter(|e| e.t.is_finite()) {
        lo = lo.min(e.t);
        hi = hi.max(e.t);
    }
    if hi > lo { (lo, hi) } else { (lo - 0.5, lo + 0.5) }
}

/// Draws the strip on `area`: its panels row by row, each row split in as many columns as it has quantities.
pub(crate) fn draw(
    doc: &SharedDoc,
    area: &Area,
    input: &PlotInput<'_>,
    run: &Run<'_>,
) -> Result<(), PlotError> {
    let time = time_range(input, run);
    let (w, _) = area.dim_in_pixel();
    let grid = Quantity::grid(input);
    let mut top = 0;
    for (r, row) in grid.iter().enumerate() {
        let last = r + 1 == grid.len();
        let cw = w / row.len().max(1) as u32;
        for (c, q) in row.iter().enumerate() {
            let cell = area.clone().shrink((c as u32 * cw, top), (cw, panel_h(last)));
            let labelled = r == 0 && c == 0;
            draw_panel(doc, &cell, input, run, *q, time, (last, labelled))?;
        }
        top += panel_h(last);
    }
    Ok(())
}

/// One quantity's panel on `area`: `last` names the time axis, `labelled` names the events.
fn draw_panel(
    doc: &SharedDoc,
    area: &Area,
    input: &PlotInput<'_>,
    run: &Run<'_>,
    q: Quantity,
    (tx0, tx1): (f64, f64),
    (last, labelled): (bool, bool),
) -> Result<(), PlotError> {
    let (w, h) = area.dim_in_pixel();
    let data = q.curves(input, run);
    let mut b = Bounds::new();
    for (a, f) in &data {
        b.add_all(a);
        b.add_all(f);
    }
    let limit = q.bounded().and_then(|l| run.safety.limit(l));
    // The limit is drawn to scale unless it would flatten the curves.
    let peak = if b.is_empty() { 0.0 } else { b.y1.max(FLOOR) };
    let to_scale = limit.filter(|l| peak <= 0.0 || *l <= OFF_SCALE * peak);
    let y = if q == Quantity::Clearance {
        if b.is_empty() { (0.0, 1.0) } else { padded(b.y0.min(0.0), b.y1.max(0.0), 0.08) }
    } else if b.is_empty() && to_scale.is_none() {
        (0.0, 1.0)
    } else if limit.is_some() && to_scale.is_none() {
        // Room at the top for the limit's value, above the curves.
        padded(0.0, peak * 1.3, 0.05)
    } else {
        padded(0.0, peak.max(to_scale.unwrap_or(0.0)), 0.05)
    };
    Doc::begin(doc, &[("class", q.class()), ("id", &format!("strip-{}", q.class()))]);
    let mut chart = chart_on(area, if last { X_LABEL_AREA } else { TICKS_ONLY }, |_, _| ((tx0, tx1), y))?;
    draw_mesh(&mut chart, if last { "t (s)" } else { "" }, q.desc(), 10, 4)?;
    if q == Quantity::Clearance {
        if b.is_empty() {
            put_text(area, "no obstacle", (w as i32 / 2, h as i32 / 2), 15, HPos::Center);
        } else {
            draw_curve(&mut chart, &[(tx0, 0.0), (tx1, 0.0)], Stroke::solid(CONTACT, 1.0))?;
        }
    }
    for ((adapted, free), g) in data.iter().zip(&run.groups) {
        Doc::group(doc, "path-free", || draw_curve(&mut chart, free, free_stroke(run, g)))?;
        Doc::group(doc, "path-adapted", || draw_curve(&mut chart, adapted, adapted_stroke(run, g)))?;
    }
    if let Some(l) = limit {
        draw_limit(doc, &mut chart, q, l, to_scale.is_some(), ((tx0, tx1), y))?;
    }
    draw_events(doc, &mut chart, input, y, labelled)?;
    Doc::end(doc);
    Ok(())
}

/// The limit `l` on `q`: a dashed line labelled with its value, or, when it is far above the curves (not
/// `to_scale`), its value written at the top of the panel with an arrow up.
fn draw_limit(
    doc: &SharedDoc,
    chart: &mut Chart<'_>,
    q: Quantity,
    l: f64,
    to_scale: bool,
    ((tx0, tx1), (y0, y1)): ((f64, f64), (f64, f64)),
) -> Result<(), PlotError> {
    Doc::begin(doc, &[("class", "limit"), ("data-limit", &fmt_num(l))]);
    let text = format!("limit {} {}", fmt_num(l), q.unit());
    let style = |v: VPos| (FONT, px(12)).into_font().color(&LIMIT).pos(Pos::new(HPos::Right, v));
    let label: (P2, (i32, i32), VPos) = if to_scale {
        draw_curve(chart, &[(tx0, l), (tx1, l)], limit_stroke())?;
        // Above the line, unless it is near the top of the panel.
        if (l - y0) / (y1 - y0) > 0.8 {
            ((tx1, l), (-(px(6) as i32), px(3) as i32), VPos::Top)
        } else {
            ((tx1, l), (-(px(6) as i32), -(px(3) as i32)), VPos::Bottom)
        }
    } else {
        ((tx1, y1), (-(px(6) as i32), px(3) as i32), VPos::Top)
    };
    let text = if to_scale { text } else { format!("{text} ↑ (off scale)") };
    let (at, offset, v) = label;
    chart
        .draw_series(std::iter::once(EmptyElement::at(at) + Text::new(text, offset, style(v))))
        .map_err(drawing_err)?;
    Doc::end(doc);
    Ok(())
}

/// Each event as a vertical line, labelled on the first panel.
fn draw_events(
    doc: &SharedDoc,
    chart: &mut Chart<'_>,
    input: &PlotInput<'_>,
    (y0, y1): (f64, f64),
    labelled: bool,
) -> Result<(), PlotError> {
    for (k, e) in input.events.iter().filter(|e| e.t.is_finite()).enumerate() {
        Doc::begin(doc, &[("class", "event"), ("data-t", &fmt_num(e.t))]);
        draw_curve(
            chart,
            &[(e.t, y0), (e.t, y1)],
            Stroke { color: EVENT.to_rgba(), width: 1.2, dash: Some((6, 3)) },
        )?;
        if labelled {
            let style = (FONT, px(12)).into_font().color(&EVENT);
            let label = format!("{} ({} s)", e.label, fmt_num(e.t));
            chart
                .draw_series(std::iter::once(
                    // Staggered on three rows, so that close events stay readable.
                    EmptyElement::at((e.t, y1))
                        + Text::new(label, (px(4) as i32, px(2 + 14 * (k as u32 % 3)) as i32), style),
                ))
                .map_err(drawing_err)?;
        }
        Doc::end(doc);
    }
    Ok(())
}
