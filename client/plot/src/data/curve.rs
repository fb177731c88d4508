//! A decimated curve: the rows of a trajectory or of the demonstration that are drawn, and what is plotted of them
//! (positions on a plane, a coordinate or a norm against time).

use dmp::Trajectory;

use super::decimate::decimated;
use super::geometry::P2;

/// A decimated curve: times and full-dimensional positions (and, for rollouts, velocities and accelerations).
#[derive(Debug, Default)]
pub(crate) struct Curve {
    pub(crate) t: Vec<f64>,
    pub(crate) x: Vec<Vec<f64>>,
    pub(crate) v: Vec<Vec<f64>>,
    pub(crate) a: Vec<Vec<f64>>,
}

impl Curve {
    pub(crate) fn of(tr: &Trajectory) -> Self {
        Self::rows(tr, &decimated(tr.len()))
    }

    /// Rows `idx` of `tr`.
    pub(crate) fn rows(tr: &Trajectory, idx: &[usize]) -> Self {
        Self {
            t: idx.iter().map(|&k| tr.t[k]).collect(),
            x: idx.iter().map(|&k| tr.position(k).to_vec()).collect(),
            v: idx.iter().map(|&k| tr.velocity(k).to_vec()).collect(),
            a: idx.iter().map(|&k| tr.acceleration(k).to_vec()).collect(),
        }
    }

    /// The norm over `dims` of `rows` (velocities or accelerations) against time.
    pub(crate) fn norm_against_time(&self, rows: &[Vec<f64>], dims: &[usize]) -> Vec<P2> {
        self.t
            .iter()
            .zip(rows)
            .map(|(t, r)| (*t, dims.iter().map(|&k| r[k] * r[k]).sum::<f64>().sqrt()))
            .collect()
    }

    /// The demonstration, its rows spread evenly over `[t0, t1]`.
    pub(crate) fn spread(rows: &[Vec<f64>], t0: f64, t1: f64) -> Self {
        let idx = decimated(rows.len());
        let n = rows.len().saturating_sub(1).max(1) as f64;
        Self {
            t: idx.iter().map(|&k| t0 + (t1 - t0) * k as f64 / n).collect(),
            x: idx.iter().map(|&k| rows[k].clone()).collect(),
            ..Self::default()
        }
    }

    /// The demonstration at its own times `times` (one per row), shifted so that its first sample is at `t0`.
    pub(crate) fn timed(rows: &[Vec<f64>], times: &[f64], t0: f64) -> Self {
        let idx = decimated(rows.len());
        let first = times.first().copied().unwrap_or(0.0);
        Self {
            t: idx.iter().map(|&k| times[k] - first + t0).collect(),
            x: idx.iter().map(|&k| rows[k].clone()).collect(),
            ..Self::default()
        }
    }

    /// Positions restricted to `dims`, then projected on the local axes `(i, j)`.
    pub(crate) fn plane(&self, dims: &[usize], (i, j): (usize, usize)) -> Vec<P2> {
        self.x.iter().map(|p| (p[dims[i]], p[dims[j]])).collect()
    }

    /// Coordinate `k` against time.
    pub(crate) fn against_time(&self, k: usize) -> Vec<P2> {
        self.t.iter().zip(&self.x).map(|(t, p)| (*t, p[k])).collect()
    }
}
