//! Roles and what each may do: the one table that every request is checked against.

use serde::{Deserialize, Serialize};

/// What an identity is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub(crate) enum Role {
    /// The cell's planner: primitives of its robots; plan and execute any robot of its cells; change the scene of
    /// its cells; everything an observer reads.
    Planner,
    /// A robot: plans, executes and sessions only as its own robot ids; reads its own primitives.
    Robot,
    /// A perception node: changes (and reads) the scene of its cells, over gRPC or Zenoh.
    Perception,
    /// Reads: primitives, scenes, stats, reflection.
    Observer,
    /// Everything.
    Admin,
    /// Another server of the plant: over Zenoh, publishes its robots' states and reads the cells' keys; over gRPC,
    /// reads as an observer.
    Server,
}

impl Role {
    /// The role's name, as in the access file.
    pub(crate) fn as_str(self) -> &'static str {
        match self {
            Role::Planner => "planner",
            Role::Robot => "robot",
            Role::Perception => "perception",
            Role::Observer => "observer",
            Role::Admin => "admin",
            Role::Server => "server",
        }
    }
}

impl std::fmt::Display for Role {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// What a request does, with the cell and robots it acts on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Action<'a> {
    /// Learn or put a primitive of `robot`.
    WritePrimitive {
        /// The robot.
        robot: &'a str,
    },
    /// Delete a primitive of `robot`.
    DeletePrimitive {
        /// The robot.
        robot: &'a str,
    },
    /// Get or list the primitives of `robot`.
    ReadPrimitive {
        /// The robot.
        robot: &'a str,
    },
    /// Plan a motion of `robots` in `cell` (answers only, moves nothing).
    Plan {
        /// The cell.
        cell: &'a str,
        /// The robots.
        robots: &'a [&'a str],
    },
    /// Execute `robots` in `cell`: Execute, Session and ExecuteGroup, and the commands of a session.
    Execute {
        /// The cell.
        cell: &'a str,
        /// The robots.
        robots: &'a [&'a str],
    },
    /// Put or delete obstacles of `cell`.
    ChangeScene {
        /// The cell.
        cell: &'a str,
    },
    /// List or watch the obstacles of `cell`.
    ReadScene {
        /// The cell.
        cell: &'a str,
    },
    /// The server's counters.
    Stats,
    /// gRPC reflection (the services' descriptions).
    Reflection,
}

impl Action<'_> {
    /// Its kind, without its robots and cells: what the audit log's refusals are counted by.
    pub(crate) fn kind(&self) -> &'static str {
        match self {
            Action::WritePrimitive { .. } => "write primitive",
            Action::DeletePrimitive { .. } => "delete primitive",
            Action::ReadPrimitive { .. } => "read primitive",
            Action::Plan { .. } => "plan",
            Action::Execute { .. } => "execute",
            Action::ChangeScene { .. } => "change scene",
            Action::ReadScene { .. } => "read scene",
            Action::Stats => "stats",
            Action::Reflection => "reflection",
        }
    }

    /// The action in words, for refusals and the audit log: `execute robot `r1` in cell `a``.
    pub(crate) fn describe(&self) -> String {
        let robots = |rs: &[&str]| match rs {
            [one] => format!("robot `{one}`"),
            many => {
                format!("robots {}", many.iter().map(|r| format!("`{r}`")).collect::<Vec<_>>().join(", "))
            }
        };
        match self {
            Action::WritePrimitive { robot } => format!("write the primitives of robot `{robot}`"),
            Action::DeletePrimitive { robot } => format!("delete the primitives of robot `{robot}`"),
            Action::ReadPrimitive { robot } => format!("read the primitives of robot `{robot}`"),
            Action::Plan { cell, robots: rs } => format!("plan {} in cell `{cell}`", robots(rs)),
            Action::Execute { cell, robots: rs } => format!("execute {} in cell `{cell}`", robots(rs)),
            Action::ChangeScene { cell } => format!("change the scene of cell `{cell}`"),
            Action::ReadScene { cell } => format!("read the scene of cell `{cell}`"),
            Action::Stats => "read the server's stats".into(),
            Action::Reflection => "use gRPC reflection".into(),
        }
    }
}

