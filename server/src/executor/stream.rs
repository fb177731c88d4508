//! The producer task of a streamed execution: one task and one bounded channel per stream (the bound is the
//! backpressure: a slow reader holds the producer, never grows memory). Real-time pacing keeps the segments sent
//! between `lookahead` and `lookahead + refill` ahead of the wall clock, waking once per refill rather than once
//! per segment; a scene change or a command is applied from the robot's current time by rolling back and sending a
//! segment that supersedes the points already sent.

use std::sync::Arc;
use std::time::Duration;

use dmp_proto::v1;
use tokio::sync::mpsc;
use tokio::time::Instant;
use tracing::{debug, info, warn};

use super::runner::{Outcome, Runner};
use crate::error::ServerError;
use crate::scene::{RemoteRobot, SceneState, now_unix_s};
use crate::state::AppState;
use crate::write_batching::Urgency;

/// Robot states older than this are ignored.
const REMOTE_MAX_AGE_S: f64 = 0.5;

/// Real time: how far beyond the lookahead one wake-up computes (the producer sleeps about this long between two
/// wake-ups), with few streams. A longer refill means fewer wake-ups (each costs a timer, the cell-mates' states, a
/// state published and a write to the connection) but longer ones, which a change must wait behind: at 100 robots
/// the update-to-segment p99 was 1.47 - 2.67 ms (five 30 s runs) with 30 ms and 2.18 - 2.90 ms (three) with 60 ms;
/// at 1,000 robots 30 ms took the server to 146 % of a core and 98 % on time, 60 ms to 118 % and 99.9998 %
/// (BENCHMARKS.md).
pub const MIN_REFILL: Duration = Duration::from_millis(30);

/// Real time: the longest refill, with many streams (and what buffers and histories are sized for).
pub const MAX_REFILL: Duration = Duration::from_millis(60);

/// Stream wake-ups per second beyond which refills grow (from [`MIN_REFILL`] at 300 streams to [`MAX_REFILL`]
/// at 600).
pub const WAKE_UPS_PER_SECOND: f64 = 10_000.0;

/// The refill of a wake-up while the server carries `streams` streams: wake-ups stay under
/// [`WAKE_UPS_PER_SECOND`] as long as the refill can grow.
pub fn refill(streams: usize) -> Duration {
    let s = (streams as f64 / WAKE_UPS_PER_SECOND).clamp(MIN_REFILL.as_secs_f64(), MAX_REFILL.as_secs_f64());
    Duration::from_secs_f64(s)
}

/// Real time: how long after the request the run's first point is due.
pub const FIRST_POINT_DELAY: Duration = Duration::from_millis(20);

/// Real time: the most segments one wake-up computes.
pub fn refill_segments(cfg: &StreamConfig) -> usize {
    let seg = cfg.segment_points as f64 * cfg.dt;
    (MAX_REFILL.as_secs_f64() / seg).ceil() as usize + 1
}

/// How a stream is paced and bounded.
#[derive(Debug, Clone)]
pub struct StreamConfig {
    /// Output step, seconds.
    pub dt: f64,
    /// Points per segment.
    pub segment_points: usize,
    /// Internal RK4 step, in output steps (with a tolerance: the largest adaptive step).
    pub step_points: usize,
    /// The adaptive step's local error tolerance (None: RK4 at `step_points`).
    pub tolerance: Option<f64>,
    /// Real time (true) or as fast as the client reads.
    pub realtime: bool,
    /// Real-time: how far ahead of the wall clock segments are computed.
    pub lookahead: Duration,
    /// The run ends at this time (seconds of run time).
    pub max_duration: f64,
    /// The connection's urgency (a superseding segment is written at once), when it batches its writes.
    pub urgency: Option<Urgency>,
}

/// A command of a session.
#[derive(Debug, Clone)]
pub enum Control {
    /// New goal.
    SetGoal(Vec<f64>),
    /// New tau.
    SetTau(f64),
    /// Hold position.
    Pause,
    /// Continue.
    Resume,
    /// Decelerate to rest and end.
    Stop,
    /// The robot's measured state: published to the cell.
    State(v1::RobotState),
}

/// What the loop sends: one segment per member, all covering the same times.
pub type Batch = Vec<v1::Segment>;

