//! A pose run: the orientation over time (its rotation away from the start orientation, a panel of the time
//! strip) and the held tool's outline along the path, at the marked times.

use super::decimate::decimated;
use super::geometry::{P2, convex_hull, finite};
use crate::error::PlotError;

/// The orientations of a pose run and the tool it holds: what a figure needs to show a pose run.
#[derive(Debug, Clone, Copy)]
pub struct PoseTrace<'a> {
    /// The orientation `[x, y, z, w]` (a unit quaternion) at each row of the adapted trajectory.
    pub orientations: &'a [[f64; 4]],
    /// The same at each row of the obstacle-free trajectory.
    pub free_orientations: &'a [[f64; 4]],
    /// Samples of the held tool's surface in the tool frame (the frame of the pose), metres; empty: no tool.
    pub tool_surface: &'a [[f64; 3]],
}

impl PoseTrace<'_> {
    /// Checks the orientations against the trajectories' rows.
    pub(crate) fn validate(&self, adapted_rows: usize, free_rows: usize) -> Result<(), PlotError> {
        for (what, q, rows) in [
            ("the adapted run's orientations", self.orientations, adapted_rows),
            ("the obstacle-free run's orientations", self.free_orientations, free_rows),
        ] {
            if q.len() != rows {
                return Err(PlotError::Length { what: what.into(), expected: rows, found: q.len() });
            }
        }
        Ok(())
    }

    /// The rotation away from the start orientation (the adapted run's first), degrees, against time: `(adapted,
    /// free)`, thinned like the other curves.
    pub(crate) fn turn_curves(&self, adapted_t: &[f64], free_t: &[f64]) -> (Vec<P2>, Vec<P2>) {
        let Some(start) = self.orientations.first() else { return (Vec::new(), Vec::new()) };
        let curve = |t: &[f64], q: &[[f64; 4]]| -> Vec<P2> {
            decimated(t.len().min(q.len())).into_iter().map(|k| (t[k], angle_deg(start, &q[k]))).collect()
        };
        (curve(adapted_t, self.orientations), curve(free_t, self.free_orientations))
    }

    /// The tool's outline on the axes `(i, j)` with its frame at `position` turned by `q`: the convex hull of its
    /// projected surface samples. Empty without a tool.
    pub(crate) fn tool_outline(&self, position: &[f64], q: &[f64; 4], (i, j): (usize, usize)) -> Vec<P2> {
        if self.tool_surface.is_empty() || position.len() < 3 {
            return Vec::new();
        }
        let points = self
            .tool_surface
            .iter()
            .map(|s| {
                let w = rotate(q, s);
                let p = [position[0] + w[0], position[1] + w[1], position[2] + w[2]];
                (p[i], p[j])
            })
            .filter(finite)
            .collect();
        convex_hull(points)
    }
}

/// The angle between two orientations, degrees (`2 acos |⟨q1, q2⟩|`: q and -q are the same orientation).
fn angle_deg(a: &[f64; 4], b: &[f64; 4]) -> f64 {
    let norm = |q: &[f64; 4]| q.iter().map(|v| v * v).sum::<f64>().sqrt();
    let dot = a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>() / (norm(a) * norm(b));
    (2.0 * dot.abs().min(1.0).acos()).to_degrees()
}

/// `v` turned by the unit quaternion `q = [x, y, z, w]`: `v + 2w (u × v) + 2 u × (u × v)` with `u = (x, y, z)`.
fn rotate(q: &[f64; 4], v: &[f64; 3]) -> [f64; 3] {
    let n = q.iter().map(|c| c * c).sum::<f64>().sqrt();
    let (u, w) = ([q[0] / n, q[1] / n, q[2] / n], q[3] / n);
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    };
    let uv = cross(u, *v);
    let uuv = cross(u, uv);
    [0, 1, 2].map(|k| v[k] + 2.0 * (w * uv[k] + uuv[k]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_quarter_turn_about_z_takes_x_to_y() {
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let r = rotate(&[0.0, 0.0, h, h], &[1.0, 0.0, 0.0]);
        assert!((r[0]).abs() < 1e-12 && (r[1] - 1.0).abs() < 1e-12 && r[2].abs() < 1e-12, "{r:?}");
        assert!((angle_deg(&[0.0, 0.0, 0.0, 1.0], &[0.0, 0.0, h, h]) - 90.0).abs() < 1e-9);
        // The double cover: -q is q.
        assert!(angle_deg(&[0.0, 0.0, h, h], &[0.0, 0.0, -h, -h]).abs() < 1e-6);
    }
}
