//! What a stretch of a run becomes on the wire: one segment per member, and each member's state published to its
//! cell.

use dmp::execution::Stretch;
use dmp_proto::v1;

use super::served_run::ServedRun;
use crate::cell::Cell;
use crate::state::AppState;

/// What the loop sends: one segment per member, all covering the same times.
pub type Batch = Vec<v1::Segment>;

/// One segment per member out of a stretch of the run (a single robot's run moves the points, without a copy).
/// `start_unix` is the wall time of run time zero (real time).
pub fn member_segments(
    run: &ServedRun,
    p: Stretch,
    sequence: u64,
    status: v1::SegmentStatus,
    start_unix: Option<f64>,
) -> Batch {
    let e = &run.execution;
    let d = e.dim();
    let n = p.x.len() / d.max(1);
    let segment = |robot_id: &str, dim: usize, positions, velocities, accelerations| v1::Segment {
        robot_id: robot_id.to_string(),
        sequence,
        start_time: p.start_time,
        dt: e.dt(),
        dim: dim as u32,
        positions,
        velocities,
        accelerations,
        status: status as i32,
        scene_version: run.scene_version,
        start_unix_s: start_unix.map(|s| s + p.start_time).unwrap_or(0.0),
        warnings: Vec::new(),
        scene_stale: false,
    };
    match e.members() {
        [m] if m.dims.len() == d => vec![segment(&m.id, d, p.x, p.xd, p.xdd)],
        members => members
            .iter()
            .map(|m| {
                let member_columns = |v: &[f64]| -> Vec<f64> {
                    let mut out = Vec::with_capacity(n * m.dims.len());
                    for row in v.chunks_exact(d) {
                        out.extend(m.dims.iter().map(|&i| row[i]));
                    }
                    out
                };
                segment(
                    &m.id,
                    m.dims.len(),
                    member_columns(&p.x),
                    member_columns(&p.xd),
                    member_columns(&p.xdd),
                )
            })
            .collect(),
    }
}

/// The state at a stretch's first point (run time `t`).
#[derive(Debug)]
pub struct FirstPoint {
    /// Run time.
    pub t: f64,
    /// Position (the DMP's dimension).
    pub x: Vec<f64>,
    /// Velocity.
    pub xd: Vec<f64>,
}

impl FirstPoint {
    /// The first point of `p`, a stretch of a `dim`-dimensional run.
    pub fn of(p: &Stretch, dim: usize) -> Self {
        Self { t: p.start_time, x: p.x[..dim].to_vec(), xd: p.xd[..dim].to_vec() }
    }
}

/// Publishes each member's state at `p`, stamped with the wall time of its run time (`start_unix` is that of run
/// time zero in real time; as fast as read, now).
pub async fn publish_states(
    app: &AppState,
    cell: &Cell,
    run: &ServedRun,
    p: FirstPoint,
    start_unix: Option<f64>,
) {
    let stamp = start_unix.map(|s| s + p.t).unwrap_or_else(|| app.clock.now_unix_s());
    for (m, footprint) in run.execution.members().iter().zip(&run.footprints) {
        let state = v1::RobotState {
            robot_id: m.id.clone(),
            stamp_unix_s: stamp,
            position: m.dims.iter().map(|&i| p.x[i]).collect(),
            velocity: m.dims.iter().map(|&i| p.xd[i]).collect(),
            footprint: footprint.clone(),
        };
        app.robots.publish(cell, state, m.footprint.clone()).await;
    }
}
