//! What a stretch of a run becomes on the wire: one segment per member.

use dmp::execution::Stretch;
use dmp_proto::v1;

use super::served_run::ServedRun;
use super::verdict::{Ending, verdict};

/// What the loop sends: one segment per member, all covering the same times.
pub(crate) type Batch = Vec<v1::Segment>;

/// One segment per member out of a stretch of the run (a single robot's run moves the points, without a copy).
/// `start_unix` is the wall time of run time zero (real time). The run's judge records the stretch; when it ends the
/// run, every member's segment carries the run's verdict.
pub(crate) fn member_segments(
    run: &mut ServedRun,
    mut p: Stretch,
    sequence: u64,
    status: v1::SegmentStatus,
    start_unix: Option<f64>,
) -> Batch {
    run.judge.observe(&run.execution, &p, status);
    let ending = Ending::of(p.outcome);
    let e = &run.execution;
    let d = e.dim();
    let n = p.x.len() / d.max(1);
    let goal_reached_time = match status {
        v1::SegmentStatus::GoalReached => e.goal_met_since().unwrap_or(0.0),
        _ => 0.0,
    };
    // A pose run has one member, the robot owning the position dimensions.
    let mut orientation = Some(std::mem::take(&mut p.orientation));
    let clearance = std::mem::take(&mut p.min_clearance);
    let clearance_of = |m: usize| clearance.get(m).copied().filter(|c| c.is_finite());
    let mut segment = |robot_id: &str, dim: usize, positions, velocities, accelerations, min_clearance| {
        let o = orientation.take().unwrap_or_default();
        v1::Segment {
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
            goal_reached_time,
            orientations: o.q,
            angular_velocities: o.omega,
            angular_accelerations: o.omega_dot,
            min_clearance,
            verdict: None,
            limits: None,
        }
    };
    let mut batch = match e.members() {
        [m] if m.dims.len() == d => vec![segment(&m.id, d, p.x, p.xd, p.xdd, clearance_of(0))],
        members => members
            .iter()
            .enumerate()
            .map(|(mi, m)| {
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
                    clearance_of(mi),
                )
            })
            .collect(),
    };
    for s in &batch {
        run.judge.observe_clearance(s.start_time, s.min_clearance);
    }
    if let Some(ending) = ending {
        let v = verdict(&run.execution, &run.judge, &batch, ending);
        for s in &mut batch {
            s.verdict = Some(v.clone());
        }
    }
    batch
}
