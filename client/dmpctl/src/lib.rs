//! `dmpctl`, the command line of the DMP cell, and what it is built from: offline scenario runs with their files
//! and figures, the commands that talk to the server, and the simulations and load of `dmp-sim`.
//!
//! | concept | module |
//! | --- | --- |
//! | the dispatcher: runs a parsed command line | [`cli`] |
//! | the flags and commands, as clap parses them (TLS and token flags included) | `args` |
//! | the commands that talk to the server (`learn`, `list`, `plan`, `stream`, `scene` ...) | `server_commands` |
//! | `info`, `stats`, `health` and the server's warnings | `server_info` |
//! | the warnings of a run counted by kind, for its summary | `warning_tally` |
//! | the figure of `plan` and `stream` | `server_plot` |
//! | changes during a `stream`: its schedule and its stdin commands | `stream_controls` |
//! | what a plan or stream reported beside its setpoints: events, limits in force, clearances | `run_record` |
//! | `robot put`, `show`, `delete`: a robot's record | `robot_commands` |
//! | `scenario run --server`: the offline experiment computed by the server | [`scenario_through_server`] |
//! | `scene put --via zenoh` confirmed by the server's scene | `scene_confirm` |
//! | where a command acts: its cell and Zenoh endpoints, its server found over Zenoh | `place` |
//! | the tools with robots of their own (`sim`, `load`, `scenario run --server`): clean-up on Ctrl-C | `tools` |
//! | offline runs and timing | [`offline`] |
//! | reading scenario files, errors at the field | [`scenario_file`] |
//! | obstacles from JSON (`scene put`, a scenario's), one error style `FILE:LINE:COLUMN: FIELD: REASON` | `obstacle_file` |
//! | the line and column of a value at a field path | `json_position` |
//! | `NaN` and `Infinity` in a JSON file, found and named | `json_non_finite` |
//! | demonstrations from CSV | [`demo_csv`] |
//! | the JSON printed of a stored primitive | `primitive_json` |
//! | output files | `outputs` |
//! | progress on a terminal (`indicatif`), nothing when piped | `progress` |
//! | errors and the exit code | [`DmpctlError`] |
//!
//! The modules form layers, each using only those below it: the dispatcher [`cli`] on top; the commands
//! (`server_commands`, `robot_commands`, [`scenario_through_server`], `server_plot`, `server_info`, `place`,
//! `tools`); the flags (`args`); and the files, outputs and runs they share ([`offline`], [`scenario_file`],
//! `run_record`, `obstacle_file`, `json_position`, [`demo_csv`], `primitive_json`, `outputs`, `progress`, `error`).
//! What other crates use (the tests, the deploy checks) is public; the rest is the crate's own.

#![warn(missing_docs)]
#![warn(unreachable_pub)]

mod args;
pub mod cli;
pub mod demo_csv;
mod error;
mod json_non_finite;
mod json_position;
mod obstacle_file;
pub mod offline;
mod outputs;
mod place;
mod primitive_json;
mod progress;
mod robot_commands;
mod run_record;
pub mod scenario_file;
pub mod scenario_through_server;
mod scene_confirm;
mod server_commands;
mod server_info;
mod server_plot;
mod stream_controls;
mod tools;
mod warning_tally;

pub use error::DmpctlError;
