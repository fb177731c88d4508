//! The time strip under the path panels: speed, acceleration and clearance to the nearest obstacle against time,
//! and for a pose run its rotation from the start orientation, one panel each on a shared time axis, with the run's
//! events as vertical lines.

use plotters::prelude::*;
use plotters::style::text_anchor::HPos;

use crate::data::bounds::{Bounds, padded};
use crate::data::decimate::decimated;
use crate::data::geometry::P2;
use crate::data::input::PlotInput;
use crate::data::run::Run;
use crate::draw::backend::{Doc, SharedDoc, px};
use crate::draw::primitives::{Area, Chart, draw_curve, draw_mesh, drawing_err, put_text};
use crate::draw::style::{CONTACT, EVENT, FONT, Stroke, adapted_stroke, fmt_num, free_stroke};
use crate::error::PlotError;
use crate::layout::chart::{PANEL_MARGIN, X_LABEL_AREA, chart_on};

/// Height of one panel's plotting area, pixels.
const PANEL_H: u32 = 96;
/// The quantities: the first three always, the orientation for a pose run.
const QUANTITIES: [(&str, &str); 4] = [
    ("speed", "speed (m/s)"),
    ("acceleration", "acceleration (m/s²)"),
    ("clearance", "clearance (m)"),
    ("orientation", "rotation from start (°)"),
];

/// The panels of `input`'s strip.
fn quantities(input: &PlotInput<'_>) -> usize {
    if input.pose.is_some() { 4 } else { 3 }
}

/// Room for the tick labels of the upper panels (only the lowest one names the time axis).
const TICKS_ONLY: u32 = px(24);

fn panel_h(last: bool) -> u32 {
    px(PANEL_H) + 2 * PANEL_MARGIN + if last { X_LABEL_AREA } else { TICKS_ONLY }
}

/// Height of the strip of `input`.
pub(crate) fn height(input: &PlotInput<'_>) -> u32 {
    let n = quantities(input);
    (0..n).map(|q| panel_h(q + 1 == n)).sum()
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

/// The curves of quantity `q` per robot: `(adapted, free)`; the clearance has no free curve.
fn curves(input: &PlotInput<'_>, run: &Run<'_>, q: usize) -> Vec<(Vec<P2>, Vec<P2>)> {
    if q == 3 {
        return input.pose.iter().map(|p| p.turn_curves(&input.adapted.t, &input.free.t)).collect();
    }
    run.groups
        .iter()
        .enumerate()
        .map(|(gi, g)| match q {
            0 => (
                run.adapted.norm_against_time(&run.adapted.v, &g.dims),
                run.free.norm_against_time(&run.free.v, &g.dims),
            ),
            1 => (
                run.adapted.norm_against_time(&run.adapted.a, &g.dims),
                run.free.norm_against_time(&run.free.a, &g.dims),
            ),
            _ => {
                let s = &run.clearance[gi];
                let idx = decimated(s.t.len());
                (idx.iter().map(|&k| (s.t[k], s.v[k])).collect(), Vec::new())
            }
        })
        .collect()
}

/// Draws the strip on `area`.
pub(crate) fn draw(
    doc: &SharedDoc,
    area: &Area,
    input: &PlotInput<'_>,
    run: &Run<'_>,
) -> Result<(), PlotError> {
    let (tx0, tx1) = time_range(input, run);
    let (w, _) = area.dim_in_pixel();
    let n = quantities(input);
    for (q, (class, desc)) in QUANTITIES.iter().enumerate().take(n) {
        let last = q + 1 == n;
        let top: u32 = (0..q).map(|k| panel_h(k + 1 == n)).sum();
        let sub = area.clone().shrink((0, top), (w, panel_h(last)));
        let data = curves(input, run, q);
        let mut b = Bounds::new();
        for (a, f) in &data {
            b.add_all(a);
            b.add_all(f);
        }
        let y = if b.is_empty() {
            (0.0, 1.0)
        } else if q == 2 {
            padded(b.y0.min(0.0), b.y1.max(0.0), 0.08)
        } else {
            padded(0.0, b.y1.max(0.0), 0.05)
        };
        Doc::begin(doc, &[("class", class), ("id", &format!("strip-{class}"))]);
        let mut chart = chart_on(&sub, if last { X_LABEL_AREA } else { TICKS_ONLY }, |_, _| ((tx0, tx1), y))?;
        draw_mesh(&mut chart, if last { "t (s)" } else { "" }, desc, 10, 4)?;
        if q == 2 {
            if b.is_empty() {
                put_text(&sub, "no obstacle", (w as i32 / 2, panel_h(last) as i32 / 2), 15, HPos::Center);
            } else {
                draw_curve(&mut chart, &[(tx0, 0.0), (tx1, 0.0)], Stroke::solid(CONTACT, 1.0))?;
            }
        }
        for (gi, g) in run.groups.iter().enumerate() {
            let (adapted, free) = &data[gi];
            Doc::group(doc, "path-free", || draw_curve(&mut chart, free, free_stroke(run, g)))?;
            Doc::group(doc, "path-adapted", || draw_curve(&mut chart, adapted, adapted_stroke(run, g)))?;
        }
        draw_events(doc, &mut chart, input, y, q == 0)?;
        Doc::end(doc);
    }
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
