//! Robot-space panels, for robots moving in 2-D (one panel `x1`-`x2`) or 3-D (three projections): the obstacles'
//! true shapes and isopotentials, the paths with their contacts, and, where things move, outlines at the marked
//! times with the paths ticked at the same times; with an equal aspect ratio.

use plotters::prelude::*;

use dmp::Obstacle;

use super::backend::{Doc, SharedDoc, px};
use super::bounds::fit_equal_aspect;
use super::draw::{Chart, draw_curve, draw_mesh, draw_outline, draw_patch, drawing_err};
use super::layout::{
    CAPTION_H, Frame, PANEL_MARGIN, X_LABEL_AREA, Y_LABEL_AREA, captioned, chart_on, figure,
};
use super::legend::{Entry, Mark, path_entries};
use super::projection::{Outline, Plane, planes};
use super::run::Run;
use super::strip;
use super::style::{
    CONTACT, MARKER, OBSTACLE_EDGE, Stroke, demo_stroke, fmt_num, isopotential_fill, isopotential_stroke,
    obstacle_fill,
};
use super::{OUTLINE_SAMPLES_2D, OUTLINE_SAMPLES_ND, P2, PlotError, PlotInput, finite};

/// The outline of `o` at time `t` on the local axes `(i, j)`: its boundary samples in order in 2-D, the convex hull
/// of its projected surface samples in 3-D.
pub(super) fn obstacle_outline(o: &Obstacle, t: f64, (i, j): (usize, usize), n: usize) -> Vec<P2> {
    let d = o.dim();
    let mut c = vec![0.0; d];
    o.center_at(t, &mut c);
    let pts: Vec<P2> =
        o.boundary_offsets(n).chunks(d).map(|off| (off[i] + c[i], off[j] + c[j])).filter(finite).collect();
    if d == 2 { pts } else { super::projection::convex_hull(pts) }
}

fn moving(o: &Obstacle) -> bool {
    o.velocity().iter().any(|v| *v != 0.0)
}

/// The outlines on the plane `axes`: isopotentials, true shapes, and the robots' footprints.
fn outlines(input: &PlotInput<'_>, run: &Run<'_>, axes: (usize, usize), n: usize) -> Plane {
    let at = |is_moving: bool| -> Vec<Option<f64>> {
        if is_moving { run.marks.iter().map(|t| Some(*t)).collect() } else { vec![None] }
    };
    let mut iso = Vec::new();
    // Without true shapes given, the obstacles are their own: the isopotential is the outline drawn as the shape.
    let isopotentials = if input.solids.is_empty() { &[][..] } else { input.obstacles };
    for o in isopotentials {
        for t in at(moving(o)) {
            let poly = obstacle_outline(o, t.unwrap_or(run.obstacle_time), axes, n);
            iso.push(Outline { t, poly, cloud: false });
        }
    }
    let mut truth = Vec::new();
    for s in &run.truths {
        for t in at(s.moving()) {
            if t.is_some_and(|t| !s.present_at(t)) {
                continue;
            }
            let poly = s.outline(t.unwrap_or(run.obstacle_time), axes, n);
            truth.push(Outline { t, poly, cloud: s.is_cloud() });
        }
    }
    let prints = run
        .groups
        .iter()
        .map(|g| match g.footprint {
            Some(shape) if run.groups.len() > 1 => run
                .marks
                .iter()
                .filter_map(|&t| {
                    let row = run.adapted_row_at(t);
                    let center: Vec<f64> = g.dims.iter().map(|&k| run.adapted.x[row][k]).collect();
                    let o = Obstacle::new(&g.label, shape.clone(), center, None, None).ok()?;
                    Some(Outline { t: Some(t), poly: obstacle_outline(&o, 0.0, axes, n), cloud: false })
                })
                .collect(),
            // One robot holding a tool: the tool where it is at each marked time.
            _ => match input.pose {
                Some(pose) if run.single() => {
                    let (adapted, orientations) = (input.adapted, pose.orientations);
                    run.marks
                        .iter()
                        .filter_map(|&t| {
                            let k = adapted.t.partition_point(|s| *s < t).min(adapted.len() - 1);
                            let poly = pose.tool_outline(adapted.position(k), orientations.get(k)?, axes);
                            (!poly.is_empty()).then_some(Outline { t: Some(t), poly, cloud: false })
                        })
                        .collect()
                }
                _ => Vec::new(),
            },
        })
        .collect();
    Plane::new(run, axes, iso, truth, prints)
}