/// The end of a robot entry that names every robot id starting with what comes before it (`sim.*`: `sim.panda`,
/// `sim.youbot1` ...).
pub(crate) const PREFIX_WILDCARD: &str = "*";

/// Whether the robot entry `entry` (an id, or a prefix ending in [`PREFIX_WILDCARD`]) names `robot`.
fn names_robot(entry: &str, robot: &str) -> bool {
    match entry.strip_suffix(PREFIX_WILDCARD) {
        Some(prefix) => robot.starts_with(prefix),
        None => entry == robot,
    }
}

/// The cells and robots an identity may act on.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub(crate) struct Scope {
    /// Its cells; `*` is every cell.
    pub cells: Vec<String>,
    /// Its robots, each an id or a prefix ending in `*` (`sim.*`); empty is every robot of its cells.
    pub robots: Vec<String>,
}

impl Scope {
    /// Whether `cell` is one of its cells.
    pub(crate) fn has_cell(&self, cell: &str) -> bool {
        self.cells.iter().any(|c| c == "*" || c == cell)
    }

    /// Whether `robot` is one of its robots (every robot when none is listed).
    pub(crate) fn has_robot(&self, robot: &str) -> bool {
        self.robots.is_empty() || self.robots.iter().any(|r| names_robot(r, robot))
    }

    /// Whether the primitives of `robot` are its own. Primitives belong to a robot, not to a cell: an identity that
    /// lists its robots has theirs; one that lists none has every robot's only when its cells are `*` (listing
    /// none in some cells does not give other cells' robots' primitives).
    pub(crate) fn has_primitives_of(&self, robot: &str) -> bool {
        if self.robots.is_empty() {
            self.cells.iter().any(|c| c == "*")
        } else {
            self.robots.iter().any(|r| names_robot(r, robot))
        }
    }

    fn has_robots(&self, robots: &[&str]) -> bool {
        robots.iter().all(|r| self.has_robot(r))
    }
}

