//! A session's messages after its `start`, checked and turned into the stream's commands. A message that breaks a
//! rule changes nothing in the run: it becomes a [`Control::Rejected`] warning (`COMMAND_REJECTED`, naming the field,
//! e.g. `set_goal.goal[2]`), which the robot receives with its next segment. A measured state that the cell does not
//! take ([`StateAdmission`]) is dropped, counted, and reported the same way as `STATE_DROPPED`.

use dmp_proto::WireError;
use dmp_proto::check::{check_in_workspace, check_tau, check_vector};
use dmp_proto::robot_state::check_robot_state;
use dmp_proto::v1;
use dmp_proto::v1::session_request::Message;
use dmp_proto::v1::warning::Kind;

use crate::cells::state_admission::StateAdmission;
use crate::clock::Clock;
use crate::runs::control::{Control, warning};

/// What a session's messages are checked against: its robot and the server's bounds.
#[derive(Debug, Clone)]
pub(crate) struct SessionCommands {
    robot_id: String,
    dim: usize,
    /// A pose run: goals may carry an orientation.
    pose: bool,
    workspace_m: f64,
    admission: StateAdmission,
    clock: Clock,
}

impl SessionCommands {
    /// The checks of a session of `robot_id`, moving in `dim` dimensions in the box `[-workspace_m, workspace_m]`;
    /// its states are stamped against `clock`.
    pub(crate) fn new(
        robot_id: String,
        dim: usize,
        pose: bool,
        workspace_m: f64,
        admission: StateAdmission,
        clock: Clock,
    ) -> Self {
        Self { robot_id, dim, pose, workspace_m, admission, clock }
    }

    /// The command of one message (None: an empty message), or the warning that rejects it.
    pub(crate) fn control(&self, message: Option<Message>) -> Control {
        match message {
            Some(Message::SetGoal(g)) => {
                self.goal(g.goal, &g.goal_orientation).unwrap_or_else(|e| rejected("set_goal", &e))
            }
            Some(Message::SetTau(t)) => match check_tau("tau", t.tau) {
                Ok(()) => Control::SetTau(t.tau),
                Err(e) => rejected("set_tau", &e),
            },
            Some(Message::Pause(_)) => Control::Pause,
            Some(Message::Resume(_)) => Control::Resume,
            Some(Message::Stop(_)) => Control::Stop,
            Some(Message::State(s)) => self.state(s),
            Some(Message::Start(_)) => Control::Rejected(warning(
                Kind::CommandRejected,
                "start".into(),
                "the session has started already: `start` is only its first message".into(),
            )),
            None => Control::Rejected(warning(
                Kind::CommandRejected,
                "message".into(),
                "is empty: one of state, set_goal, set_tau, pause, resume or stop is required".into(),
            )),
        }
    }

    fn goal(&self, goal: Vec<f64>, orientation: &[f64]) -> Result<Control, WireError> {
        let orientation = match orientation {
            [] => None,
            _ if !self.pose => {
                return Err(WireError::new(
                    "goal_orientation",
                    "the run has no orientation (a position primitive)",
                ));
            }
            &[x, y, z, w] => {
                dmp::orientation::quaternion::from_xyzw("goal_orientation", [x, y, z, w])?;
                Some([x, y, z, w])
            }
            other => {
                return Err(WireError::new(
                    "goal_orientation",
                    format!("must be empty or 4 numbers (x, y, z, w), found {}", other.len()),
                ));
            }
        };
        // An orientation alone keeps the position goal.
        if !(goal.is_empty() && orientation.is_some()) {
            check_vector("goal", &goal, self.dim)?;
            check_in_workspace("goal", &goal, self.workspace_m)?;
        }
        Ok(Control::SetGoal(goal, orientation))
    }

    /// The robot's measured state, named after the session's robot: published, or rejected (malformed, or of
    /// another dimension), or dropped (out of the admitted stamps, positions and speeds).
    fn state(&self, mut s: v1::RobotState) -> Control {
        s.robot_id.clone_from(&self.robot_id);
        if let Err(e) = check_robot_state(&s).and_then(|_| check_vector("position", &s.position, self.dim)) {
            return rejected("state", &e);
        }
        match self.admission.admit(&s, self.clock.now_unix_s()) {
            Ok(()) => Control::State(s),
            Err(e) => Control::Rejected(warning(Kind::StateDropped, format!("state.{}", e.field), e.rule)),
        }
    }
}

