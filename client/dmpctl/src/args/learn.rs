//! `dmpctl learn`: the primitive to store and the demonstration it is learned from.

use std::path::PathBuf;

use clap::Args;

use super::values::{Vector, positive};

/// Where a demonstration comes from.
#[derive(Debug, Args)]
#[group(required = true, multiple = false)]
pub(crate) struct LearnSource {
    /// A scenario file: its demonstration and its `dmp` parameters.
    #[arg(long, value_name = "FILE")]
    pub(crate) scenario: Option<PathBuf>,
    /// A CSV file: first column the time, then the positions (optional header `t,x1..xd`).
    #[arg(long, value_name = "FILE")]
    pub(crate) csv: Option<PathBuf>,
}

/// `dmpctl learn`.
#[derive(Debug, Args)]
pub(crate) struct LearnArgs {
    /// The robot.
    #[arg(long)]
    pub(crate) robot: String,
    /// The primitive's name.
    #[arg(long)]
    pub(crate) name: String,
    /// The demonstration.
    #[command(flatten)]
    pub(crate) source: LearnSource,
    /// The paper's N (N + 1 Gaussians) [default: the scenario's, or 50].
    #[arg(long = "n-basis", value_name = "N")]
    pub(crate) n_basis: Option<u32>,
    /// Stiffness K, one value or one per dimension [default: the scenario's, or 1050].
    #[arg(long, value_name = "K,..", allow_hyphen_values = true)]
    pub(crate) k: Option<Vector>,
    /// Damping D, like K [default: the scenario's, or 2 sqrt(K)].
    #[arg(long, value_name = "D,..", allow_hyphen_values = true)]
    pub(crate) d: Option<Vector>,
    /// Canonical decay alpha [default: the scenario's, or 4].
    #[arg(long, value_parser = positive, allow_hyphen_values = true)]
    pub(crate) alpha: Option<f64>,
}
