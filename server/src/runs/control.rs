//! What a running stream is told after it started: a session's commands, the robot's measured states, and the
//! warnings of commands that were refused (which reach the robot with its next segment while the run goes on).

use dmp_proto::v1;
use dmp_proto::v1::warning::Kind;

/// A command of a session.
#[derive(Debug, Clone)]
pub(crate) enum Control {
    /// New goal: the position (empty keeps it) and a pose run's orientation (`[x, y, z, w]`, `None` keeps it).
    SetGoal(Vec<f64>, Option<[f64; 4]>),
    /// New tau.
    SetTau(f64),
    /// Hold position.
    Pause,
    /// Continue.
    Resume,
    /// Decelerate to rest and end.
    Stop,
    /// The robot's measured state: published to the cell.
    State(v1::RobotState),
    /// A command that was refused: the warning goes to the robot with the next segment, the run goes on.
    Rejected(v1::Warning),
}

/// The warning of a refused command: `field` of `command` (`command.field`), for `reason`.
pub(crate) fn command_rejected(command: &str, field: &str, reason: &str) -> v1::Warning {
    warning(Kind::CommandRejected, format!("{command}.{field}"), reason.to_owned())
}

/// A warning of `kind` on `field`, for `reason`.
pub(crate) fn warning(kind: Kind, field: String, reason: String) -> v1::Warning {
    v1::Warning { kind: kind as i32, field, reason, obstacle_id: String::new() }
}
