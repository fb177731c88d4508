//! `dmpctl`, the command line of the DMP cell, and what it is built from: offline scenario runs with their files
//! and figures, the commands that talk to the server, and the simulations and load of `dmp-sim`.
//!
//! | concept | module |
//! | --- | --- |
//! | the command line: flags and dispatch | [`cli`] |
//! | TLS and token flags | [`connect_args`] |
//! | reading scenario files, errors at the field | [`scenario_file`] |
//! | obstacles from JSON (`scene put`, a scenario's), one error style `FILE:LINE:COLUMN: FIELD: REASON` | [`obstacle_file`] |
//! | the line and column of a value at a field path | [`json_position`] |
//! | offline runs and timing | [`offline`] |
//! | output files | [`outputs`] |
//! | demonstrations from CSV | [`demo_csv`] |
//! | the commands that talk to the server (`learn`, `list`, `plan`, `stream`, `scene` ...) | [`server_commands`] |
//! | the figure of `plan` and `stream` | [`server_plot`] |
//! | `robot put`, `show`, `delete`: a robot's record | [`robot_commands`] |
//! | `scenario run --server`: the offline experiment computed by the server | [`scenario_through_server`] |
//! | the tools with robots of their own (`sim`, `load`, `scenario run --server`): clean-up on Ctrl-C | [`tools`] |
//! | progress on a terminal (`indicatif`), nothing when piped | [`progress`] |
//! | errors and the exit code | [`error`] |

pub mod cli;
pub mod connect_args;
pub mod demo_csv;
pub mod error;
pub mod json_position;
pub mod obstacle_file;
pub mod offline;
pub mod outputs;
pub mod place;
pub mod progress;
pub mod robot_commands;
pub mod scenario_file;
pub mod scenario_through_server;
pub mod server_commands;
pub mod server_info;
pub mod server_plot;
pub mod tools;

pub use error::DmpctlError;
