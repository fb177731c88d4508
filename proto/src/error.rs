//! The one error of the wire: the field at fault and the rule it breaks.

use dmp::{DmpError, InvalidInput};
use thiserror::Error;

/// A wire value (a message field, a JSON key, a Zenoh key's name, a session setting) that breaks a rule.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("{field}: {rule}")]
pub struct WireError {
    /// Path of the value, e.g. `extra_obstacles[1].superquadric.semi_axes[0]` or `zenoh.connect[0]`.
    pub field: String,
    /// What it must satisfy.
    pub rule: String,
}

impl WireError {
    /// The error of `field`.
    pub fn new(field: impl Into<String>, rule: impl Into<String>) -> Self {
        Self { field: field.into(), rule: rule.into() }
    }

    /// The same error with `prefix.` in front of its field.
    pub fn within(self, prefix: &str) -> Self {
        Self { field: format!("{prefix}.{}", self.field), rule: self.rule }
    }
}

impl From<InvalidInput> for WireError {
    fn from(i: InvalidInput) -> Self {
        Self { field: i.field, rule: i.rule }
    }
}

/// The engine's refusal of a field keeps its path; its other errors (learning, the format version) are about a
/// primitive and name `primitive`.
impl From<DmpError> for WireError {
    fn from(e: DmpError) -> Self {
        match e {
            DmpError::Invalid(i) => i.into(),
            other => Self::new("primitive", other.to_string()),
        }
    }
}