/// Runs `runner` until the goal, a stop, `max_duration`, the client leaving or shutdown. Items go to `tx`
/// (mapped by the caller's stream); errors end the stream with a status.
pub async fn run_stream(
    app: Arc<AppState>,
    mut runner: Runner,
    cell: SceneState,
    cfg: StreamConfig,
    tx: mpsc::Sender<Result<Batch, tonic::Status>>,
    mut control: Option<mpsc::Receiver<Control>>,
) {
    let ids: Vec<String> = runner.members().iter().map(|m| m.robot_id.clone()).collect();
    let result = produce(&app, &cell, &mut runner, &cfg, &tx, &mut control).await;
    for id in &ids {
        app.robots.retire(&cell, id).await;
    }
    match result {
        Ok(reason) => info!(robots = ?ids, reason, t = runner.time(), "stream ended"),
        Err(ServerError::ShuttingDown) => {
            info!(robots = ?ids, t = runner.time(), "stream ended by shutdown");
            // Never wait on a reader that stopped reading: the status goes only if there is room.
            let _ = tx.try_send(Err(ServerError::ShuttingDown.into()));
        }
        Err(e) => {
            warn!(robots = ?ids, error = %e, "stream failed");
            tokio::select! {
                _ = tx.send(Err(e.into())) => {}
                _ = app.shutdown.cancelled() => {}
            }
        }
    }
}

/// Margin added to the robot's current time when a change rolls the run back: the superseding segment must reach
/// the robot before its first point is due. Computing and sending it takes well under a millisecond on an idle
/// host, but a busy one (the server sharing its cores with robots' drivers and builds) delays a task by several:
/// 3 ms let a superseding segment arrive late there.
pub const ROLLBACK_MARGIN: Duration = Duration::from_millis(10);

