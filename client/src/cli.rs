//! The `dmpctl` command line: argument parsing and dispatch (the binary only sets up and calls [`run`]).

use std::path::PathBuf;

use clap::{Parser, Subcommand};

use crate::error::ClientError;
use crate::offline::{bench_scenario, run_scenario};
use crate::outputs::to_json;

/// Command line of the DMP cell.
#[derive(Debug, Parser)]
#[command(
    name = "dmpctl",
    version,
    about = "Learn, plan and replay Dynamic Movement Primitives around obstacles"
)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// Top-level commands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Reproducible experiments in the scenario format (shared/scenarios/SPEC.md).
    #[command(subcommand)]
    Scenario(ScenarioCommand),
}

/// `dmpctl scenario ...`
#[derive(Debug, Subcommand)]
pub enum ScenarioCommand {
    /// Learn, roll out with and without obstacles, write trajectory.csv, metrics.json and plot.svg.
    Run {
        /// The scenario file.
        file: PathBuf,
        /// Output directory (created).
        #[arg(long)]
        out: PathBuf,
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

/// Runs a parsed command line; returns what to print on standard output.
pub fn run(cli: Cli) -> Result<String, ClientError> {
    match cli.command {
        Command::Scenario(ScenarioCommand::Run { file, out }) => {
            let summary = run_scenario(&file, &out)?;
            let m = &summary.metrics;
            Ok(format!(
                "{}: {} steps in {:.3} s, collision: {}, eps_max {:.4}, final goal distance {:.2e}; wrote {}",
                file.display(),
                m.steps,
                m.compute_seconds,
                m.collision,
                m.eps_max,
                m.final_goal_distance,
                out.display()
            ))
        }
        Command::Scenario(ScenarioCommand::Bench { file, repeat }) => {
            let report = bench_scenario(&file, repeat)?;
            Ok(serde_json::to_string(&report).unwrap_or_else(|_| to_json(&report)))
        }
    }
}
