//! `dmpctl scene ...`: the cell's obstacles, and how an update travels.

use std::path::PathBuf;

use clap::{Subcommand, ValueEnum};

use super::values::non_negative;
use crate::scene_confirm::DEFAULT_WAIT_S;

/// How an obstacle update travels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum Via {
    /// The scene service.
    Grpc,
    /// A put or delete on `dmp/<cell>/obstacles/<id>`.
    Zenoh,
}

/// `dmpctl scene ...`
#[derive(Debug, Subcommand)]
pub(crate) enum SceneCommand {
    /// Add or replace obstacles: FILE is one JSON obstacle of the scenario format (plus optional `margin`,
    /// `ttl_s`), or a file whose `obstacles` are all put (e.g. a scenario).
    Put {
        /// The file.
        file: PathBuf,
        /// Transport.
        #[arg(long, value_enum, default_value_t = Via::Grpc)]
        via: Via,
        /// Seconds after which the obstacles expire (replaces the file's `ttl_s`; 0: never). `--ttl` is an alias.
        #[arg(long = "ttl-s", alias = "ttl", value_parser = non_negative, allow_hyphen_values = true)]
        ttl: Option<f64>,
        /// With `--via zenoh`: how long to wait, seconds, for the server's scene (watched over gRPC) to show each
        /// obstacle; one that does not is an error naming it. 0 publishes without confirming.
        #[arg(long = "wait-s", value_name = "S", value_parser = non_negative, default_value_t = DEFAULT_WAIT_S)]
        wait: f64,
    },
    /// Remove an obstacle.
    Delete {
        /// Its id.
        id: String,
        /// Transport.
        #[arg(long, value_enum, default_value_t = Via::Grpc)]
        via: Via,
    },
    /// The current obstacles, as JSON.
    List,
}
