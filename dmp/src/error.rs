//! Typed errors of the engine. Every error names the field at fault and the rule it breaks.

use thiserror::Error;

/// An input the engine refuses. `field` is a path such as `demonstration.t[4]` or `obstacles[1].semi_axes[0]`.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("{field}: {rule}")]
pub struct InvalidInput {
    /// Where the bad value sits.
    pub field: String,
    /// What it must satisfy.
    pub rule: String,
}

impl InvalidInput {
    /// Builds the error from anything printable.
    pub fn new(field: impl Into<String>, rule: impl Into<String>) -> Self {
        Self { field: field.into(), rule: rule.into() }
    }
}

/// Errors of the `dmp` crate.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum DmpError {
    /// An argument or a deserialized value breaks a rule.
    #[error(transparent)]
    Invalid(#[from] InvalidInput),
    /// The least-squares fit of the forcing weights failed (degenerate basis).
    #[error("learning failed: {0}")]
    Learning(String),
    /// The state of a run stopped being finite (the stability bound on the step and `tau` should prevent it).
    #[error("the integration diverged at t = {t:.3} s (no point was handed out from there)")]
    Diverged {
        /// Run time of the first point that was not finite.
        t: f64,
    },
    /// A stored primitive was written by an unknown version of the format.
    #[error("primitive format version {found} is not supported (this build reads version {supported})")]
    UnsupportedVersion {
        /// The version in the data.
        found: u32,
        /// The version this build writes and reads.
        supported: u32,
    },
}

/// Result alias of the crate.
pub type Result<T, E = DmpError> = std::result::Result<T, E>;

/// Returns an error naming `field` unless `value` is finite.
pub(crate) fn ensure_finite(field: impl FnOnce() -> String, value: f64) -> Result<(), InvalidInput> {
    if value.is_finite() { Ok(()) } else { Err(InvalidInput::new(field(), "must be a finite number")) }
}

/// Returns an error naming `field` (and the entry) unless `v` has `dim` finite entries.
pub(crate) fn check_vector(field: &str, v: &[f64], dim: usize) -> Result<(), InvalidInput> {
    if v.len() != dim {
        return Err(InvalidInput::new(field, format!("must have {dim} entries, found {}", v.len())));
    }
    for (i, x) in v.iter().enumerate() {
        ensure_finite(|| format!("{field}[{i}]"), *x)?;
    }
    Ok(())
}

/// Returns an error naming `field` unless `value` is finite and strictly positive.
pub(crate) fn ensure_positive(field: impl FnOnce() -> String, value: f64) -> Result<(), InvalidInput> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(InvalidInput::new(field(), "must be a finite number greater than zero"))
    }
}

impl InvalidInput {
    /// The same error with `prefix.` in front of its field.
    pub fn within(self, prefix: &str) -> Self {
        Self { field: format!("{prefix}.{}", self.field), rule: self.rule }
    }
}

impl DmpError {
    /// The same error with `prefix.` in front of its field, when it names one.
    pub fn within(self, prefix: &str) -> Self {
        match self {
            DmpError::Invalid(i) => DmpError::Invalid(i.within(prefix)),
            other => other,
        }
    }
}
