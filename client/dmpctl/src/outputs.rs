//! Writing a run's files: `trajectory.csv`, `metrics.json`, `plot.svg`.

use std::fmt::Write as _;
use std::path::Path;

use dmp::Trajectory;
use serde::Serialize;

use crate::error::DmpctlError;

/// The CSV of SPEC.md: header `t,x1..xd,xd1..xdd,a1..ad`, one row per step from `t = 0`. Numbers are written in
/// their shortest exact form, so the file round-trips bit for bit.
pub fn trajectory_csv(traj: &Trajectory) -> String {
    let d = traj.dim();
    let mut out = String::with_capacity(traj.len() * (d * 3 + 1) * 22);
    out.push('t');
    for prefix in ["x", "xd", "a"] {
        for i in 1..=d {
            let _ = write!(out, ",{prefix}{i}");
        }
    }
    out.push('\n');
    for k in 0..traj.len() {
        let _ = write!(out, "{}", traj.t[k]);
        for v in traj.position(k).iter().chain(traj.velocity(k)).chain(traj.acceleration(k)) {
            let _ = write!(out, ",{v}");
        }
        out.push('\n');
    }
    out
}

/// Writes `contents` to `dir/name`, creating `dir`.
pub fn write_file(dir: &Path, name: &str, contents: &[u8]) -> Result<(), DmpctlError> {
    std::fs::create_dir_all(dir).map_err(|source| DmpctlError::Io { path: dir.to_path_buf(), source })?;
    let path = dir.join(name);
    std::fs::write(&path, contents).map_err(|source| DmpctlError::Io { path, source })
}

/// Pretty JSON of any serializable value.
pub fn to_json<T: Serialize>(value: &T) -> String {
    serde_json::to_string_pretty(value).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
}
