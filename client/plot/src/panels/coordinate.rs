//! A panel of one coordinate against time: the demonstration, the obstacle-free and the adapted run, and each
//! obstacle as the band its extent along that coordinate sweeps.

use dmp::Obstacle;
use plotters::prelude::*;

use crate::data::bounds::{Bounds, padded};
use crate::data::geometry::P2;
use crate::data::input::PlotInput;
use crate::data::outline::OUTLINE_SAMPLES_ND;
use crate::data::run::Run;
use crate::draw::backend::{Doc, SharedDoc, px};
use crate::draw::primitives::{Area, draw_curve, draw_mesh, draw_patch};
use crate::draw::style::{OBSTACLE_EDGE, Stroke, adapted_stroke, band_fill, demo_stroke, free_stroke};
use crate::error::PlotError;
use crate::layout::chart::{PANEL_MARGIN, X_LABEL_AREA, Y_LABEL_AREA, chart_on};

/// Size of every coordinate's panel: the plotting area, plus the margins and label areas.
pub(crate) const SIZE: (u32, u32) =
    (px(840) + 2 * PANEL_MARGIN + Y_LABEL_AREA, px(150) + 2 * PANEL_MARGIN + X_LABEL_AREA);

/// Extent of `o` along each of its axes, as offsets from its centre.
pub(crate) fn extent(o: &Obstacle) -> Vec<(f64, f64)> {
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

/// One coordinate's panel.
#[derive(Debug)]
pub(crate) struct Panel {
    /// The DMP dimension.
    j: usize,
    /// The robot owning it.
    owner: Option<usize>,
    /// The obstacles' extents along it, as polygons over the time axis.
    bands: Vec<Vec<P2>>,
    /// Its data range.
    y: (f64, f64),
}

impl Panel {
    /// The panel of DMP dimension `j` over the time axis `(tx0, tx1)`; `extents` are those of `input`'s obstacles
    /// ([`extent`]).
    pub(crate) fn new(
        input: &PlotInput<'_>,
        run: &Run<'_>,
        j: usize,
        extents: &[Vec<(f64, f64)>],
        (tx0, tx1): (f64, f64),
    ) -> Self {
        let owner = run.groups.iter().position(|g| g.dims.contains(&j));
        let bands: Vec<Vec<P2>> = match owner {
            Some(gi) => {
                let i = run.groups[gi].dims.iter().position(|&k| k == j).unwrap_or(0);
                input
                    .obstacles
                    .iter()
                    .zip(extents)
                    .map(|(o, ext)| {
                        let (lo, hi) = ext[i];
                        let c = |t: f64| o.center()[i] + o.velocity()[i] * t;
                        vec![(tx0, c(tx0) + lo), (tx1, c(tx1) + lo), (tx1, c(tx1) + hi), (tx0, c(tx0) + hi)]
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
        Self { j, owner, bands, y }
    }

    /// Draws the panel on `area` over the time axis `(tx0, tx1)`: axes, the obstacles' bands, then the runs.
    pub(crate) fn draw(
        &self,
        doc: &SharedDoc,
        area: &Area,
        run: &Run<'_>,
        (tx0, tx1): (f64, f64),
    ) -> Result<(), PlotError> {
        let mut chart = chart_on(area, X_LABEL_AREA, |_, _| ((tx0, tx1), self.y))?;
        let y_desc = match self.owner {
            Some(gi) if !run.single() => format!("x{} ({})", self.j + 1, run.groups[gi].label),
            _ => format!("x{}", self.j + 1),
        };
        draw_mesh(&mut chart, "t (s)", &y_desc, 10, 5)?;
        Doc::group(doc, "obstacle-true", || -> Result<(), PlotError> {
            for band in &self.bands {
                draw_patch(
                    &mut chart,
                    band,
                    band_fill(),
                    Some(Stroke { color: OBSTACLE_EDGE.mix(0.5), width: 1.0, dash: None }),
                )?;
            }
            Ok(())
        })?;
        let g = self.owner.map(|gi| &run.groups[gi]).unwrap_or(&run.groups[0]);
        Doc::group(doc, "demonstration", || {
            draw_curve(&mut chart, &run.demo.against_time(self.j), demo_stroke())
        })?;
        Doc::group(doc, "path-free", || {
            draw_curve(&mut chart, &run.free.against_time(self.j), free_stroke(run, g))
        })?;
        Doc::group(doc, "path-adapted", || {
            draw_curve(&mut chart, &run.adapted.against_time(self.j), adapted_stroke(run, g))
        })
    }
}