async fn produce(
    app: &AppState,
    cell: &SceneState,
    runner: &mut Runner,
    cfg: &StreamConfig,
    tx: &mpsc::Sender<Result<Batch, tonic::Status>>,
    control: &mut Option<mpsc::Receiver<Control>>,
) -> Result<&'static str, ServerError> {
    let mut scene_rx = cell.subscribe();
    let mut others: Vec<Arc<RemoteRobot>> = Vec::new();
    let first_robot = runner.members()[0].robot_id.clone();
    // Real time: the first point is due FIRST_POINT_DELAY from now, so that the first segment (computed and sent
    // now) reaches the robot before it.
    let delay = if cfg.realtime { FIRST_POINT_DELAY } else { Duration::ZERO };
    let start = Instant::now() + delay;
    let start_unix = now_unix_s() + delay.as_secs_f64();
    // The wall time (Unix seconds) of run time t: real time maps them one to one; as fast as read, "now" is
    // whenever the point is computed.
    let wall_of = |t: f64| if cfg.realtime { start_unix + t } else { now_unix_s() };
    let snap = scene_rx.borrow_and_update().clone();
    let now = wall_of(runner.time());
    cell.other_robots_into(&first_robot, now, REMOTE_MAX_AGE_S, &mut others);
    runner.apply_scene(&snap, &others, now)?;
    let dt = runner.dt();
    let mut seq = 0u64;
    let mut stopping = false;
    // Real time: the run is complete once this point (run time) has been executed; until then it can still be
    // superseded.
    let mut finished: Option<(f64, &'static str)> = None;
    loop {
        // 1. Wait until the next segment is due (real time) while reacting to changes; as fast as read: take what
        //    is pending and go on.
        let mut changed_scene = false;
        let mut commands = Vec::new();
        if cfg.realtime {
            let due = match finished {
                Some((t_end, _)) => start + Duration::from_secs_f64(t_end),
                None => (start + Duration::from_secs_f64(runner.time()))
                    .checked_sub(cfg.lookahead)
                    .unwrap_or_else(Instant::now),
            };
            tokio::select! {
                _ = tokio::time::sleep_until(due) => {
                    if let Some((_, reason)) = finished {
                        return Ok(reason);
                    }
                }
                r = scene_rx.changed() => {
                    if r.is_err() { return Ok("scene closed") }
                    changed_scene = true;
                }
                c = recv(control) => match c {
                    Some(c) => commands.push(c),
                    None => *control = None,
                },
                _ = app.shutdown.cancelled() => return Err(ServerError::ShuttingDown),
                _ = tx.closed() => return Ok("client left"),
            }
        } else {
            if app.shutdown.is_cancelled() {
                return Err(ServerError::ShuttingDown);
            }
            changed_scene = scene_rx.has_changed().unwrap_or(false);
        }
        if let Some(rx) = control.as_mut() {
            while let Ok(c) = rx.try_recv() {
                commands.push(c);
            }
        }
        // Measured states are published, and change nothing in the plan.
        let mut changes_plan = changed_scene;
        for c in &commands {
            if let Control::State(s) = c {
                let fp = runner
                    .members()
                    .iter()
                    .find(|m| m.robot_id == s.robot_id)
                    .and_then(|m| m.footprint.clone());
                app.robots.publish(cell, s.clone(), fp).await;
            } else {
                changes_plan = true;
            }
        }
        if !changes_plan && finished.is_some() {
            continue;
        }
        // 2. Apply changes from the robot's current time: roll back what was computed ahead of it.
        if changes_plan && cfg.realtime {
            let now_t = (start.elapsed() + ROLLBACK_MARGIN).as_secs_f64() + dt;
            runner.rollback_to(now_t);
            finished = None;
        }
        let now = wall_of(runner.time());
        cell.other_robots_into(&first_robot, now, REMOTE_MAX_AGE_S, &mut others);
        if changed_scene {
            let snap = scene_rx.borrow_and_update().clone();
            runner.apply_scene(&snap, &others, now)?;
            debug!(robot = %first_robot, version = snap.version, t = runner.time(), "scene applied");
        } else {
            runner.set_remote(&others, now)?;
        }
        for c in commands {
            match c {
                Control::SetGoal(g) => runner.set_goal(g)?,
                Control::SetTau(tau) => runner.set_tau(tau)?,
                Control::Pause => runner.set_holding(true),
                Control::Resume => {
                    if !stopping {
                        runner.set_holding(false)
                    }
                }
                Control::Stop => {
                    stopping = true;
                    runner.set_holding(true);
                }
                Control::State(_) => {}
            }
        }
        // 3. Compute and send segments: one as fast as read; in real time, up to a refill beyond the lookahead (each
        //    segment goes out as soon as it is computed). The last one ends with the point at exactly max_duration.
        //    The cell-mates are read once per wake-up (above): within a refill they move along their velocities.
        let horizon = (start.elapsed() + cfg.lookahead + refill(app.open_streams())).as_secs_f64();
        if cfg.realtime {
            // This wake-up ends with the first segment that reaches the horizon: the next change applies there
            // at the earliest.
            let seg = cfg.segment_points as f64 * dt;
            let segments = ((horizon - runner.time()) / seg).ceil().max(1.0);
            runner.limit_knots_to(runner.time() + segments * seg);
        }
        let mut first_of_wake = true;
        loop {
            let remaining = ((cfg.max_duration - runner.time()) / dt).round().max(0.0) as usize + 1;
            let points = runner.advance(cfg.segment_points.min(remaining))?;
            let outcome = points.outcome.unwrap_or(Outcome::Running);
            let last_point_time = runner.time() - dt;
            let (status, last) = if stopping && runner.at_rest() {
                (v1::SegmentStatus::Stopped, Some("stopped"))
            } else if outcome == Outcome::GoalReached {
                (v1::SegmentStatus::GoalReached, Some("goal reached"))
            } else if last_point_time >= cfg.max_duration - 0.5 * dt {
                (v1::SegmentStatus::Stopped, Some("max duration"))
            } else {
                (
                    match outcome {
                        Outcome::Running | Outcome::GoalReached => v1::SegmentStatus::Running,
                        Outcome::Stalled => v1::SegmentStatus::Stalled,
                        Outcome::Collision => v1::SegmentStatus::Collision,
                        Outcome::Holding => v1::SegmentStatus::Paused,
                    },
                    None,
                )
            };
            // The first point's state, published once per wake-up (below).
            let first = first_of_wake.then(|| FirstPoint {
                t: points.start_time,
                x: points.x[..runner.dim()].to_vec(),
                xd: points.xd[..runner.dim()].to_vec(),
            });
            let batch = split(runner, points, seq, status, cfg.realtime.then_some(start_unix));
            let members = batch.len() as u64;
            // A segment that supersedes points already sent cannot wait for the connection's batched write.
            if changes_plan
                && first_of_wake
                && cfg.realtime
                && let Some(urgency) = &cfg.urgency
            {
                urgency.write_now();
            }
            // The robot first: publishing the states may wait on Zenoh (a robot's first state declares its
            // publisher).
            tokio::select! {
                sent = tx.send(Ok(batch)) => if sent.is_err() { return Ok("client left") },
                _ = app.shutdown.cancelled() => return Err(ServerError::ShuttingDown),
            }
            // One state per wake-up: the cell-mates read them at their own wake-ups (once per refill) and
            // extrapolate them with the velocity.
            if let Some(first) = first {
                publish_states(app, cell, runner, first, cfg.realtime.then_some(start_unix)).await;
                first_of_wake = false;
                // A change wakes every stream of the cell at once: let the others send their superseding segment
                // before this one computes the rest of its refill.
                if changes_plan && cfg.realtime {
                    tokio::task::yield_now().await;
                }
            }
            app.counters.segments_sent.fetch_add(members, std::sync::atomic::Ordering::Relaxed);
            seq += 1;
            if let Some(reason) = last {
                if !cfg.realtime {
                    return Ok(reason);
                }
                // Keep the stream open until the robot has executed the last point: a change may still supersede
                // it.
                finished = Some((last_point_time, reason));
                break;
            }
            if !cfg.realtime || runner.time() >= horizon {
                break;
            }
        }
    }
}

