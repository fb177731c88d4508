//! Where the repulsive terms act on a held tool: its control points, in the tool frame.

use nalgebra::Vector3;

use crate::error::InvalidInput;
use crate::isopotential::{Isopotential, Shape};
use crate::ranges::check_count;

/// Default count of surface samples ([`ControlPoints::Surface`]).
pub const DEFAULT_SURFACE_POINTS: usize = 64;

/// Default count of axis samples ([`ControlPoints::Axis`]): 2.5 cm apart on a 0.6 m bar.
pub const DEFAULT_AXIS_POINTS: usize = 25;

/// Allowed counts of surface samples: four points are the fewest that span a solid (an invertible inertia).
pub const SURFACE_POINTS: std::ops::RangeInclusive<usize> = 4..=10_000;

/// Allowed counts of axis samples: the two tips at least.
pub const AXIS_POINTS: std::ops::RangeInclusive<usize> = 2..=10_000;

/// How a tool is sampled.
///
/// - [`ControlPoints::Surface`] is the general choice (a tray, a ring, a box): `count` points of the surface
///   `C = 0`, in the nearly uniform directions of a Fibonacci sphere (`directions.rs`), the
///   same boundary sampling as the point methods' obstacles. The obstacles then need no inflation for the tool,
///   but the surface between samples is not guarded: use enough of them for the obstacles' size.
/// - [`ControlPoints::Axis`] is for a long, thin tool (a bar, a rod, a probe): `count` points evenly spaced along
///   the longest semi-axis, tips included (a long tool touches first with its tips). The obstacles are inflated by
///   the tool's half-thickness (the largest other semi-axis) plus the sag between two samples, as the paper
///   inflates them by a robot's size. It needs far fewer points than the surface of a thin shape, whose Fibonacci
///   samples are spread over its whole surface while only its length matters for turning; and every point lies on
///   the axis, so no term twists the tool about its own axis (a moment it cannot use to get by).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ControlPoints {
    /// Samples of the surface.
    Surface {
        /// How many ([`SURFACE_POINTS`]).
        count: usize,
    },
    /// Samples along the longest axis.
    Axis {
        /// How many ([`AXIS_POINTS`]).
        count: usize,
    },
}

impl Default for ControlPoints {
    /// [`DEFAULT_SURFACE_POINTS`] surface samples.
    fn default() -> Self {
        ControlPoints::Surface { count: DEFAULT_SURFACE_POINTS }
    }
}

impl ControlPoints {
    /// [`DEFAULT_AXIS_POINTS`] samples along the axis.
    pub fn axis() -> Self {
        ControlPoints::Axis { count: DEFAULT_AXIS_POINTS }
    }

    /// Checks the count; errors name `{prefix}.count`.
    pub fn validate(&self, prefix: &str) -> Result<(), InvalidInput> {
        match *self {
            ControlPoints::Surface { count } => {
                check_count(&format!("{prefix}.count"), count, &SURFACE_POINTS)
            }
            ControlPoints::Axis { count } => check_count(&format!("{prefix}.count"), count, &AXIS_POINTS),
        }
    }

    /// The control points of `shape` (3-D, centred at the origin, axes along the frame's), in that frame.
    pub fn sample(&self, shape: &Shape) -> Vec<Vector3<f64>> {
        match *self {
            ControlPoints::Surface { count } => {
                let mut p = [0.0; 3];
                crate::directions::unit_directions(3, count)
                    .iter()
                    .map(|w| {
                        shape.surface_point(w, &mut p);
                        Vector3::from(p)
                    })
                    .collect()
            }
            ControlPoints::Axis { count } => {
                let (axis, half) = longest_axis(shape.semi_axes());
                (0..count)
                    .map(|k| {
                        let s = -half + 2.0 * half * k as f64 / (count - 1).max(1) as f64;
                        let mut p = Vector3::zeros();
                        p[axis] = s;
                        p
                    })
                    .collect()
            }
        }
    }

    /// For axis samples, a distance within which every point of the tool (a superquadric inside its box
    /// `|y_i| <= a_i`) lies of some control point: the half-thickness (largest other semi-axis, times `sqrt 2` for
    /// the box's corner) plus half the spacing. An isopotential that holds every point within this distance of an
    /// obstacle keeps the whole tool off the obstacle while every control point stays outside it: the paper's
    /// inflation by the held object's size, made for the axis. (Adding it to the semi-axes, the paper's way, holds
    /// that set exactly for a ball only; elongated and box-like shapes need more room, as the pegs of
    /// `dmp/tests/properties/bar_through_gap.rs` get.) `None` for surface samples: the gaps between them are not
    /// bounded here.
    pub fn reach(&self, shape: &Shape) -> Option<f64> {
        match *self {
            ControlPoints::Surface { .. } => None,
            ControlPoints::Axis { count } => {
                let a = shape.semi_axes();
                let (axis, half) = longest_axis(a);
                let side =
                    a.iter().enumerate().filter(|(i, _)| *i != axis).map(|(_, v)| *v).fold(0.0, f64::max);
                Some(std::f64::consts::SQRT_2 * side + half / (count - 1).max(1) as f64)
            }
        }
    }
}

/// The index and length of the longest semi-axis (the first of equals).
fn longest_axis(a: &[f64]) -> (usize, f64) {
    a.iter().enumerate().fold((0, a[0]), |best, (i, &v)| if v > best.1 { (i, v) } else { best })
}
