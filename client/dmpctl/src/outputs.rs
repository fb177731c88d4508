//! Writing a run's files: `trajectory.csv`, `metrics.json`, `plot.svg`.

use std::borrow::Cow;
use std::fmt::Write as _;
use std::path::Path;

use dmp::Trajectory;
use dmp::execution::OrientationPoints;
use dmp::scenario::Prepared;
use serde::Serialize;

use crate::error::DmpctlError;

/// The CSV of SPEC.md: header `t,x1..xd,xd1..xdd,a1..ad`, one row per step from `t = 0`. Numbers are written in
/// their shortest exact form, so the file round-trips bit for bit.
pub(crate) fn trajectory_csv(traj: &Trajectory) -> String {
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

/// A pose run's CSV: the columns of [`trajectory_csv`] for its positions (`t,x1..xn,xd1..xdn,a1..an`), then its
/// orientation `qx,qy,qz,qw`, angular velocity `wx,wy,wz` (rad/s) and angular acceleration `wdx,wdy,wdz`
/// (rad/s²), world frame.
pub(crate) fn pose_trajectory_csv(traj: &Trajectory, orientations: &OrientationPoints) -> String {
    let n = traj.dim() - 3;
    let mut out = String::with_capacity(traj.len() * (n * 3 + 11) * 22);
    out.push('t');
    for prefix in ["x", "xd", "a"] {
        for i in 1..=n {
            let _ = write!(out, ",{prefix}{i}");
        }
    }
    out.push_str(",qx,qy,qz,qw,wx,wy,wz,wdx,wdy,wdz\n");
    for k in 0..traj.len() {
        let _ = write!(out, "{}", traj.t[k]);
        let (x, xd, a) = (traj.position(k), traj.velocity(k), traj.acceleration(k));
        let q = orientations.q.get(4 * k..4 * k + 4).unwrap_or(&[f64::NAN; 4]);
        let w = orientations.omega.get(3 * k..3 * k + 3).unwrap_or(&[f64::NAN; 3]);
        let wd = orientations.omega_dot.get(3 * k..3 * k + 3).unwrap_or(&[f64::NAN; 3]);
        for v in x[..n].iter().chain(&xd[..n]).chain(&a[..n]).chain(q).chain(w).chain(wd) {
            let _ = write!(out, ",{v}");
        }
        out.push('\n');
    }
    out
}

/// The positions of a run: all of a position scenario's dimensions, the first `n` of a pose scenario's.
pub(crate) fn positions_of<'a>(p: &Prepared, traj: &'a Trajectory) -> Cow<'a, Trajectory> {
    let n = p.position_dim();
    if n == traj.dim() {
        return Cow::Borrowed(traj);
    }
    let mut out = Trajectory::with_capacity(n, traj.len());
    for k in 0..traj.len() {
        out.push(traj.t[k], &traj.position(k)[..n], &traj.velocity(k)[..n], &traj.acceleration(k)[..n]);
    }
    Cow::Owned(out)
}

/// Writes `contents` to `dir/name`, creating `dir`.
pub(crate) fn write_file(dir: &Path, name: &str, contents: &[u8]) -> Result<(), DmpctlError> {
    std::fs::create_dir_all(dir).map_err(|source| DmpctlError::Io { path: dir.to_path_buf(), source })?;
    let path = dir.join(name);
    std::fs::write(&path, contents).map_err(|source| DmpctlError::Io { path, source })
}

/// Pretty JSON of any serializable value.
pub(crate) fn to_json<T: Serialize>(value: &T) -> String {
    serde_json::to_string_pretty(value).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
}
