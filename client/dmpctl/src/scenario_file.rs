//! Reading scenario files (SPEC.md): JSON, read leniently enough (JSON5) that a `NaN` written by a careless
//! exporter is reported as a bad value at its field rather than as a syntax error.

use std::path::Path;

use dmp::scenario::Scenario;

use crate::error::DmpctlError;

/// Parses a scenario from text; `path` only names the source in errors.
pub fn parse_scenario(text: &str, path: &Path) -> Result<Scenario, DmpctlError> {
    let mut de = json5::Deserializer::from_str(text);
    serde_path_to_error::deserialize(&mut de).map_err(|e| {
        let field = e.path().to_string();
        let field = if field == "." || field.is_empty() { "(document)".to_string() } else { field };
        DmpctlError::Parse { path: path.to_path_buf(), field, message: e.into_inner().to_string() }
    })
}

/// Reads and parses a scenario file.
pub fn load_scenario(path: &Path) -> Result<Scenario, DmpctlError> {
    let text = std::fs::read_to_string(path)
        .map_err(|source| DmpctlError::Io { path: path.to_path_buf(), source })?;
    parse_scenario(&text, path)
}

/// Reads, parses and validates a scenario file, and learns its primitive.
pub fn prepare_scenario(path: &Path) -> Result<dmp::scenario::Prepared, DmpctlError> {
    let scenario = load_scenario(path)?;
    dmp::scenario::prepare(&scenario)
        .map_err(|source| DmpctlError::Invalid { path: path.to_path_buf(), source })
}
