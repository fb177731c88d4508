//! `dmpctl robot ...`: a robot's record on the server.

use std::path::PathBuf;

use clap::Subcommand;

use super::values::Vector;

/// `dmpctl robot ...`
#[derive(Debug, Subcommand)]
pub(crate) enum RobotCommand {
    /// Store the record of robot ID (replacing the one before), and print it as stored.
    Put {
        /// The robot.
        id: String,
        /// Its limits: a profile (`panda`, `psm`, `youbot`) or a JSON file of the six fields of `Limits`
        /// (`max_speed`, `max_acceleration`, `max_jerk`, `max_angular_speed`, ...; a field left out is no limit).
        #[arg(long)]
        limits: Option<String>,
        /// Its footprint: the semi-axes of an ellipsoid, metres, e.g. `0.4,0.3`.
        #[arg(long, allow_hyphen_values = true)]
        footprint: Option<Vector>,
        /// The tool it holds in its pose runs: a JSON file `{"semi_axes": [...], "exponents": [...], "offset":
        /// [...], "axis": true, "control_points": 25}`.
        #[arg(long)]
        tool: Option<PathBuf>,
    },
    /// The record of robot ID, as JSON.
    Show {
        /// The robot.
        id: String,
    },
    /// Delete the record of robot ID (its primitives stay).
    Delete {
        /// The robot.
        id: String,
    },
}
