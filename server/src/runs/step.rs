//! One wake-up's computation, as it runs on a compute thread: apply the changes to the run (roll back, new scene,
//! cell-mates, commands) and compute its next segments. Nothing here awaits; the producer ([`super::stream`])
//! sends what this returns.

use std::sync::Arc;

use dmp::execution::Outcome;
use dmp_proto::status::{end_reason, segment_status_limited};
use dmp_proto::v1;

use super::control::Control;
use super::control::command_rejected;
use super::ignored::push_obstacle_warnings;
use super::segments::{Batch, member_segments};
use super::served_run::ServedRun;
use crate::cells::cell::{ObstacleSet, SeenRobot};
use crate::error::ServerError;
use crate::runs::compute::pool::JobContext;

/// What one wake-up asks of the run.
#[derive(Debug)]
pub(crate) struct Step {
    /// Real time: roll back to this run time first (a change applies from the robot's time).
    pub rollback_to: Option<f64>,
    /// The cell's scene, when it changed (or at the start).
    pub scene: Option<Arc<ObstacleSet>>,
    /// The cell's other robots now.
    pub others: Vec<Arc<SeenRobot>>,
    /// The wall time (Unix seconds) of run time zero in real time; `None`: as fast as read, where "now" is
    /// `now_unix_s`.
    pub start_unix: Option<f64>,
    /// As fast as read: the wall time now.
    pub now_unix_s: f64,
    /// Changes of plan (goal, tau, pause, resume, stop) in the order received.
    pub commands: Vec<Control>,
    /// After the commands: hold position (true) or not (false); `None` leaves it to them (the scene's staleness
    /// under the `stop` policy, [`crate::cells::staleness::StaleGuard::hold`]).
    pub hold: Option<bool>,
    /// Real time: compute until the run reaches this run time (the lookahead and a refill ahead of the robot);
    /// `None`: as fast as read, one segment.
    pub horizon: Option<f64>,
    /// At most this many segments (0: only apply the changes).
    pub max_segments: usize,
    /// Points per segment.
    pub segment_points: usize,
    /// Sequence number of the first segment.
    pub sequence: u64,
}

/// A segment computed, ready to send.
#[derive(Debug)]
pub(crate) struct Computed {
    /// The members' segments.
    pub batch: Batch,
    /// What the segment came to.
    pub outcome: Outcome,
    /// Run time of its last point.
    pub last_point_time: f64,
}

/// What a wake-up computed.
#[derive(Debug, Default)]
pub(crate) struct Stepped {
    /// Segments, in order; the last may end the run ([`end_reason`] of its outcome).
    pub segments: Vec<Computed>,
    /// The members' states at the first point computed, to publish to the cell (with each member's footprint).
    pub states: Vec<(v1::RobotState, Option<dmp::Shape>)>,
    /// Warnings for the robot: commands that could not be applied, obstacles it could not use.
    pub warnings: Vec<v1::Warning>,
}

impl Step {
    /// The wall time (Unix seconds) of run time `t`.
    fn wall_of(&self, t: f64) -> f64 {
        self.start_unix.map_or(self.now_unix_s, |s| s + t)
    }
}

/// Applies `step`'s changes to `run` and computes its segments. Stops early (with what it has) when nobody waits
/// for the result any more.
pub(crate) fn compute(run: &mut ServedRun, step: Step, job: &JobContext<'_>) -> Result<Stepped, ServerError> {
    let mut out = Stepped::default();
    if let Some(t) = step.rollback_to {
        run.execution.rollback_to(t);
    }
    let now = step.wall_of(run.execution.time());
    match &step.scene {
        Some(scene) => run.apply_scene(scene, &step.others, now)?,
        None => run.set_cell_mates(&step.others, now)?,
    }
    // A change the engine refuses is a warning for the robot; the run goes on as before it.
    for c in &step.commands {
        let e = &mut run.execution;
        let (command, applied) = match c {
            Control::SetGoal(g, q) => ("set_goal", e.set_pose_goal((!g.is_empty()).then(|| g.clone()), *q)),
            Control::SetTau(tau) => ("set_tau", e.set_tau(*tau)),
            Control::Pause => {
                e.set_holding(true);
                continue;
            }
            Control::Resume => {
                e.set_holding(false);
                continue;
            }
            Control::Stop => {
                e.stop();
                continue;
            }
            Control::State(_) | Control::Rejected(_) => continue,
        };
        if let Err(i) = applied {
            out.warnings.push(command_rejected(command, &i.field, &i.rule));
        }
    }
    if let Some(hold) = step.hold {
        run.execution.set_holding(hold);
    }
    if step.max_segments == 0 {
        return Ok(out);
    }
    if let Some(h) = step.horizon {
        // This wake-up ends with the first segment that reaches the horizon: the next change applies there at the
        // earliest.
        let seg = step.segment_points as f64 * run.execution.dt();
        let t = run.execution.time();
        run.execution.limit_knots_to(t + ((h - t) / seg).ceil().max(1.0) * seg);
    }
    let mut sequence = step.sequence;
    loop {
        let e = &mut run.execution;
        let mut stretch = e.advance(step.segment_points.min(e.points_to_end()))?;
        push_obstacle_warnings(&mut stretch.ignored, &mut out.warnings);
        let last_point_time = e.time() - e.dt();
        let outcome = stretch.outcome;
        let status = segment_status_limited(outcome, stretch.limit);
        if out.segments.is_empty() {
            out.states = member_states(run, &stretch, step.wall_of(stretch.start_time));
        }
        let batch = member_segments(run, stretch, sequence, status, step.start_unix);
        sequence += 1;
        out.segments.push(Computed { batch, outcome, last_point_time });
        let done = end_reason(outcome).is_some()
            || out.segments.len() >= step.max_segments
            || step.horizon.is_none_or(|h| run.execution.time() >= h)
            || job.cancelled();
        if done {
            return Ok(out);
        }
    }
}

/// Each member's state at the first point of `p`, stamped `stamp` (Unix seconds).
fn member_states(
    run: &ServedRun,
    p: &dmp::execution::Stretch,
    stamp: f64,
) -> Vec<(v1::RobotState, Option<dmp::Shape>)> {
    let d = run.execution.dim();
    let (x, xd) = (&p.x[..d.min(p.x.len())], &p.xd[..d.min(p.xd.len())]);
    run.execution
        .members()
        .iter()
        .zip(&run.footprints)
        .map(|(m, footprint)| {
            let state = v1::RobotState {
                robot_id: m.id.clone(),
                stamp_unix_s: stamp,
                position: m.dims.iter().filter_map(|&i| x.get(i).copied()).collect(),
                velocity: m.dims.iter().filter_map(|&i| xd.get(i).copied()).collect(),
                footprint: footprint.clone(),
                // A pose run (one member): its orientation and angular velocity at the point.
                orientation: p.orientation.q.get(..4).map(<[f64]>::to_vec).unwrap_or_default(),
                angular_velocity: p.orientation.omega.get(..3).map(<[f64]>::to_vec).unwrap_or_default(),
            };
            (state, m.footprint.clone())
        })
        .collect()
}
