//! Learning a primitive from one demonstration.

#[cfg(feature = "learn")]
use nalgebra::DMatrix;

#[cfg(feature = "learn")]
use crate::basis::GaussianBasis;
#[cfg(feature = "learn")]
use crate::canonical::phase_at;
#[cfg(feature = "learn")]
use crate::derivatives::gradient;
#[cfg(feature = "learn")]
use crate::error::{DmpError, ensure_positive};
use crate::error::{InvalidInput, Result, ensure_finite};
#[cfg(feature = "learn")]
use crate::primitive::{FORMAT_VERSION, Primitive};

/// One demonstration: increasing sample times (any start, not necessarily uniform) and a position per sample.
#[derive(Debug, Clone, PartialEq)]
pub struct Demonstration {
    t: Vec<f64>,
    x: Vec<Vec<f64>>,
}

impl Demonstration {
    /// Checks and wraps the samples: at least 3, times finite and strictly increasing, every row of the same
    /// dimension `d >= 1` and finite.
    pub fn new(t: Vec<f64>, x: Vec<Vec<f64>>) -> Result<Self> {
        check_samples(&t, x.len(), "demonstration.x", "row")?;
        let d = x[0].len();
        if d == 0 {
            return Err(InvalidInput::new("demonstration.x[0]", "must have at least one coordinate").into());
        }
        for (i, row) in x.iter().enumerate() {
            if row.len() != d {
                return Err(InvalidInput::new(
                    format!("demonstration.x[{i}]"),
                    format!("has {} coordinates, but the first row has {d}", row.len()),
                )
                .into());
            }
            for (j, v) in row.iter().enumerate() {
                ensure_finite(|| format!("demonstration.x[{i}][{j}]"), *v)?;
            }
        }
        Ok(Self { t, x })
    }

    /// Dimension `d`.
    pub fn dim(&self) -> usize {
        self.x[0].len()
    }

    /// Sample times.
    pub fn times(&self) -> &[f64] {
        &self.t
    }

    /// Positions, one row per sample.
    pub fn positions(&self) -> &[Vec<f64>] {
        &self.x
    }

    /// Duration, last time minus first.
    pub fn duration(&self) -> f64 {
        self.t[self.t.len() - 1] - self.t[0]
    }
}

/// Checks the samples of a demonstration: at least 3 sample times, one `item` of `field` per time (`rows` of
/// them), and times finite and strictly increasing (`demonstration.t[i]` at fault).
pub(crate) fn check_samples(t: &[f64], rows: usize, field: &str, item: &str) -> Result<(), InvalidInput> {
    if t.len() < 3 {
        return Err(InvalidInput::new("demonstration.t", "needs at least 3 samples"));
    }
    if rows != t.len() {
        return Err(InvalidInput::new(
            field,
            format!("must have one {item} per sample time ({}), found {rows}", t.len()),
        ));
    }
    for (i, ti) in t.iter().enumerate() {
        ensure_finite(|| format!("demonstration.t[{i}]"), *ti)?;
        if i > 0 && *ti <= t[i - 1] {
            return Err(InvalidInput::new(
                format!("demonstration.t[{i}]"),
                "sample times must be strictly increasing",
            ));
        }
    }
    Ok(())
}

/// How to learn: the paper's `N`, the gains and the canonical decay.
#[derive(Debug, Clone, PartialEq)]
pub struct LearnConfig {
    /// `N`: the basis has `N + 1` Gaussians.
    pub n_basis: usize,
    /// Stiffness, one value per dimension or one for all.
    pub k: Vec<f64>,
    /// Damping, same shape as `k`; `None` for critical damping `2 sqrt(K)`.
    pub d: Option<Vec<f64>>,
    /// Canonical decay `alpha`.
    pub alpha: f64,
}

impl LearnConfig {
    /// The paper's synthetic settings: `N = 50`, `K = 1050`, `D = 2 sqrt(K)`, `alpha = 4`.
    pub fn paper() -> Self {
        Self { n_basis: 50, k: vec![1050.0], d: None, alpha: 4.0 }
    }
}

