//! Errors of `dmpctl`: its own (files, scenarios, flags, figures) and those of the libraries it calls.

use std::path::PathBuf;

use dmp_client::ClientError;
use dmp_plot::PlotError;
use dmp_sim::SimError;
use thiserror::Error;

/// What can go wrong in a `dmpctl` command.
#[derive(Debug, Error)]
pub enum DmpctlError {
    /// A call to the server or a Zenoh publication failed, or an answer broke the schema's contract.
    #[error(transparent)]
    Client(#[from] ClientError),
    /// A simulation or a load run failed.
    #[error(transparent)]
    Sim(#[from] SimError),
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A scenario file is not valid JSON of the scenario format; `field` is the path of the bad value:
    /// `FILE:LINE:COLUMN: FIELD: REASON` (the position when known).
    #[error("{}{}: {field}: {message}", path.display(), position.map_or(String::new(), |(l, c)| format!(":{l}:{c}")))]
    Parse {
        /// The file.
        path: PathBuf,
        /// Line and column (from 1) of the value at fault, when known.
        position: Option<(usize, usize)>,
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
    /// An argument of the command line breaks a rule.
    #[error("{field}: {message}")]
    Argument {
        /// The flag or field at fault, e.g. `--scenario / --csv`.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// The plot could not be drawn.
    #[error("plot: {0}")]
    Plot(#[from] PlotError),
    /// The server answers but some of its services are not serving (`health`).
    #[error("{0}")]
    Unhealthy(String),
    /// A run completed, with a collision, a stall, a missed goal, non-finite values or late setpoints (`dmpctl`
    /// exits with code 3: a CI gate). `summary` is the line the run would print; `problems` says which.
    #[error("{summary}\nthe run completed with problems: {}", problems.join("; "))]
    Problems {
        /// The run's summary line.
        summary: String,
        /// What went wrong, one entry each.
        problems: Vec<String>,
    },
    /// An update published over Zenoh did not show in the server's scene (the message names the obstacle and why).
    #[error("{0}")]
    NotApplied(String),
    /// The command was interrupted (Ctrl-C) after cleaning up what it had stored (`dmpctl` exits with 130).
    #[error("interrupted{}", if cleaned.is_empty() { String::new() } else { format!(" ({cleaned})") })]
    Interrupted {
        /// What the clean-up did, or why it could not.
        cleaned: String,
    },
}

impl DmpctlError {
    /// True when the user's input is at fault (`dmpctl` exits with code 2): a bad scenario or argument, or a
    /// request the server refused as InvalidArgument or NotFound.
    pub fn is_bad_input(&self) -> bool {
        match self {
            DmpctlError::Parse { .. } | DmpctlError::Invalid { .. } | DmpctlError::Argument { .. } => true,
            DmpctlError::Client(e) => e.is_bad_input(),
            DmpctlError::Sim(e) => e.is_bad_input(),
            DmpctlError::Io { .. }
            | DmpctlError::Plot(_)
            | DmpctlError::Problems { .. }
            | DmpctlError::Interrupted { .. }
            | DmpctlError::NotApplied(_)
            | DmpctlError::Unhealthy(_) => false,
        }
    }

    /// The process's exit code: 3 for a run with problems, 2 for bad input, 130 when interrupted (128 + SIGINT,
    /// as shells report it), 1 for anything else.
    pub fn exit_code(&self) -> u8 {
        match self {
            DmpctlError::Problems { .. } => 3,
            DmpctlError::Interrupted { .. } => 130,
            e if e.is_bad_input() => 2,
            _ => 1,
        }
    }

    /// An argument error.
    pub fn argument(field: impl Into<String>, message: impl Into<String>) -> Self {
        DmpctlError::Argument { field: field.into(), message: message.into() }
    }

    /// The server's answer breaks what the command expects ([`ClientError::Protocol`]).
    pub fn protocol(message: String) -> Self {
        DmpctlError::Client(ClientError::Protocol(message))
    }
}
