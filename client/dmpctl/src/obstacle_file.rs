//! Obstacles read from a JSON file, by `scene put` (one obstacle, or a file whose `obstacles` are all put) and by
//! `scenario run` (a scenario's `obstacles`): one reading, so the same broken obstacle gives the same error either
//! way, `FILE:LINE:COLUMN: FIELD: REASON`.

use std::path::Path;

use dmp_proto::obstacle_json::JsonObstacle;
use serde_json::Value;

use crate::error::DmpctlError;
use crate::json_non_finite::json_error;
use crate::json_position::locate;

/// A parse error at `field` of the file at `path`, pointing at the value's line and column in `text` when found.
pub(crate) fn error_at(path: &Path, text: &str, field: String, message: String) -> DmpctlError {
    let position = locate(text, &field);
    DmpctlError::Parse { path: path.to_path_buf(), position, field, message }
}

/// The obstacles of `text` (the file at `path`): the entries of its `obstacles`, or the whole document as one
/// obstacle; each parsed and checked, the first error naming its field. `ttl_s` replaces each one's `ttl_s`.
pub(crate) fn obstacles_of(
    text: &str,
    path: &Path,
    ttl_s: Option<f64>,
) -> Result<Vec<JsonObstacle>, DmpctlError> {
    let value: Value = serde_json::from_str(text).map_err(|e| json_error(path, text, &e))?;
    let out = match value.get("obstacles") {
        Some(Value::Array(list)) => listed(text, path, list, ttl_s)?,
        Some(_) => return Err(error_at(path, text, "obstacles".into(), "must be an array".into())),
        None => vec![one(text, path, &value, String::new(), ttl_s)?],
    };
    if out.is_empty() {
        return Err(error_at(path, text, "obstacles".into(), "the file has no obstacles".into()));
    }
    Ok(out)
}

/// Checks the `obstacles` of a scenario's text as [`obstacles_of`] reads them; a text that is not plain JSON
/// (e.g. JSON5 with a `NaN`) is left to the scenario's own reading.
pub(crate) fn check_scenario_obstacles(text: &str, path: &Path) -> Result<(), DmpctlError> {
    let Ok(value) = serde_json::from_str::<Value>(text) else { return Ok(()) };
    if let Some(Value::Array(list)) = value.get("obstacles") {
        listed(text, path, list, None)?;
    }
    Ok(())
}

fn listed(
    text: &str,
    path: &Path,
    list: &[Value],
    ttl_s: Option<f64>,
) -> Result<Vec<JsonObstacle>, DmpctlError> {
    list.iter().enumerate().map(|(i, v)| one(text, path, v, format!("obstacles[{i}]"), ttl_s)).collect()
}

fn one(
    text: &str,
    path: &Path,
    value: &Value,
    prefix: String,
    ttl_s: Option<f64>,
) -> Result<JsonObstacle, DmpctlError> {
    let mut o = JsonObstacle::parse(value, &prefix).map_err(|e| error_at(path, text, e.field, e.rule))?;
    if let Some(ttl) = ttl_s {
        o.ttl_s = ttl;
    }
    o.validate().map_err(|e| {
        let e = if prefix.is_empty() { e } else { e.within(&prefix) };
        error_at(path, text, e.field, e.rule)
    })?;
    Ok(o)
}
