//! Robot-space panels, for robots moving in 2-D (one panel `x1`-`x2`) or 3-D (three projections): the paths, the
//! obstacles (moving ones also at the start and at the end) and the robots' footprints, with an equal aspect ratio.

use plotters::prelude::*;

use dmp::Obstacle;

use super::bounds::fit_equal_aspect;
use super::draw::{Chart, closed, draw_curve, draw_mesh, draw_patch, drawing_err};
use super::projection::{Plane, planes};
use super::run::Run;
use super::style::{
    Entry, GHOST, MARKER, Mark, OBSTACLE_EDGE, Stroke, demo_stroke, fmt_num, ghost_stroke, obstacle_fill,
    path_entries,
};
use super::{
    CAPTION_H, OUTLINE_SAMPLES_2D, OUTLINE_SAMPLES_ND, PANEL_MARGIN, PlotError, PlotInput, X_LABEL_AREA,
    Y_LABEL_AREA, captioned, chart_on, figure, finite,
};

/// Outlines of one obstacle, as surface samples in robot space.
#[derive(Debug)]
pub(super) struct Outlines {
    /// At the obstacle time.
    pub(super) now: Vec<Vec<f64>>,
    /// At the start and at the end of the run (moving obstacles only).
    pub(super) ghosts: Vec<Vec<Vec<f64>>>,
    /// The centre at the start and at the end of the run (moving obstacles only).
    pub(super) path: Option<(Vec<f64>, Vec<f64>)>,
}

/// Surface samples of `o` at time `t`, absolute positions.
fn surface(o: &Obstacle, t: f64, n: usize) -> Vec<Vec<f64>> {
    let d = o.dim();
    let mut c = vec![0.0; d];
    o.center_at(t, &mut c);
    o.boundary_offsets(n).chunks(d).map(|off| off.iter().zip(&c).map(|(a, b)| a + b).collect()).collect()
}

fn outlines(input: &PlotInput<'_>, run: &Run<'_>, n: usize) -> Vec<Outlines> {
    input
        .obstacles
        .iter()
        .map(|o| {
            let moving = o.velocity().iter().any(|v| *v != 0.0);
            let (mut c0, mut c1) = (vec![0.0; o.dim()], vec![0.0; o.dim()]);
            o.center_at(run.t0, &mut c0);
            o.center_at(run.t1, &mut c1);
            Outlines {
                now: surface(o, run.obstacle_time, n),
                ghosts: if moving { vec![surface(o, run.t0, n), surface(o, run.t1, n)] } else { Vec::new() },
                path: moving.then_some((c0, c1)),
            }
        })
        .collect()
}

/// Footprint outline of each robot at the obstacle time (robots without one: empty).
fn footprints(run: &Run<'_>, n: usize) -> Vec<Vec<Vec<f64>>> {
    let row = run.adapted_row_at(run.obstacle_time);
    run.groups
        .iter()
        .map(|g| match g.footprint {
            Some(shape) if run.groups.len() > 1 => {
                let center: Vec<f64> = g.dims.iter().map(|&k| run.adapted.x[row][k]).collect();
                if center.iter().all(|v| v.is_finite()) {
                    Obstacle::new(&g.label, shape.clone(), center, None, None)
                        .map(|o| surface(&o, 0.0, n))
                        .unwrap_or_default()
                } else {
                    Vec::new()
                }
            }
            _ => Vec::new(),
        })
        .collect()
}

/// The figure of a robot moving in 2-D or 3-D.
pub(super) fn render(input: &PlotInput<'_>, run: &Run<'_>) -> Result<String, PlotError> {
    let sub = run.groups[0].dims.len();
    let ordered = sub == 2;
    let n = if ordered { OUTLINE_SAMPLES_2D } else { OUTLINE_SAMPLES_ND };
    let obstacles = outlines(input, run, n);
    let prints = footprints(run, n);
    let planes: Vec<Plane> =
        planes(sub).into_iter().map(|axes| Plane::new(run, axes, &obstacles, &prints, ordered)).collect();
    let panels: Vec<(u32, u32)> = planes.iter().map(|pl| panel_size(pl, sub)).collect();
    let entries = legend(input, run, prints.iter().any(|p| !p.is_empty()));

    figure(input.title, &panels, false, (&entries, &[]), |k, area| {
        let pl = &planes[k];
        let names = (format!("x{}", pl.axes.0 + 1), format!("x{}", pl.axes.1 + 1));
        let caption = (sub == 3).then(|| format!("{} - {}", names.0, names.1));
        let area = captioned(area, caption.as_deref());
        let mut chart = chart_on(&area, |pw, ph| fit_equal_aspect(pl.ranges.0, pl.ranges.1, pw, ph))?;
        draw_mesh(&mut chart, &names.0, &names.1, 8, 8)?;
        draw_plane(&mut chart, pl, run)
    })
}

