//! Changes made during a `dmpctl stream`: a schedule on the run's clock (`--goal-at T=X,Y`, `--tau-at T=TAU`,
//! `--stop-at T`) and commands typed on stdin (`--stdin`: `goal X Y Z`, `tau T`, `pause`, `resume`, `stop`). They
//! go to the server as the session's commands (`MotionService.Session`), as the Python client sends them.

use dmp_client::grpc::SessionSender;
use tokio::sync::mpsc;

use crate::args::{GoalAt, TauAt, finite_number, positive_number};
use crate::error::DmpctlError;

/// One change to a running stream.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Command {
    /// A new goal (the position; as many values as the primitive's dimension).
    Goal(Vec<f64>),
    /// A new time scale, seconds (larger is slower).
    Tau(f64),
    /// Hold position.
    Pause,
    /// Go on after a pause.
    Resume,
    /// Decelerate to rest and end the run.
    Stop,
}

impl Command {
    /// Sends it on the session.
    pub(crate) async fn send(&self, session: &SessionSender) -> Result<(), DmpctlError> {
        match self {
            Command::Goal(g) => session.set_goal(g.clone()).await?,
            Command::Tau(t) => session.set_tau(*t).await?,
            Command::Pause => session.pause().await?,
            Command::Resume => session.resume().await?,
            Command::Stop => session.stop().await?,
        }
        Ok(())
    }

    /// How it reads in the stderr line that says it was sent (`goal 0.5 1`).
    pub(crate) fn words(&self) -> String {
        match self {
            Command::Goal(g) => {
                format!("goal {}", g.iter().map(f64::to_string).collect::<Vec<_>>().join(" "))
            }
            Command::Tau(t) => format!("tau {t}"),
            Command::Pause => "pause".into(),
            Command::Resume => "resume".into(),
            Command::Stop => "stop".into(),
        }
    }
}

/// What a line of stdin may say.
const STDIN_COMMANDS: &str = "`goal X Y [Z ...]`, `tau SECONDS`, `pause`, `resume` or `stop`";

/// A line of stdin as a command; `None` for a blank line or a `#` comment. The error says what is wrong and what a
/// line may say.
pub(crate) fn parse_line(line: &str) -> Result<Option<Command>, String> {
    let line = line.trim();
    if line.is_empty() || line.starts_with('#') {
        return Ok(None);
    }
    let mut words = line.split_whitespace();
    let verb = words.next().unwrap_or_default();
    let args: Vec<&str> = words.collect();
    let none = |c: Command| {
        if args.is_empty() { Ok(Some(c)) } else { Err(format!("`{verb}` takes no value")) }
    };
    match verb {
        "goal" => {
            if args.is_empty() {
                return Err("`goal` needs the goal's coordinates, e.g. `goal 0.5 1 0`".into());
            }
            let g = args
                .iter()
                .enumerate()
                .map(|(i, a)| finite_number(a.trim_end_matches(','), &format!("coordinate {}", i + 1)))
                .collect::<Result<Vec<_>, _>>()?;
            Ok(Some(Command::Goal(g)))
        }
        "tau" => match args.as_slice() {
            [t] => Ok(Some(Command::Tau(positive_number(t, "tau")?))),
            _ => Err("`tau` takes one value, seconds, e.g. `tau 2`".into()),
        },
        "pause" => none(Command::Pause),
        "resume" => none(Command::Resume),
        "stop" => none(Command::Stop),
        _ => Err(format!("unknown command `{verb}`, expected {STDIN_COMMANDS}")),
    }
}

/// The scheduled changes, in time order; each is due once the run's time reaches its own.
#[derive(Debug, Default)]
pub(crate) struct Schedule {
    /// Not yet due, latest first (so the next one is popped from the end).
    pending: Vec<(f64, Command)>,
}

