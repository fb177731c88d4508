//! The learned primitive: what is stored, sent and replayed.

use serde::{Deserialize, Serialize};

use crate::error::{DmpError, InvalidInput, Result, ensure_finite, ensure_positive};

/// Version of the serialized layout of [`Primitive`].
pub const FORMAT_VERSION: u32 = 1;

/// A DMP learned from one demonstration (paper, `eqs:dmps_eq`). It replays identically after a save and a load
/// (serialize with exact float round-trips, e.g. `serde_json` with `float_roundtrip`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Primitive {
    /// Layout version, [`FORMAT_VERSION`].
    pub format_version: u32,
    /// Dimension `d`.
    pub dim: usize,
    /// The paper's `N`: the basis has `N + 1` Gaussians.
    pub n_basis: usize,
    /// Canonical decay `alpha`.
    pub alpha: f64,
    /// Stiffness per dimension, `K_p`.
    pub k: Vec<f64>,
    /// Damping per dimension, `D_p`.
    pub d: Vec<f64>,
    /// Time scale of the demonstration (its duration).
    pub tau: f64,
    /// Start of the demonstration.
    pub start: Vec<f64>,
    /// Goal of the demonstration.
    pub goal: Vec<f64>,
    /// Weights, `weights[p][i]`, `d x (N + 1)`.
    pub weights: Vec<Vec<f64>>,
    /// A pose primitive: its last three dimensions are the orientation's rotation vector in this chart
    /// ([`OrientationChart`]); `None` for a position-only primitive.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub orientation: Option<OrientationChart>,
}

/// The orientation of a pose primitive: its last three dimensions are the rotation vector
/// `y = log(q ⊗ q̄_ref)` of the orientation `q` in the chart at `reference` (Koutras and Doulgeri's formulation,
/// [`crate::orientation`]). A learned pose primitive has its chart at the demonstration's last orientation, so the
/// goal of those dimensions is `0`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OrientationChart {
    /// `q_ref`, `[x, y, z, w]`: a unit quaternion.
    pub reference: [f64; 4],
}

impl OrientationChart {
    /// Checks that `reference` is a unit quaternion within `1e-6` (the rule of
    /// `orientation::quaternion::from_xyzw`).
    pub fn validate(&self) -> Result<(), InvalidInput> {
        let q = self.reference;
        if q.iter().any(|v| !v.is_finite()) {
            return Err(InvalidInput::new(
                "orientation.reference",
                "must be four finite numbers (x, y, z, w)",
            ));
        }
        let norm = q.iter().map(|v| v * v).sum::<f64>().sqrt();
        if (norm - 1.0).abs() > 1e-6 {
            return Err(InvalidInput::new(
                "orientation.reference",
                format!("must be a unit quaternion (x, y, z, w): its norm is {norm}, more than 1e-6 from 1"),
            ));
        }
        Ok(())
    }
}

impl Primitive {
    /// A primitive with null weights: a critically damped straight line from `start` to `goal` (the youBot and
    /// Panda moves of the paper). `d` defaults to `2 sqrt(K)`.
    pub fn straight_line(
        n_basis: usize,
        alpha: f64,
        k: Vec<f64>,
        d: Option<Vec<f64>>,
        tau: f64,
        start: Vec<f64>,
        goal: Vec<f64>,
    ) -> Result<Self> {
        let dim = start.len();
        let d = d.unwrap_or_else(|| k.iter().map(|k| 2.0 * k.sqrt()).collect());
        let p = Self {
            format_version: FORMAT_VERSION,
            dim,
            n_basis,
            alpha,
            k,
            d,
            tau,
            start,
            goal,
            weights: vec![vec![0.0; n_basis + 1]; dim],
            orientation: None,
        };
        p.validate()?;
        Ok(p)
    }

    /// Checks a primitive that came from outside (a file, a store, the network).
    pub fn validate(&self) -> Result<()> {
        if self.format_version != FORMAT_VERSION {
            return Err(DmpError::UnsupportedVersion {
                found: self.format_version,
                supported: FORMAT_VERSION,
            });
        }
        let d = self.dim;
        if d == 0 {
            return Err(InvalidInput::new("dim", "must be at least 1").into());
        }
        if self.n_basis == 0 {
            return Err(InvalidInput::new("n_basis", "must be at least 1").into());
        }
        ensure_positive(|| "alpha".into(), self.alpha)?;
        ensure_positive(|| "tau".into(), self.tau)?;
        for (name, v) in [("k", &self.k), ("d", &self.d), ("start", &self.start), ("goal", &self.goal)] {
            if v.len() != d {
                return Err(
                    InvalidInput::new(name, format!("must have {d} entries, found {}", v.len())).into()
                );
            }
        }
        for (i, k) in self.k.iter().enumerate() {
            ensure_positive(|| format!("k[{i}]"), *k)?;
        }
        for (i, x) in self.d.iter().enumerate() {
            ensure_finite(|| format!("d[{i}]"), *x)?;
            if *x < 0.0 {
                return Err(InvalidInput::new(format!("d[{i}]"), "must be >= 0").into());
            }
        }
        for (i, (s, g)) in self.start.iter().zip(&self.goal).enumerate() {
            ensure_finite(|| format!("start[{i}]"), *s)?;
            ensure_finite(|| format!("goal[{i}]"), *g)?;
        }
        if self.weights.len() != d {
            return Err(InvalidInput::new(
                "weights",
                format!("must have {d} rows, found {}", self.weights.len()),
            )
            .into());
        }
        for (p, row) in self.weights.iter().enumerate() {
            if row.len() != self.n_basis + 1 {
                return Err(InvalidInput::new(
                    format!("weights[{p}]"),
                    format!("must have N + 1 = {} entries, found {}", self.n_basis + 1, row.len()),
                )
                .into());
            }
            for (i, w) in row.iter().enumerate() {
                ensure_finite(|| format!("weights[{p}][{i}]"), *w)?;
            }
        }
        if let Some(chart) = &self.orientation {
            chart.validate()?;
            if d < 4 {
                return Err(InvalidInput::new(
                    "dim",
                    format!("a pose primitive has a position and the 3 orientation dimensions, found {d}"),
                )
                .into());
            }
        }
        Ok(())
    }

    /// The dimension of the position part: `dim` less the 3 orientation dimensions of a pose primitive.
    pub fn position_dim(&self) -> usize {
        if self.orientation.is_some() { self.dim.saturating_sub(3) } else { self.dim }
    }
}