/// Panel size: a plotting area shaped like the data (within limits; the ranges are then fitted exactly), plus the
/// margins, label areas and caption.
fn panel_size(pl: &Plane, sub: usize) -> (u32, u32) {
    let ((x0, x1), (y0, y1)) = pl.ranges;
    let (w, h) = if sub == 2 {
        let a = ((x1 - x0) / (y1 - y0)).clamp(0.4, 2.5);
        if a >= 1.0 { (620.0, 620.0 / a) } else { (620.0 * a, 620.0) }
    } else {
        let a = ((x1 - x0) / (y1 - y0)).clamp(0.6, 1.8);
        (380.0 * a, 380.0)
    };
    let caption = if sub == 2 { 0 } else { CAPTION_H };
    (
        w.round() as u32 + 2 * PANEL_MARGIN + Y_LABEL_AREA,
        h.round() as u32 + 2 * PANEL_MARGIN + X_LABEL_AREA + caption,
    )
}

fn legend(input: &PlotInput<'_>, run: &Run<'_>, footprints: bool) -> Vec<Entry> {
    let mut entries = path_entries(run, (!input.demonstration.is_empty()).then_some("demonstration"));
    if !input.obstacles.is_empty() {
        let text = if run.moving {
            format!("obstacle at t = {}", fmt_num(run.obstacle_time))
        } else {
            "obstacle".into()
        };
        entries.push(Entry::new(Mark::Patch(obstacle_fill(), Stroke::solid(OBSTACLE_EDGE, 1)), text));
        if run.moving {
            entries.push(Entry::new(
                Mark::Patch(TRANSPARENT.to_rgba(), ghost_stroke()),
                format!("at t = {} and t = {}", fmt_num(run.t0), fmt_num(run.t1)),
            ));
        }
    }
    if footprints {
        entries.push(Entry::new(
            Mark::Patch(TRANSPARENT.to_rgba(), Stroke::solid(MARKER, 1)),
            format!("footprints at t = {}", fmt_num(run.obstacle_time)),
        ));
    }
    entries.push(Entry::new(Mark::Dot, "start"));
    entries.push(Entry::new(Mark::Cross, "goal"));
    entries
}

/// The content of one panel, back to front: obstacles, footprints, reference paths, adapted paths, markers.
fn draw_plane(chart: &mut Chart<'_, '_>, pl: &Plane, run: &Run<'_>) -> Result<(), PlotError> {
    for poly in &pl.now {
        draw_patch(chart, poly, obstacle_fill(), Some(Stroke::solid(OBSTACLE_EDGE, 1)))?;
    }
    for poly in &pl.ghosts {
        draw_curve(chart, &closed(poly.clone()), ghost_stroke())?;
    }
    for path in &pl.paths {
        draw_curve(chart, path, Stroke { color: GHOST.mix(0.6), width: 1, dash: Some((2, 3)) })?;
    }
    for (gi, g) in run.groups.iter().enumerate() {
        if let Some(print) = pl.prints.get(gi).filter(|p| p.len() >= 3) {
            draw_curve(
                chart,
                &closed(print.clone()),
                Stroke { color: g.color.mix(0.9), width: 1, dash: None },
            )?;
        }
    }
    for (gi, g) in run.groups.iter().enumerate() {
        draw_curve(chart, &pl.demo[gi], demo_stroke())?;
        draw_curve(chart, &pl.free[gi], run.free_stroke(g))?;
    }
    for (gi, g) in run.groups.iter().enumerate() {
        draw_curve(chart, &pl.adapted[gi], run.adapted_stroke(g))?;
    }
    for s in pl.starts.iter().filter(|p| finite(p)) {
        chart.draw_series(std::iter::once(Circle::new(*s, 4, MARKER.filled()))).map_err(drawing_err)?;
    }
    for g in pl.goals.iter().filter(|p| finite(p)) {
        chart.draw_series(std::iter::once(Cross::new(*g, 5, MARKER.stroke_width(2)))).map_err(drawing_err)?;
    }
    Ok(())
}
