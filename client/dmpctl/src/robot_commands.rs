//! `dmpctl robot put | show | delete`: a robot's record on the server (its limits, footprint and tool), the
//! defaults of its motion requests.

use std::path::Path;

use dmp::Limits;
use dmp_client::grpc::DmpClient;
use dmp_proto::limits::limits_to_proto;
use dmp_proto::v1;
use serde::Deserialize;
use serde_json::{Value, json};

use crate::error::DmpctlError;
use crate::json_non_finite::{json_error, non_finite_at};
use crate::outputs::to_json;

/// `--limits`: a profile name (`panda`, `psm`, `youbot`, or `dvrk_psm`, `youbot_base`) or a JSON file of the six
/// fields of `Limits` (`{"max_speed": 0.5, "max_jerk": 10}`; a field left out is 0, no limit).
pub(crate) fn read_limits(given: &str) -> Result<Limits, DmpctlError> {
    if let Some(l) = Limits::profile(given) {
        return Ok(l);
    }
    let path = Path::new(given);
    if !path.exists() {
        return Err(DmpctlError::argument(
            "--limits",
            format!("`{given}` is neither a profile (panda, psm, youbot) nor a file"),
        ));
    }
    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    struct File {
        #[serde(default)]
        max_speed: f64,
        #[serde(default)]
        max_acceleration: f64,
        #[serde(default)]
        max_jerk: f64,
        #[serde(default)]
        max_angular_speed: f64,
        #[serde(default)]
        max_angular_acceleration: f64,
        #[serde(default)]
        max_angular_jerk: f64,
    }
    let text = std::fs::read_to_string(path)
        .map_err(|e| DmpctlError::argument("--limits", format!("{}: {e}", path.display())))?;
    let f: File =
        serde_json::from_str(&text).map_err(|e| match non_finite_at(&text, e.line(), e.column()) {
            Some(_) => json_error(path, &text, &e),
            None => DmpctlError::argument("--limits", format!("{}: {e}", path.display())),
        })?;
    let l = Limits {
        max_speed: f.max_speed,
        max_acceleration: f.max_acceleration,
        max_jerk: f.max_jerk,
        max_angular_speed: f.max_angular_speed,
        max_angular_acceleration: f.max_angular_acceleration,
        max_angular_jerk: f.max_angular_jerk,
    };
    l.validate().map_err(|e| DmpctlError::argument(format!("--limits: {}", e.field), e.rule))?;
    Ok(l)
}

/// `--tool FILE`: a JSON tool, `{"semi_axes": [0.3, 0.02, 0.02], "exponents": [], "offset": [0, 0, 0.1],
/// "axis": true, "control_points": 25}` (all but `semi_axes` optional).
pub(crate) fn read_tool(path: &Path) -> Result<v1::Tool, DmpctlError> {
    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    struct File {
        semi_axes: Vec<f64>,
        #[serde(default)]
        exponents: Vec<f64>,
        #[serde(default)]
        offset: Vec<f64>,
        #[serde(default)]
        axis: bool,
        #[serde(default)]
        control_points: u32,
    }
    let text = std::fs::read_to_string(path)
        .map_err(|e| DmpctlError::argument("--tool", format!("{}: {e}", path.display())))?;
    let f: File =
        serde_json::from_str(&text).map_err(|e| match non_finite_at(&text, e.line(), e.column()) {
            Some(_) => json_error(path, &text, &e),
            None => DmpctlError::argument("--tool", format!("{}: {e}", path.display())),
        })?;
    Ok(v1::Tool {
        shape: Some(v1::Superquadric { semi_axes: f.semi_axes, exponents: f.exponents }),
        offset: f.offset,
        axis: f.axis,
        control_points: f.control_points,
    })
}

/// The record `robot put` sends.
pub(crate) fn record(
    id: &str,
    limits: Option<&Limits>,
    footprint: Option<&[f64]>,
    tool: Option<v1::Tool>,
) -> v1::RobotRecord {
    v1::RobotRecord {
        robot_id: id.into(),
        limits: limits.map(limits_to_proto),
        footprint: footprint.map(|a| v1::Superquadric { semi_axes: a.to_vec(), exponents: Vec::new() }),
        tool,
        updated_unix_ms: 0,
        margin: 0.0,
    }
}

/// A record as JSON (the fields of the message, unset ones null).
pub(crate) fn record_json(r: &v1::RobotRecord) -> Value {
    let limits = r.limits.as_ref().map(|l| {
        json!({
            "max_speed": l.max_speed, "max_acceleration": l.max_acceleration, "max_jerk": l.max_jerk,
            "max_angular_speed": l.max_angular_speed, "max_angular_acceleration": l.max_angular_acceleration,
            "max_angular_jerk": l.max_angular_jerk,
        })
    });
    let footprint = r.footprint.as_ref().map(|f| json!({"semi_axes": f.semi_axes, "exponents": f.exponents}));
    let tool = r.tool.as_ref().map(|t| {
        let shape = t.shape.as_ref();
        json!({
            "semi_axes": shape.map(|s| s.semi_axes.clone()), "exponents": shape.map(|s| s.exponents.clone()),
            "offset": t.offset, "axis": t.axis, "control_points": t.control_points,
        })
    });
    json!({
        "robot_id": r.robot_id, "limits": limits, "footprint": footprint, "tool": tool,
        "updated_unix_ms": r.updated_unix_ms,
    })
}

/// `robot put`: stores the record; prints it as stored.
pub(crate) async fn put(client: &DmpClient, record: v1::RobotRecord) -> Result<String, DmpctlError> {
    Ok(to_json(&record_json(&client.put_robot(record).await?)))
}

/// `robot show`: the record as JSON.
pub(crate) async fn show(client: &DmpClient, id: &str) -> Result<String, DmpctlError> {
    Ok(to_json(&record_json(&client.get_robot(id).await?)))
}

/// `robot delete`.
pub(crate) async fn delete(client: &DmpClient, id: &str) -> Result<String, DmpctlError> {
    client.delete_robot(id).await?;
    Ok(format!("deleted the record of {id}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_are_a_profile_or_a_file_and_a_bad_one_names_the_field() {
        assert_eq!(read_limits("panda").unwrap(), Limits::PANDA);
        assert_eq!(read_limits("psm").unwrap(), Limits::DVRK_PSM);
        assert_eq!(read_limits("youbot").unwrap(), Limits::YOUBOT_BASE);
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("l.json");
        std::fs::write(&file, r#"{"max_speed": 0.5, "max_jerk": 10}"#).unwrap();
        let l = read_limits(file.to_str().unwrap()).unwrap();
        assert_eq!(l, Limits { max_speed: 0.5, max_jerk: 10.0, ..Limits::NONE });
        std::fs::write(&file, r#"{"max_speed": -1}"#).unwrap();
        let e = read_limits(file.to_str().unwrap()).unwrap_err();
        assert!(e.to_string().contains("max_speed"), "{e}");
        std::fs::write(&file, r#"{"max_sped": 1}"#).unwrap();
        assert!(read_limits(file.to_str().unwrap()).unwrap_err().to_string().contains("max_sped"));
        assert!(read_limits("kuka").unwrap_err().to_string().contains("--limits"));
    }
}
