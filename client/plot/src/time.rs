//! Plots against time, for robots that are neither 2-D nor 3-D: each coordinate in its own panel (at most
//! [`MAX_TIME_PANELS`]), an obstacle as the band its extent along that coordinate sweeps.

use dmp::Obstacle;
use plotters::prelude::*;

use super::backend::{Doc, px};
use super::bounds::{Bounds, padded};
use super::draw::{draw_curve, draw_mesh, draw_patch};
use super::layout::{Frame, PANEL_MARGIN, X_LABEL_AREA, Y_LABEL_AREA, chart_on, figure};
use super::legend::{Entry, Mark, path_entries};
use super::run::Run;
use super::strip;
use super::style::{OBSTACLE_EDGE, Stroke, band_fill, demo_stroke};
use super::{MAX_TIME_PANELS, OUTLINE_SAMPLES_ND, P2, PlotError, PlotInput};

/// One coordinate's panel.
#[derive(Debug)]
struct Panel {
    /// The DMP dimension.
    j: usize,
    /// The robot owning it.
    owner: Option<usize>,
    /// The obstacles' extents along it, as polygons over the time axis.
    bands: Vec<Vec<P2>>,
    /// Its data range.
    y: (f64, f64),
}

/// Extent of `o` along each of its axes, as offsets from its centre.
fn extent(o: &Obstacle) -> Vec<(f64, f64)> {
    if o.rotation().is_none() {
        // Axis-aligned: the extent along axis i is exactly the semi-axis.
        return o.shape().semi_axes().iter().map(|a| (-a, *a)).collect();
    }
    let off = o.boundary_offsets(OUTLINE_SAMPLES_ND);
    (0..o.dim())
        .map(|i| {
            off.iter()
                .skip(i)
                .step_by(o.dim())
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(*v), hi.max(*v)))
        })
        .collect()
}

/// The figure of the first [`MAX_TIME_PANELS`] of the `d` coordinates against time.
pub(super) fn render(input: &PlotInput<'_>, run: &Run<'_>, d: usize) -> Result<String, PlotError> {
    let shown = d.min(MAX_TIME_PANELS);
    let extents: Vec<Vec<(f64, f64)>> = input.obstacles.iter().map(extent).collect();
    let (lo, hi) = run.time_span;
    let (tx0, tx1) = if hi > lo { (lo, hi) } else { (lo - 0.5, lo + 0.5) };

    let panels_data: Vec<Panel> = (0..shown)
        .map(|j| {
            let owner = run.groups.iter().position(|g| g.dims.contains(&j));
            let bands: Vec<Vec<P2>> = match owner {
                Some(gi) => {
                    let i = run.groups[gi].dims.iter().position(|&k| k == j).unwrap_or(0);
                    input
                        .obstacles
                        .iter()
                        .zip(&extents)
                        .map(|(o, ext)| {
                            let (lo, hi) = ext[i];
                            let c = |t: f64| o.center()[i] + o.velocity()[i] * t;
                            vec![
                                (tx0, c(tx0) + lo),
                                (tx1, c(tx1) + lo),
                                (tx1, c(tx1) + hi),
                                (tx0, c(tx0) + hi),
                            ]
                        })
                        .collect()
                }
                None => Vec::new(),
            };
            let mut b = Bounds::new();
            for c in [&run.demo, &run.free, &run.adapted] {
                b.add_all(&c.against_time(j));
            }
            bands.iter().for_each(|p| b.add_all(p));
            let y = if b.is_empty() { (-1.0, 1.0) } else { padded(b.y0, b.y1, 0.08) };
            Panel { j, owner, bands, y }
        })
        .collect();

    let panels =
        vec![(px(840) + 2 * PANEL_MARGIN + Y_LABEL_AREA, px(150) + 2 * PANEL_MARGIN + X_LABEL_AREA); shown];
    let demo_text = if run.demo_timed { "demonstration" } else { "demonstration (time rescaled)" };
    let mut entries = path_entries(run, (!input.demonstration.is_empty()).then_some(demo_text), input.method);
    if !input.obstacles.is_empty() {
        entries
            .push(Entry::new(Mark::Patch(band_fill(), Stroke::solid(OBSTACLE_EDGE, 1.0)), "obstacle extent"));
    }
    let mut notes = Vec::new();
    if d > shown {
        notes.push(format!("showing {shown} of {d} coordinates"));
    }

    let frame = Frame {
        title: input.title,
        panels: &panels,
        vertical: true,
        legend: (&entries, &notes),
        strip_h: strip::height(input),
    };
    figure(
        &frame,
        |doc, k, area| {
            let p = &panels_data[k];
            let mut chart = chart_on(area, X_LABEL_AREA, |_, _| ((tx0, tx1), p.y))?;
            let y_desc = match p.owner {
                Some(gi) if !run.single() => format!("x{} ({})", p.j + 1, run.groups[gi].label),
                _ => format!("x{}", p.j + 1),
            };
            draw_mesh(&mut chart, "t (s)", &y_desc, 10, 5)?;
            Doc::group(doc, "obstacle-true", || -> Result<(), PlotError> {
                for band in &p.bands {
                    draw_patch(
                        &mut chart,
                        band,
                        band_fill(),
                        Some(Stroke { color: OBSTACLE_EDGE.mix(0.5), width: 1.0, dash: None }),
                    )?;
                }
                Ok(())
            })?;
            let g = p.owner.map(|gi| &run.groups[gi]).unwrap_or(&run.groups[0]);
            Doc::group(doc, "demonstration", || {
                draw_curve(&mut chart, &run.demo.against_time(p.j), demo_stroke())
            })?;
            Doc::group(doc, "path-free", || {
                draw_curve(&mut chart, &run.free.against_time(p.j), run.free_stroke(g))
            })?;
            Doc::group(doc, "path-adapted", || {
                draw_curve(&mut chart, &run.adapted.against_time(p.j), run.adapted_stroke(g))
            })
        },
        |doc, area| strip::draw(doc, area, input, run),
    )
}
