//! Reading scenario files (SPEC.md): JSON, read leniently enough (JSON5) that a `NaN` written by a careless
//! exporter is reported as a bad value at its field rather than as a syntax error.

use std::path::Path;

use dmp::scenario::Scenario;

use crate::error::DmpctlError;
use crate::json_position::without_position;
use crate::obstacle_file::{check_scenario_obstacles, error_at};

/// Parses a scenario from text; `path` only names the source in errors, which give the value's line and column.
/// Its obstacles are read as `scene put` reads them (`obstacle_file::check_scenario_obstacles`): the same broken
/// obstacle gives the same error.
pub fn parse_scenario(text: &str, path: &Path) -> Result<Scenario, DmpctlError> {
    let mut de = json5::Deserializer::from_str(text);
    let parsed: Result<Scenario, _> = serde_path_to_error::deserialize(&mut de);
    match parsed {
        Ok(scenario) => {
            check_scenario_obstacles(text, path)?;
            Ok(scenario)
        }
        Err(e) => {
            let field = e.path().to_string();
            let field = if field == "." || field.is_empty() { "(document)".to_string() } else { field };
            if field.starts_with("obstacles") {
                check_scenario_obstacles(text, path)?;
            }
            let message = e.into_inner().to_string();
            let mut error = error_at(path, text, field, without_position(&message));
            // Where the parser stopped, when the value could not be found (a syntax error).
            if let DmpctlError::Parse { position: p @ None, .. } = &mut error {
                *p = parser_position(&message);
            }
            Err(error)
        }
    }
}

/// `line L column C` at the end of a parser's message.
fn parser_position(message: &str) -> Option<(usize, usize)> {
    let rest = &message[message.rfind(" at line ")? + " at line ".len()..];
    let (line, column) = rest.split_once(" column ")?;
    Some((line.trim().parse().ok()?, column.trim().parse().ok()?))
}

/// Reads and parses a scenario file.
pub fn load_scenario(path: &Path) -> Result<Scenario, DmpctlError> {
    let text = std::fs::read_to_string(path)
        .map_err(|source| DmpctlError::Io { path: path.to_path_buf(), source })?;
    parse_scenario(&text, path)
}

/// Reads, parses and validates a scenario file, and learns its primitive.
pub(crate) fn prepare_scenario(path: &Path) -> Result<dmp::scenario::Prepared, DmpctlError> {
    let scenario = load_scenario(path)?;
    dmp::scenario::prepare(&scenario)
        .map_err(|source| DmpctlError::Invalid { path: path.to_path_buf(), source })
}