async fn recv(control: &mut Option<mpsc::Receiver<Control>>) -> Option<Control> {
    match control {
        Some(rx) => rx.recv().await,
        None => std::future::pending().await,
    }
}

/// One segment per member out of the run's points (a single robot's run moves them, without a copy).
fn split(
    runner: &Runner,
    p: super::runner::Points,
    seq: u64,
    status: v1::SegmentStatus,
    start_unix: Option<f64>,
) -> Batch {
    let d = runner.dim();
    let n = p.x.len() / d;
    let segment = |m: &super::runner::Member, positions, velocities, accelerations| v1::Segment {
        robot_id: m.robot_id.clone(),
        sequence: seq,
        start_time: p.start_time,
        dt: runner.dt(),
        dim: m.dims.len() as u32,
        positions,
        velocities,
        accelerations,
        status: status as i32,
        scene_version: runner.scene_version(),
        start_unix_s: start_unix.map(|s| s + p.start_time).unwrap_or(0.0),
    };
    match runner.members() {
        [m] if m.dims.len() == d => vec![segment(m, p.x, p.xd, p.xdd)],
        members => members
            .iter()
            .map(|m| {
                let pick = |v: &[f64]| -> Vec<f64> {
                    (0..n).flat_map(|k| v[k * d + m.dims.start..k * d + m.dims.end].iter().copied()).collect()
                };
                segment(m, pick(&p.x), pick(&p.xd), pick(&p.xdd))
            })
            .collect(),
    }
}

/// The state at a segment's first point (run time `t`).
struct FirstPoint {
    t: f64,
    x: Vec<f64>,
    xd: Vec<f64>,
}

/// Publishes each member's state at the first point of a segment.
async fn publish_states(
    app: &AppState,
    cell: &SceneState,
    runner: &Runner,
    p: FirstPoint,
    start_unix: Option<f64>,
) {
    let stamp = start_unix.map(|s| s + p.t).unwrap_or_else(now_unix_s);
    for m in runner.members() {
        let state = v1::RobotState {
            robot_id: m.robot_id.clone(),
            stamp_unix_s: stamp,
            position: p.x[m.dims.clone()].to_vec(),
            velocity: p.xd[m.dims.clone()].to_vec(),
            footprint: m.footprint_proto.clone(),
        };
        app.robots.publish(cell, state, m.footprint.clone()).await;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refills_grow_with_the_streams_between_their_bounds() {
        assert_eq!(refill(0), MIN_REFILL);
        assert_eq!(refill(100), MIN_REFILL);
        assert_eq!(refill(450), Duration::from_millis(45));
        assert_eq!(refill(600), MAX_REFILL);
        assert_eq!(refill(1_000), MAX_REFILL);
        let cfg = StreamConfig {
            dt: 1e-3,
            segment_points: 10,
            step_points: 1,
            tolerance: None,
            realtime: true,
            lookahead: Duration::from_millis(50),
            max_duration: 1.0,
            urgency: None,
        };
        assert_eq!(refill_segments(&cfg), 7, "room for the longest refill");
    }
}