/// The rejection of a command for `e`, a fault in the command's field (`command.field`).
pub(crate) fn rejected(command: &str, e: &WireError) -> Control {
    Control::Rejected(warning(Kind::CommandRejected, format!("{command}.{}", e.field), e.rule.clone()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::RequestLimits;

    fn commands() -> SessionCommands {
        let limits = RequestLimits { workspace_m: 10.0, ..RequestLimits::default() };
        SessionCommands::new(
            "r1".into(),
            3,
            false,
            limits.workspace_m,
            StateAdmission::new(&limits),
            Clock::system(),
        )
    }

    /// The warning of a rejected command: its kind and field.
    fn rejection(c: Control) -> (Kind, String) {
        match c {
            Control::Rejected(w) => (w.kind(), w.field),
            other => panic!("not rejected: {other:?}"),
        }
    }

    fn state(stamp: f64, x: f64) -> v1::RobotState {
        v1::RobotState {
            robot_id: "someone-else".into(),
            stamp_unix_s: stamp,
            position: vec![x, 0.0, 0.0],
            velocity: vec![0.0; 3],
            footprint: None,
            ..Default::default()
        }
    }

    #[test]
    fn valid_commands_pass() {
        let c = commands();
        assert!(
            matches!(c.control(Some(Message::SetGoal(v1::SetGoal { goal: vec![1.0, -2.0, 9.5], ..Default::default() }))),
            Control::SetGoal(g, None) if g == [1.0, -2.0, 9.5])
        );
        assert!(matches!(c.control(Some(Message::SetTau(v1::SetTau { tau: 2.0 }))), Control::SetTau(2.0)));
        assert!(matches!(c.control(Some(Message::Pause(v1::Pause {}))), Control::Pause));
        assert!(matches!(c.control(Some(Message::Resume(v1::Resume {}))), Control::Resume));
        assert!(matches!(c.control(Some(Message::Stop(v1::Stop {}))), Control::Stop));
        let now = crate::clock::system_unix_s();
        match c.control(Some(Message::State(state(now, 1.0)))) {
            Control::State(s) => assert_eq!(s.robot_id, "r1", "named after the session's robot"),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn bad_commands_are_rejected_naming_the_field() {
        let c = commands();
        let goal =
            |goal: Vec<f64>| c.control(Some(Message::SetGoal(v1::SetGoal { goal, ..Default::default() })));
        let tau = |tau: f64| c.control(Some(Message::SetTau(v1::SetTau { tau })));
        let rejected = |field: &str| (Kind::CommandRejected, field.to_owned());
        assert_eq!(rejection(goal(vec![0.0, 0.0, f64::NAN])), rejected("set_goal.goal[2]"));
        assert_eq!(rejection(goal(vec![0.0, 0.0])), rejected("set_goal.goal"));
        assert_eq!(rejection(goal(vec![0.0, 11.0, 0.0])), rejected("set_goal.goal[1]"));
        for bad in [0.0, 1e-300, -1.0, f64::NAN, f64::INFINITY, 1e9] {
            assert_eq!(rejection(tau(bad)), rejected("set_tau.tau"), "tau {bad}");
        }
        assert_eq!(rejection(c.control(None)), rejected("message"));
        let start = Message::Start(v1::ExecuteRequest::default());
        assert_eq!(rejection(c.control(Some(start))), rejected("start"));
        let now = crate::clock::system_unix_s();
        let mut s = state(now, f64::NAN);
        assert_eq!(rejection(c.control(Some(Message::State(s.clone())))), rejected("state.position[0]"));
        s = state(now, 1.0);
        s.position.pop();
        s.velocity.pop();
        assert_eq!(rejection(c.control(Some(Message::State(s)))), rejected("state.position"));
    }

    #[test]
    fn states_out_of_bounds_are_dropped_and_counted() {
        let c = commands();
        let now = crate::clock::system_unix_s();
        let dropped = |field: &str| (Kind::StateDropped, field.to_owned());
        assert_eq!(
            rejection(c.control(Some(Message::State(state(now + 1e7, 1.0))))),
            dropped("state.stamp_unix_s")
        );
        assert_eq!(
            rejection(c.control(Some(Message::State(state(now, 10.5))))),
            dropped("state.position[0]")
        );
        assert_eq!(c.admission.dropped(), 2);
    }
}
