//! The Zenoh key expressions of a cell, built and parsed here only, and the one rule for the names they hold.
//!
//! | key | payload |
//! | --- | --- |
//! | `dmp/<cell>/obstacles/<obstacle-id>` | `dmp.v1.Obstacle` (encoding `application/protobuf`) or the JSON obstacle ([`crate::obstacle_json`]); a delete removes it |
//! | `dmp/<cell>/robots/<robot-id>/state` | `dmp.v1.RobotState` (protobuf); a delete forgets the robot |
//! | `dmp/<cell>/robots/<robot-id>/alive` | a Zenoh liveliness token of the robot's publisher: when it goes, the robot goes |
//!
//! | `dmp/@servers/<server-id>` | a server's liveliness token, and its queryable answering `dmp.v1.PlantServer` |
//! | `dmp/@cells/<cell>` | the queryable of the server serving the cell, answering `dmp.v1.PlantServer` |
//! | `dmp/@primitives/<robot-id>/<name>/<version>` | `dmp.v1.PrimitiveRecord` (protobuf), one stored version, replicated between servers |
//! | `dmp/@primitives/<robot-id>/<name>/<version>` delete | a tombstone: every version of the primitive up to this one deleted |
//!
//! The plant's keys start with a verbatim chunk (`@...`): `dmp/*/...` and `dmp/**` do not match them, so the cells'
//! subscribers never see them and access rules name them explicitly.
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

/// The key of a server of a plant: its liveliness token and its queryable, `dmp/@servers/<server-id>`.
pub fn server_key(server_id: &str) -> String {
    format!("{ROOT}/@servers/{server_id}")
}

/// Every server's key: `dmp/@servers/*`.
pub fn every_server() -> String {
    server_key("*")
}

/// The server id of `dmp/@servers/<server-id>`; None for any other key.
pub fn parse_server_key(key: &str) -> Option<&str> {
    match key.split('/').collect::<Vec<_>>()[..] {
        [ROOT, "@servers", id] => Some(id),
        _ => None,
    }
}

/// The key a cell's server answers on: `dmp/@cells/<cell>`.
pub fn cell_server_key(cell: &str) -> String {
    format!("{ROOT}/@cells/{cell}")
}

/// The key of one replicated version of a primitive: `dmp/@primitives/<robot-id>/<name>/<version>`.
pub fn primitive_version_key(robot_id: &str, name: &str, version: u64) -> String {
    format!("{ROOT}/@primitives/{robot_id}/{name}/{version}")
}

/// The key of a primitive, every version (a delete): `dmp/@primitives/<robot-id>/<name>`.
pub fn primitive_key(robot_id: &str, name: &str) -> String {
    format!("{ROOT}/@primitives/{robot_id}/{name}")
}

/// Every replicated primitive: `dmp/@primitives/**`.
pub fn every_primitive() -> String {
    format!("{ROOT}/@primitives/**")
}

/// A primitive's key: robot id, name, and the version (None: every version).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PrimitiveKey<'a> {
    /// The robot.
    pub robot_id: &'a str,
    /// The primitive's name.
    pub name: &'a str,
    /// The version; None for the key of every version.
    pub version: Option<u64>,
}

/// The names of `dmp/@primitives/<robot-id>/<name>[/<version>]`; None for any other key.
pub fn parse_primitive_key(key: &str) -> Option<PrimitiveKey<'_>> {
    match key.split('/').collect::<Vec<_>>()[..] {
        [ROOT, "@primitives", robot_id, name] => Some(PrimitiveKey { robot_id, name, version: None }),
        [ROOT, "@primitives", robot_id, name, v] => {
            Some(PrimitiveKey { robot_id, name, version: Some(v.parse().ok()?) })
        }
        _ => None,
    }
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
        assert_eq!(parse_server_key(&server_key("s1")), Some("s1"));
        assert_eq!(every_server(), "dmp/@servers/*");
        assert_eq!(cell_server_key("a"), "dmp/@cells/a");
        let k = PrimitiveKey { robot_id: "r", name: "n", version: Some(7) };
        assert_eq!(parse_primitive_key(&primitive_version_key("r", "n", 7)), Some(k));
        let k = PrimitiveKey { version: None, ..k };
        assert_eq!(parse_primitive_key(&primitive_key("r", "n")), Some(k));
        assert_eq!(parse_primitive_key("dmp/@primitives/r/n/x"), None);
        assert_eq!(parse_primitive_key(&obstacle_key("c1", "box1")), None);
    }
}
