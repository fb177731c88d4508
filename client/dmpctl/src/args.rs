//! The command line's flags and commands, as clap parses them: what the user asked for, before anything is read or
//! sent. The command modules read these types; the dispatcher ([`crate::cli`]) runs them.
//!
//! | concept | module |
//! | --- | --- |
//! | the command line as a whole: global flags, the commands | `command_line` |
//! | `scenario run`, `scenario bench` | `scenario` |
//! | `learn` and its demonstration | `learn` |
//! | what `plan` and `stream` replay, and the motion message it makes | `motion` |
//! | `scene put`, `delete`, `list`, and how an update travels | `scene` |
//! | `robot put`, `show`, `delete` | `robot` |
//! | `stream`'s schedule of changes: `--goal-at`, `--tau-at`, `--stop-at` | `schedule` |
//! | TLS and the bearer token | `connect` |
//! | values clap does not parse on its own: vectors, positive numbers, avoidance | `values` |

mod command_line;
mod connect;
mod learn;
mod motion;
mod robot;
mod scenario;
mod scene;
mod schedule;
mod values;

pub use self::command_line::Cli;
pub(crate) use self::command_line::Command;
pub(crate) use self::connect::TOKEN_ENV;
pub(crate) use self::learn::{LearnArgs, LearnSource};
pub(crate) use self::motion::{MotionArgs, PlanArgs, StreamArgs};
pub(crate) use self::robot::RobotCommand;
pub(crate) use self::scenario::ScenarioCommand;
pub(crate) use self::scene::{SceneCommand, Via};
pub(crate) use self::schedule::{GoalAt, TauAt, finite_number, positive_number};
// The command line's tests compare the vectors they parse.
#[cfg(test)]
pub(crate) use self::values::Vector;