impl Schedule {
    /// The schedule of the flags.
    pub(crate) fn new(goals: &[GoalAt], taus: &[TauAt], stop: Option<f64>) -> Self {
        let mut pending: Vec<(f64, Command)> = goals
            .iter()
            .map(|g| (g.0, Command::Goal(g.1.clone())))
            .chain(taus.iter().map(|t| (t.0, Command::Tau(t.1))))
            .chain(stop.map(|t| (t, Command::Stop)))
            .collect();
        // A stable sort keeps the flags' order at equal times (goals, then taus, then the stop); reversed, the next
        // one due is popped from the end.
        pending.sort_by(|a, b| a.0.total_cmp(&b.0));
        pending.reverse();
        Self { pending }
    }

    /// Whether nothing is scheduled.
    pub(crate) fn is_empty(&self) -> bool {
        self.pending.is_empty()
    }

    /// The commands due at the run's time `t`, in order.
    pub(crate) fn due(&mut self, t: f64) -> Vec<(f64, Command)> {
        let mut due = Vec::new();
        while self.pending.last().is_some_and(|(at, _)| *at <= t) {
            due.extend(self.pending.pop());
        }
        due
    }
}

/// Reads stdin on a thread of its own (a blocking read cannot be cancelled; the thread ends with the process):
/// each command on the returned channel, each bad line reported on stderr, naming it, and skipped. The channel
/// closes at the end of stdin.
pub(crate) fn read_stdin() -> mpsc::Receiver<Command> {
    let (tx, rx) = mpsc::channel(16);
    std::thread::spawn(move || {
        use std::io::BufRead;
        for (n, line) in std::io::stdin().lock().lines().enumerate() {
            let Ok(line) = line else { break };
            match parse_line(&line) {
                Ok(Some(c)) => {
                    if tx.blocking_send(c).is_err() {
                        break;
                    }
                }
                Ok(None) => {}
                Err(e) => eprintln!("dmpctl: stdin line {} `{}` ignored: {e}", n + 1, line.trim()),
            }
        }
    });
    rx
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stdin_lines_read_as_commands() {
        assert_eq!(parse_line("goal 0.5 1 -2"), Ok(Some(Command::Goal(vec![0.5, 1.0, -2.0]))));
        assert_eq!(parse_line("  tau 2.5 "), Ok(Some(Command::Tau(2.5))));
        assert_eq!(parse_line("pause"), Ok(Some(Command::Pause)));
        assert_eq!(parse_line("resume"), Ok(Some(Command::Resume)));
        assert_eq!(parse_line("stop"), Ok(Some(Command::Stop)));
        assert_eq!(parse_line(""), Ok(None));
        assert_eq!(parse_line("# a comment"), Ok(None));
    }

    #[test]
    fn bad_lines_say_what_is_wrong() {
        let e = parse_line("jump 1").unwrap_err();
        assert!(e.contains("unknown command `jump`") && e.contains("`pause`"), "{e}");
        assert!(parse_line("goal 1 x").unwrap_err().contains("coordinate 2 `x`"));
        assert!(parse_line("goal").unwrap_err().contains("needs the goal's coordinates"));
        assert!(parse_line("tau -1").unwrap_err().contains("greater than zero"));
        assert!(parse_line("tau 1 2").unwrap_err().contains("one value"));
        assert!(parse_line("stop now").unwrap_err().contains("takes no value"));
    }

    #[test]
    fn the_schedule_gives_each_command_once_when_due_in_order() {
        let mut s =
            Schedule::new(&[GoalAt(0.5, vec![1.0]), GoalAt(0.2, vec![2.0])], &[TauAt(0.5, 3.0)], Some(0.9));
        assert!(s.due(0.1).is_empty());
        assert_eq!(s.due(0.2), vec![(0.2, Command::Goal(vec![2.0]))]);
        assert_eq!(s.due(0.6), vec![(0.5, Command::Goal(vec![1.0])), (0.5, Command::Tau(3.0))]);
        assert!(!s.is_empty());
        assert_eq!(s.due(5.0), vec![(0.9, Command::Stop)]);
        assert!(s.is_empty() && s.due(10.0).is_empty());
    }
}