/// Expands a per-dimension parameter given as one value or `d` values.
#[cfg(feature = "learn")]
pub(crate) fn per_dimension(name: &str, v: &[f64], dim: usize) -> Result<Vec<f64>, InvalidInput> {
    match v.len() {
        1 => Ok(vec![v[0]; dim]),
        n if n == dim => Ok(v.to_vec()),
        n => Err(InvalidInput::new(
            name,
            format!("must be one number or {dim} numbers (one per dimension), found {n}"),
        )),
    }
}

/// Learns a primitive (paper, section 2, "learning phase").
///
/// # Formula
/// With `tau` the demonstration's duration, `s_k = exp(-alpha (t_k - t_0) / tau)`, velocities and accelerations by
/// second-order finite differences, and `phi = 0` in `eq:dmp_acc_obst`, the target forcing term is
/// `f_p(s_k) = (tau^2 xdd_p + D_p tau xd_p - K_p (g_p - x_p) + K_p (g_p - x0_p) s_k) / K_p`;
/// the weights are the least-squares solution (SVD) of `sum_i w_{p,i} s_k psi_i(s_k) / sum_j psi_j(s_k) = f_p(s_k)`.
#[cfg(feature = "learn")]
pub fn learn(demo: &Demonstration, config: &LearnConfig) -> Result<Primitive> {
    let dim = demo.dim();
    let k = per_dimension("dmp.K", &config.k, dim)?;
    for (i, v) in k.iter().enumerate() {
        ensure_positive(|| format!("dmp.K[{i}]"), *v)?;
    }
    let d = match &config.d {
        Some(d) => per_dimension("dmp.D", d, dim)?,
        None => k.iter().map(|k| 2.0 * k.sqrt()).collect(),
    };
    for (i, v) in d.iter().enumerate() {
        ensure_finite(|| format!("dmp.D[{i}]"), *v)?;
        if *v < 0.0 {
            return Err(InvalidInput::new(format!("dmp.D[{i}]"), "must be >= 0").into());
        }
    }
    let basis = GaussianBasis::new(config.n_basis, config.alpha).map_err(|e| match e {
        DmpError::Invalid(i) => DmpError::Invalid(InvalidInput::new(format!("dmp.{}", i.field), i.rule)),
        other => other,
    })?;
    let t = demo.times();
    let m = t.len();
    let tau = demo.duration();
    let start = demo.positions()[0].clone();
    let goal = demo.positions()[m - 1].clone();
    let phases: Vec<f64> = t.iter().map(|ti| phase_at(config.alpha, tau, ti - t[0])).collect();

    let n1 = basis.len();
    let mut design = DMatrix::<f64>::zeros(m, n1);
    let mut act = vec![0.0; n1];
    for (row, &s) in phases.iter().enumerate() {
        let range = basis.normalized(s, &mut act);
        for i in range {
            design[(row, i)] = s * act[i];
        }
    }
    let mut targets = DMatrix::<f64>::zeros(m, dim);
    for p in 0..dim {
        let x: Vec<f64> = demo.positions().iter().map(|r| r[p]).collect();
        let xd = gradient(&x, t);
        let xdd = gradient(&xd, t);
        for j in 0..m {
            targets[(j, p)] = (tau * tau * xdd[j] + d[p] * tau * xd[j] - k[p] * (goal[p] - x[j])
                + k[p] * (goal[p] - start[p]) * phases[j])
                / k[p];
        }
    }
    let svd = design.svd(true, true);
    let w = svd.solve(&targets, 1e-12).map_err(|e| DmpError::Learning(e.to_string()))?;
    let weights: Vec<Vec<f64>> = (0..dim).map(|p| (0..n1).map(|i| w[(i, p)]).collect()).collect();
    if weights.iter().flatten().any(|w| !w.is_finite()) {
        return Err(DmpError::Learning("the least-squares weights are not finite".into()));
    }
    Ok(Primitive {
        format_version: FORMAT_VERSION,
        dim,
        n_basis: config.n_basis,
        alpha: config.alpha,
        k,
        d,
        tau,
        start,
        goal,
        weights,
        orientation: None,
    })
}
