//! Errors of the client library.

use std::path::PathBuf;

use thiserror::Error;

/// What can go wrong in the client.
#[derive(Debug, Error)]
pub enum ClientError {
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A scenario file is not valid JSON of the scenario format; `field` is the path of the bad value.
    #[error("{path}: {field}: {message}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// Path of the value at fault, e.g. `obstacles[0].semi_axes`, or `(document)`.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// The scenario parses but breaks a rule of the engine.
    #[error("{path}: {source}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// The rule.
        source: dmp::DmpError,
    },
    /// The plot could not be drawn.
    #[error("plot: {0}")]
    Plot(String),
}

impl ClientError {
    /// True when the user's input is at fault (the CLI exits with code 2).
    pub fn is_bad_input(&self) -> bool {
        matches!(self, ClientError::Parse { .. } | ClientError::Invalid { .. })
    }
}