/// Whether `role` within `scope` may do `action`.
pub(crate) fn allows(role: Role, scope: &Scope, action: &Action<'_>) -> bool {
    use Action as A;
    match role {
        Role::Admin => true,
        Role::Planner => match action {
            A::WritePrimitive { robot } | A::DeletePrimitive { robot } | A::ReadPrimitive { robot } => {
                scope.has_primitives_of(robot)
            }
            A::Plan { cell, robots } | A::Execute { cell, robots } => {
                scope.has_cell(cell) && scope.has_robots(robots)
            }
            A::ChangeScene { cell } | A::ReadScene { cell } => scope.has_cell(cell),
            A::Stats | A::Reflection => true,
        },
        Role::Robot => match action {
            A::ReadPrimitive { robot } => scope.has_primitives_of(robot),
            A::Plan { cell, robots } | A::Execute { cell, robots } => {
                scope.has_cell(cell) && scope.has_robots(robots)
            }
            _ => false,
        },
        Role::Perception => match action {
            A::ChangeScene { cell } | A::ReadScene { cell } => scope.has_cell(cell),
            _ => false,
        },
        Role::Observer | Role::Server => match action {
            A::ReadPrimitive { robot } => scope.has_primitives_of(robot),
            A::ReadScene { cell } => scope.has_cell(cell),
            A::Stats | A::Reflection => true,
            _ => false,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scope(cells: &[&str], robots: &[&str]) -> Scope {
        Scope {
            cells: cells.iter().map(|s| s.to_string()).collect(),
            robots: robots.iter().map(|s| s.to_string()).collect(),
        }
    }

    #[test]
    fn a_prefix_grants_the_robots_it_starts_and_refuses_the_others() {
        let s = scope(&["a"], &["panda-1", "sim.*"]);
        for robot in ["sim.panda", "sim.youbot1", "panda-1"] {
            assert!(allows(Role::Planner, &s, &Action::Execute { cell: "a", robots: &[robot] }), "{robot}");
            assert!(allows(Role::Planner, &s, &Action::WritePrimitive { robot }), "{robot}");
        }
        for robot in ["simulated", "sim", "panda-2", "xsim.panda"] {
            assert!(!allows(Role::Planner, &s, &Action::Execute { cell: "a", robots: &[robot] }), "{robot}");
            assert!(!allows(Role::Planner, &s, &Action::WritePrimitive { robot }), "{robot}");
        }
        assert!(!allows(
            Role::Planner,
            &s,
            &Action::Execute { cell: "a", robots: &["sim.panda", "panda-2"] }
        ));
    }

    #[test]
    fn a_robot_acts_only_as_itself_in_its_cells() {
        let s = scope(&["a"], &["panda-1"]);
        assert!(allows(Role::Robot, &s, &Action::Execute { cell: "a", robots: &["panda-1"] }));
        assert!(!allows(Role::Robot, &s, &Action::Execute { cell: "a", robots: &["panda-2"] }));
        assert!(!allows(Role::Robot, &s, &Action::Execute { cell: "a", robots: &["panda-1", "panda-2"] }));
        assert!(!allows(Role::Robot, &s, &Action::Execute { cell: "b", robots: &["panda-1"] }));
        assert!(allows(Role::Robot, &s, &Action::ReadPrimitive { robot: "panda-1" }));
        assert!(!allows(Role::Robot, &s, &Action::WritePrimitive { robot: "panda-1" }));
        assert!(!allows(Role::Robot, &s, &Action::ChangeScene { cell: "a" }));
    }

    #[test]
    fn cells_and_robots_scope_the_planner_and_a_star_is_every_cell() {
        let s = scope(&["a"], &[]);
        assert!(allows(Role::Planner, &s, &Action::Execute { cell: "a", robots: &["x", "y"] }));
        assert!(!allows(Role::Planner, &s, &Action::Execute { cell: "b", robots: &["x"] }));
        // Primitives have no cell: a planner of cell a that lists no robot may not write any robot's.
        assert!(!allows(Role::Planner, &s, &Action::DeletePrimitive { robot: "anyone" }));
        assert!(!allows(Role::Observer, &s, &Action::ReadPrimitive { robot: "anyone" }));
        assert!(allows(Role::Planner, &scope(&["*"], &[]), &Action::DeletePrimitive { robot: "anyone" }));
        let limited = scope(&["*"], &["x"]);
        assert!(allows(Role::Planner, &limited, &Action::Plan { cell: "z", robots: &["x"] }));
        assert!(!allows(Role::Planner, &limited, &Action::Plan { cell: "z", robots: &["y"] }));
        assert!(!allows(Role::Planner, &limited, &Action::WritePrimitive { robot: "y" }));
    }

    #[test]
    fn perception_changes_scenes_and_observers_only_read() {
        let s = scope(&["a"], &[]);
        assert!(allows(Role::Perception, &s, &Action::ChangeScene { cell: "a" }));
        assert!(!allows(Role::Perception, &s, &Action::ChangeScene { cell: "b" }));
        assert!(!allows(Role::Perception, &s, &Action::Stats));
        assert!(!allows(Role::Observer, &s, &Action::ChangeScene { cell: "a" }));
        assert!(allows(Role::Observer, &s, &Action::ReadScene { cell: "a" }));
        assert!(allows(Role::Observer, &s, &Action::Stats));
        assert!(!allows(Role::Observer, &s, &Action::Plan { cell: "a", robots: &["r"] }));
        assert!(allows(Role::Admin, &Scope::default(), &Action::Execute { cell: "q", robots: &["r"] }));
    }

    #[test]
    fn actions_are_described_with_their_cell_and_robots() {
        assert_eq!(
            Action::Execute { cell: "a", robots: &["r1", "r2"] }.describe(),
            "execute robots `r1`, `r2` in cell `a`"
        );
        assert_eq!(Action::ChangeScene { cell: "a" }.describe(), "change the scene of cell `a`");
    }
}
