//! How a run steps: the output step, the internal step (fixed RK4 or adaptive Dormand–Prince 5(4)), the stability
//! bound of the fixed step, and what the integration cost.

use crate::error::{InvalidInput, Result};

/// Largest `dt sqrt(K) / tau` accepted: RK4 on the critically damped transformation system is stable up to about
/// 2.8; this keeps a margin (the paper's `K = 1050` at `dt = 1 ms` allows `tau` down to 16 ms).
pub const MAX_STIFF_STEP: f64 = 2.0;

/// Largest output step, seconds.
pub(crate) const MAX_DT: f64 = 0.1;

/// Checks that RK4 with step `dt` is stable for stiffness `k` and time scale `tau`; the error names `field`.
///
/// # Formula
/// `dt sqrt(max K) / tau <= MAX_STIFF_STEP`.
pub(crate) fn check_stability(k: &[f64], dt: f64, tau: f64, field: &str) -> Result<(), InvalidInput> {
    let k_max = k.iter().copied().fold(0.0, f64::max);
    let x = dt * k_max.sqrt() / tau;
    if x > MAX_STIFF_STEP {
        return Err(InvalidInput::new(
            field,
            format!(
                "dt sqrt(K) / tau = {x:.3} exceeds {MAX_STIFF_STEP}: the integration would be unstable (use a smaller dt or a larger tau; tau >= {:.4} s here)",
                dt * k_max.sqrt() / MAX_STIFF_STEP
            ),
        ));
    }
    Ok(())
}

/// How a run steps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stepping {
    /// Output step, seconds: the points handed out are this far apart.
    pub dt: f64,
    /// The internal step in output steps: RK4 every `step_points` output points with exact dense output in
    /// between, or with a tolerance the largest adaptive step.
    pub step_points: usize,
    /// The adaptive step's local error tolerance (metres on positions and metres per second on velocities,
    /// relative to `1 + |value|`); `None`: RK4 at `step_points`.
    pub tolerance: Option<f64>,
}

impl Stepping {
    /// Classical RK4 at every output step `dt` (the reference).
    pub fn rk4(dt: f64) -> Self {
        Self { dt, step_points: 1, tolerance: None }
    }

    /// The internal step, seconds (the largest one, with a tolerance).
    pub fn internal_step(&self) -> f64 {
        self.dt * self.step_points as f64
    }

    /// True when the internal step is coarser than the output step (a fixed coarse step, or the adaptive one).
    #[cfg(test)]
    pub(crate) fn is_coarse(&self) -> bool {
        self.step_points > 1 || self.tolerance.is_some()
    }

    /// Checks every field; the error names it.
    pub fn validate(&self) -> Result<(), InvalidInput> {
        if !(self.dt.is_finite() && self.dt > 0.0 && self.dt <= MAX_DT) {
            return Err(InvalidInput::new("dt", format!("must be greater than 0 and at most {MAX_DT} s")));
        }
        if self.step_points == 0 {
            return Err(InvalidInput::new("integration_step_s", "must be at least one output step"));
        }
        if let Some(tol) = self.tolerance
            && !(tol.is_finite() && tol > 0.0)
        {
            return Err(InvalidInput::new(
                "integration_tolerance",
                "must be a finite number greater than zero",
            ));
        }
        Ok(())
    }
}

/// What a run's integration cost: its internal steps and evaluations of the acceleration (each one of the field).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct IntegrationCost {
    /// Steps kept.
    pub steps: u64,
    /// Adaptive steps rejected (and retried shorter).
    pub rejected: u64,
    /// Evaluations of the acceleration.
    pub evaluations: u64,
    /// Output points the limiter changed or braked ([`super::LimitAction::Limited`], [`super::LimitAction::Braking`]).
    pub limited: u64,
    /// Restarts of the internal grid before its next knot (a change, a limited point, the time scale coupled).
    pub restarts: u64,
}
