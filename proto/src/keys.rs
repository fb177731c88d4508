//! The Zenoh key expressions of a cell, built and parsed here only, and the one rule for the names they hold.
//!
//! | key | payload |
//! | --- | --- |
//! | `dmp/<cell>/obstacles/<obstacle-id>` | `dmp.v1.Obstacle` (encoding `application/protobuf`) or the JSON obstacle ([`crate::obstacle_json`]); a delete removes it |
//! | `dmp/<cell>/robots/<robot-id>/state` | `dmp.v1.RobotState` (protobuf); a delete forgets the robot |
//! | `dmp/<cell>/robots/<robot-id>/alive` | a Zenoh liveliness token of the robot's publisher: when it goes, the robot goes |
//!
//! [`EVERY_CELL`] in place of a cell (or `*` in place of an id) makes the expression that a subscriber declares.

use crate::WireError;

/// The first chunk of every key.
pub const ROOT: &str = "dmp";

/// The chunk that stands for every cell (or every id) in a subscriber's key expression.
pub const EVERY_CELL: &str = "*";

/// Longest name (cell, robot id, obstacle id, primitive name).
pub const MAX_NAME_CHARS: usize = 128;

/// Checks a name that goes into a key or a path (a cell, a robot id, an obstacle id published over Zenoh, a
/// primitive name): 1 to [`MAX_NAME_CHARS`] characters of `[A-Za-z0-9_.-]`.
pub fn check_name(field: &str, s: &str) -> Result<(), WireError> {
    if s.is_empty() || s.len() > MAX_NAME_CHARS {
        return Err(WireError::new(field, format!("must have 1 to {MAX_NAME_CHARS} characters")));
    }
    if let Some(c) = s.chars().find(|c| !(c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'))) {
        return Err(WireError::new(
            field,
            format!("has `{c}`: only letters, digits, `_`, `-` and `.` are allowed"),
        ));
    }
    Ok(())
}

/// The key of one obstacle: `dmp/<cell>/obstacles/<obstacle-id>`.
pub fn obstacle_key(cell: &str, obstacle_id: &str) -> String {
    format!("{ROOT}/{cell}/obstacles/{obstacle_id}")
}

/// The expression of every obstacle of `cell` ([`EVERY_CELL`]: of every cell): `dmp/<cell>/obstacles/*`.
pub fn obstacles_of(cell: &str) -> String {
    obstacle_key(cell, "*")
}

/// The key of one robot's state: `dmp/<cell>/robots/<robot-id>/state`.
pub fn robot_state_key(cell: &str, robot_id: &str) -> String {
    format!("{ROOT}/{cell}/robots/{robot_id}/state")
}

/// The expression of every robot state of `cell` ([`EVERY_CELL`]: of every cell): `dmp/<cell>/robots/*/state`.
pub fn robot_states_of(cell: &str) -> String {
    robot_state_key(cell, "*")
}

/// The key of the liveliness token that whoever publishes a robot's states declares:
/// `dmp/<cell>/robots/<robot-id>/alive`.
pub fn robot_alive_key(cell: &str, robot_id: &str) -> String {
    format!("{ROOT}/{cell}/robots/{robot_id}/alive")
}

/// The expression of every robot's liveliness token of `cell` ([`EVERY_CELL`]: of every cell):
/// `dmp/<cell>/robots/*/alive`.
pub fn robots_alive_of(cell: &str) -> String {
    robot_alive_key(cell, "*")
}

/// The names a key holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct KeyNames<'a> {
    /// The cell.
    pub cell: &'a str,
    /// The obstacle's or the robot's id.
    pub id: &'a str,
}

/// The cell and obstacle id of `dmp/<cell>/obstacles/<obstacle-id>`; None for any other key.
pub fn parse_obstacle_key(key: &str) -> Option<KeyNames<'_>> {
    match key.split('/').collect::<Vec<_>>()[..] {
        [ROOT, cell, "obstacles", id] => Some(KeyNames { cell, id }),
        _ => None,
    }
}

/// The cell and robot id of `dmp/<cell>/robots/<robot-id>/state`; None for any other key.
pub fn parse_robot_state_key(key: &str) -> Option<KeyNames<'_>> {
    match key.split('/').collect::<Vec<_>>()[..] {
        [ROOT, cell, "robots", id, "state"] => Some(KeyNames { cell, id }),
        _ => None,
    }
}

/// The cell and robot id of `dmp/<cell>/robots/<robot-id>/alive`; None for any other key.
pub fn parse_robot_alive_key(key: &str) -> Option<KeyNames<'_>> {
    match key.split('/').collect::<Vec<_>>()[..] {
        [ROOT, cell, "robots", id, "alive"] => Some(KeyNames { cell, id }),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_checked() {
        assert!(check_name("robot_id", "panda-1.left_arm").is_ok());
        assert!(check_name("robot_id", "").is_err());
        assert!(check_name("robot_id", "a/b").is_err());
        assert!(check_name("robot_id", "a*").is_err());
        assert!(check_name("robot_id", &"x".repeat(129)).is_err());
        assert_eq!(check_name("cell", "a b").unwrap_err().field, "cell");
    }

    #[test]
    fn keys_are_built_and_parsed_back() {
        assert_eq!(obstacle_key("c1", "box1"), "dmp/c1/obstacles/box1");
        assert_eq!(robot_state_key("c1", "r1"), "dmp/c1/robots/r1/state");
        assert_eq!(obstacles_of(EVERY_CELL), "dmp/*/obstacles/*");
        assert_eq!(robot_states_of("c1"), "dmp/c1/robots/*/state");
        let names = KeyNames { cell: "c1", id: "box1" };
        assert_eq!(parse_obstacle_key(&obstacle_key("c1", "box1")), Some(names));
        let names = KeyNames { cell: "c1", id: "r1" };
        assert_eq!(parse_robot_state_key(&robot_state_key("c1", "r1")), Some(names));
        assert_eq!(parse_obstacle_key(&robot_state_key("c1", "r1")), None);
        assert_eq!(robot_alive_key("c1", "r1"), "dmp/c1/robots/r1/alive");
        assert_eq!(robots_alive_of(EVERY_CELL), "dmp/*/robots/*/alive");
        assert_eq!(parse_robot_alive_key(&robot_alive_key("c1", "r1")), Some(names));
        assert_eq!(parse_robot_alive_key(&robot_state_key("c1", "r1")), None);
        assert_eq!(parse_robot_state_key(&robot_alive_key("c1", "r1")), None);
        assert_eq!(parse_robot_state_key(&obstacle_key("c1", "box1")), None);
        assert_eq!(parse_obstacle_key("dmp/c1/obstacles/a/b"), None);
        assert_eq!(parse_obstacle_key("other/c1/obstacles/a"), None);
    }
}