/// The figure of a robot moving in 2-D or 3-D.
pub(super) fn render(input: &PlotInput<'_>, run: &Run<'_>) -> Result<String, PlotError> {
    let sub = run.groups[0].dims.len();
    let n = if sub == 2 { OUTLINE_SAMPLES_2D } else { OUTLINE_SAMPLES_ND };
    let planes: Vec<Plane> = planes(sub).into_iter().map(|axes| outlines(input, run, axes, n)).collect();
    let panels: Vec<(u32, u32)> = planes.iter().map(|pl| panel_size(pl, sub)).collect();
    let entries = legend(input, run, planes.iter().any(|p| p.prints.iter().any(|f| !f.is_empty())));
    let frame = Frame {
        title: input.title,
        panels: &panels,
        vertical: false,
        legend: (&entries, &[]),
        strip_h: strip::height(input),
    };
    figure(
        &frame,
        |doc, k, area| {
            let pl = &planes[k];
            let names = (format!("x{}", pl.axes.0 + 1), format!("x{}", pl.axes.1 + 1));
            let caption = (sub == 3).then(|| format!("{} - {}", names.0, names.1));
            let area = captioned(area, caption.as_deref());
            let mut chart =
                chart_on(&area, X_LABEL_AREA, |pw, ph| fit_equal_aspect(pl.ranges.0, pl.ranges.1, pw, ph))?;
            draw_mesh(&mut chart, &format!("{} (m)", names.0), &format!("{} (m)", names.1), 8, 8)?;
            draw_plane(doc, &mut chart, pl, run)
        },
        |doc, area| strip::draw(doc, area, input, run),
    )
}

/// Panel size: a plotting area shaped like the data (within limits; the ranges are then fitted exactly), plus the
/// margins, label areas and caption.
fn panel_size(pl: &Plane, sub: usize) -> (u32, u32) {
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

fn legend(input: &PlotInput<'_>, run: &Run<'_>, footprints: bool) -> Vec<Entry> {
    let mut entries =
        path_entries(run, (!input.demonstration.is_empty()).then_some("demonstration"), input.method);
    if !run.truths.is_empty() {
        let text = if input.solids.is_empty() {
            "obstacle (its isopotential C = 0)"
        } else {
            "obstacle (true shape)"
        };
        entries.push(
            Entry::new(Mark::Patch(obstacle_fill(), Stroke::solid(OBSTACLE_EDGE, 1.0)), text)
                .class("legend-true"),
        );
    }
    if run.truths.iter().any(|t| t.is_cloud()) {
        entries.push(
            Entry::new(
                Mark::Patch(OBSTACLE_EDGE.to_rgba(), Stroke::solid(OBSTACLE_EDGE, 1.0)),
                "points seen",
            )
            .class("legend-points"),
        );
    }
    if !input.obstacles.is_empty() && !input.solids.is_empty() {
        entries.push(
            Entry::new(Mark::Patch(isopotential_fill(), isopotential_stroke()), "isopotential avoided")
                .class("legend-isopotential"),
        );
    }
    if run.contacts.iter().any(|c| !c.is_empty()) {
        entries.push(Entry::new(Mark::Line(contact_stroke()), "contact").class("legend-contact"));
    }
    if !run.marks.is_empty() {
        entries.push(Entry::new(Mark::Dot, "path and obstacles at t (s)").class("legend-time-mark"));
    }
    if footprints {
        let (text, class) =
            if run.single() { ("tool at t (s)", "legend-tool") } else { ("footprints", "legend-footprints") };
        entries.push(
            Entry::new(Mark::Patch(TRANSPARENT.to_rgba(), Stroke::solid(MARKER, 1.0)), text).class(class),
        );
    }
    entries.push(Entry::new(Mark::Dot, "start"));
    entries.push(Entry::new(Mark::Cross, "goal"));
    entries
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
    let style = (super::style::FONT, px(12)).into_font().color(&OBSTACLE_EDGE);
    let label = Text::new(format!("{} s", fmt_num(t)), (-(px(10) as i32), -(px(14) as i32)), style);
    chart.draw_series(std::iter::once(EmptyElement::at(*top) + label)).map_err(drawing_err)?;
    Ok(Some(at))
}

fn contact_stroke() -> Stroke {
    Stroke { color: CONTACT.mix(0.55), width: 7.0, dash: None }
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

/// The content of one panel, back to front: isopotentials, true shapes, footprints, reference paths, adapted paths,
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
    Doc::group(doc, "footprint", || -> Result<(), PlotError> {
        for (gi, g) in run.groups.iter().enumerate() {
            for o in pl.prints.get(gi).into_iter().flatten() {
                let color = g.color.mix(0.9 * fade(run, o.t));
                draw_outline(chart, &o.poly, Stroke { color, width: 1.0, dash: None })?;
            }
        }
        Ok(())
    })?;
    for (gi, g) in run.groups.iter().enumerate() {
        Doc::group(doc, "demonstration", || draw_curve(chart, &pl.demo[gi], demo_stroke()))?;
        Doc::group(doc, "path-free", || draw_curve(chart, &pl.free[gi], run.free_stroke(g)))?;
    }
    for (gi, g) in run.groups.iter().enumerate() {
        Doc::group(doc, "path-adapted", || draw_curve(chart, &pl.adapted[gi], run.adapted_stroke(g)))?;
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
                let color = if run.single() { MARKER } else { g.color };
                chart
                    .draw_series(std::iter::once(
                        EmptyElement::at(*p)
                            + Circle::new((0, 0), px(3), color.filled())
                            + Text::new(
                                format!("{} s", fmt_num(*t)),
                                (px(5) as i32, -(px(9) as i32)),
                                (super::style::FONT, px(12)).into_font().color(&color),
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
