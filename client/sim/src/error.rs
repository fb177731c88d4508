//! Errors of the simulations and of the load generator.

use std::path::PathBuf;

use dmp_client::ClientError;
use thiserror::Error;

/// What can go wrong in a simulation or a load run.
#[derive(Debug, Error)]
pub enum SimError {
    /// A call to the server or a Zenoh publication failed, or an answer broke the schema's contract.
    #[error(transparent)]
    Client(#[from] ClientError),
    /// A flag or a parameter breaks a rule.
    #[error("{field}: {message}")]
    Argument {
        /// The flag or parameter at fault, e.g. `--rate`.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// A report could not be written.
    #[error("{path}: {source}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A report or figure could not be made.
    #[error("plot: {0}")]
    Plot(String),
}

impl SimError {
    /// True when the user's input is at fault (the command line exits with code 2).
    pub fn is_bad_input(&self) -> bool {
        match self {
            SimError::Argument { .. } => true,
            SimError::Client(e) => e.is_bad_input(),
            SimError::Io { .. } | SimError::Plot(_) => false,
        }
    }

    /// An argument error.
    pub(crate) fn argument(field: impl Into<String>, message: impl Into<String>) -> Self {
        SimError::Argument { field: field.into(), message: message.into() }
    }

    /// The server's answers break what the run expects ([`ClientError::Protocol`]).
    pub(crate) fn protocol(message: String) -> Self {
        SimError::Client(ClientError::Protocol(message))
    }

    /// A stream or session already ended ([`ClientError::Closed`]).
    pub(crate) fn closed(what: String) -> Self {
        SimError::Client(ClientError::Closed(what))
    }
}
