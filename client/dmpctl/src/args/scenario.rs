//! `dmpctl scenario ...`: the offline experiments, or the same through the server.

use std::path::PathBuf;

use clap::Subcommand;

/// `dmpctl scenario ...`
#[derive(Debug, Subcommand)]
pub(crate) enum ScenarioCommand {
    /// Learn, roll out with and without obstacles, write trajectory.csv, metrics.json and plot.svg. Offline,
    /// unless `--server URL` is given: then the server learns and plans.
    Run {
        /// The scenario file.
        file: PathBuf,
        /// Output directory (created).
        #[arg(long)]
        out: PathBuf,
        /// A collision is expected (the paper's run without avoidance): it does not make the exit code 3.
        #[arg(long)]
        allow_collision: bool,
        /// With `--server`: keep the primitives of the run's robots (`scenario.<name>`), which are otherwise
        /// deleted when it ends, also after an error or Ctrl-C.
        #[arg(long)]
        keep: bool,
    },
    /// Time the avoidance rollout and print one JSON object.
    Bench {
        /// The scenario file.
        file: PathBuf,
        /// Timed repetitions (the median is reported).
        #[arg(long, default_value_t = 5)]
        repeat: usize,
    },
}
