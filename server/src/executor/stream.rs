//! The producer task of a streamed execution: one task and one bounded channel per stream (the bound is the
//! backpressure: a slow reader holds the producer, never grows memory). Real-time pacing keeps the segments sent
//! between `lookahead` and `lookahead + refill` ahead of the wall clock, waking once per refill rather than once
//! per segment; a scene change or a command is applied from the robot's current time by rolling back and sending a
//! segment that supersedes the points already sent. The stepping itself is the engine's ([`dmp::Execution`]).

use std::sync::Arc;
use std::time::Duration;

use dmp::Stepping;
use dmp_proto::status::{end_reason, segment_status};
use dmp_proto::v1;
use tokio::sync::{mpsc, watch};
use tokio::time::Instant;
use tracing::{debug, info, warn};

use super::pacing::{FIRST_POINT_DELAY, ROLLBACK_MARGIN, refill};
use super::segments::{Batch, FirstPoint, member_segments, publish_states};
use super::served_run::ServedRun;
use crate::cell::{Cell, ObstacleSet, SeenRobot};
use crate::error::ServerError;
use crate::staleness::StaleGuard;
use crate::state::AppState;
use crate::write_batching::Urgency;

/// Robot states older than this are ignored.
const REMOTE_MAX_AGE_S: f64 = 0.5;

/// How a stream is paced and bounded.
#[derive(Debug, Clone)]
pub struct StreamConfig {
    /// Output and internal steps.
    pub stepping: Stepping,
    /// Points per segment.
    pub segment_points: usize,
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

/// Runs `run` until the goal, a stop, `max_duration`, the client leaving or shutdown. Items go to `tx` (mapped by
/// the caller's stream); errors end the stream with a status.
pub async fn run_stream(
    app: Arc<AppState>,
    mut run: ServedRun,
    cell: Cell,
    cfg: StreamConfig,
    tx: mpsc::Sender<Result<Batch, tonic::Status>>,
    control: Option<mpsc::Receiver<Control>>,
) {
    run.execution.set_end_time(cfg.max_duration);
    let ids: Vec<String> = run.execution.members().iter().map(|m| m.id.clone()).collect();
    let mut producer = Producer::new(&app, &cell, &cfg, &tx, control);
    producer.stale = StaleGuard::new(cell.staleness(), run.ignore_scene);
    let result = producer.produce(&mut run).await;
    for id in &ids {
        app.robots.retire(&cell, id).await;
    }
    let t = run.execution.time();
    match result {
        Ok(reason) => info!(robots = ?ids, reason, t, "stream ended"),
        Err(ServerError::ShuttingDown) => {
            info!(robots = ?ids, t, "stream ended by shutdown");
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

/// What woke the producer.
#[derive(Debug, Default)]
struct Wake {
    scene_changed: bool,
    commands: Vec<Control>,
}

/// The producer's state between wake-ups.
struct Producer<'a> {
    app: &'a AppState,
    cell: &'a Cell,
    cfg: &'a StreamConfig,
    tx: &'a mpsc::Sender<Result<Batch, tonic::Status>>,
    control: Option<mpsc::Receiver<Control>>,
    scene_rx: watch::Receiver<Arc<ObstacleSet>>,
    others: Vec<Arc<SeenRobot>>,
    /// Real time: the instant and the wall time (Unix seconds) of run time zero.
    start: Instant,
    start_unix: f64,
    sequence: u64,
    /// Real time: the run is complete once this point (run time) has been executed, for this reason; until then
    /// it can still be superseded.
    finished: Option<(f64, &'static str)>,
    /// Warnings not yet sent: they go with the next segment (every member's, for a group).
    warnings: Vec<v1::Warning>,
    /// Flags the segments computed with stale obstacles, and holds the robots under the `stop` policy.
    stale: StaleGuard,
}

impl<'a> Producer<'a> {
    fn new(
        app: &'a AppState,
        cell: &'a Cell,
        cfg: &'a StreamConfig,
        tx: &'a mpsc::Sender<Result<Batch, tonic::Status>>,
        control: Option<mpsc::Receiver<Control>>,
    ) -> Self {
        // Real time: the first point is due FIRST_POINT_DELAY from now, so that the first segment (computed and
        // sent now) reaches the robot before it.
        let delay = if cfg.realtime { FIRST_POINT_DELAY } else { Duration::ZERO };
        Self {
            app,
            cell,
            cfg,
            tx,
            control,
            scene_rx: cell.subscribe(),
            others: Vec::new(),
            start: app.clock.now() + delay,
            start_unix: app.clock.now_unix_s() + delay.as_secs_f64(),
            sequence: 0,
            finished: None,
            warnings: Vec::new(),
            stale: StaleGuard::new(cell.staleness(), false),
        }
    }

    /// The wall time (Unix seconds) of run time `t`: real time maps them one to one; as fast as read, "now" is
    /// whenever the point is computed.
    fn wall_of(&self, t: f64) -> f64 {
        if self.cfg.realtime { self.start_unix + t } else { self.app.clock.now_unix_s() }
    }

    /// The loop: wait, apply what changed, send what is due.
    async fn produce(&mut self, run: &mut ServedRun) -> Result<&'static str, ServerError> {
        let snapshot = self.scene_rx.borrow_and_update().clone();
        self.read_cellmates(run);
        run.apply_scene(&snapshot, &self.others, self.wall_of(run.execution.time()))?;
        self.stale.observe(&snapshot, &mut self.warnings);
        self.stale.enforce(&mut run.execution);
        let mut wake = Wake::default();
        loop {
            let changes_plan = self.apply(run, std::mem::take(&mut wake)).await?;
            if (changes_plan || self.finished.is_none())
                && let Some(reason) = self.send_due(run, changes_plan).await?
            {
                return Ok(reason);
            }
            match self.wait(run).await? {
                Ok(w) => wake = w,
                Err(reason) => return Ok(reason),
            }
        }
    }

    /// Real time: sleeps until the next segment is due (or the run's last point executed) while reacting to
    /// changes; as fast as read: takes what is pending. `Err(reason)` when the stream is over.
    async fn wait(&mut self, run: &ServedRun) -> Result<Result<Wake, &'static str>, ServerError> {
        let mut wake = Wake::default();
        if self.cfg.realtime {
            let due = match self.finished {
                Some((t_end, _)) => self.start + Duration::from_secs_f64(t_end),
                None => (self.start + Duration::from_secs_f64(run.execution.time()))
                    .checked_sub(self.cfg.lookahead)
                    .unwrap_or_else(|| self.app.clock.now()),
            };
            tokio::select! {
                _ = tokio::time::sleep_until(due) => {
                    if let Some((_, reason)) = self.finished {
                        return Ok(Err(reason));
                    }
                }
                r = self.scene_rx.changed() => {
                    if r.is_err() { return Ok(Err("scene closed")) }
                    wake.scene_changed = true;
                }
                c = recv(&mut self.control) => match c {
                    Some(c) => wake.commands.push(c),
                    None => self.control = None,
                },
                _ = self.app.shutdown.cancelled() => return Err(ServerError::ShuttingDown),
                _ = self.tx.closed() => return Ok(Err("client left")),
            }
        } else {
            if self.app.shutdown.is_cancelled() {
                return Err(ServerError::ShuttingDown);
            }
            wake.scene_changed = self.scene_rx.has_changed().unwrap_or(false);
        }
        if let Some(rx) = self.control.as_mut() {
            while let Ok(c) = rx.try_recv() {
                wake.commands.push(c);
            }
        }
        Ok(Ok(wake))
    }

    /// Applies a wake-up's changes from the robot's current time (rolling back what was computed ahead of it), and
    /// reads the cell-mates. Measured states are published and change nothing in the plan. True when the plan
    /// changed.
    async fn apply(&mut self, run: &mut ServedRun, wake: Wake) -> Result<bool, ServerError> {
        let mut changes_plan = wake.scene_changed;
        for c in &wake.commands {
            match c {
                Control::State(s) => {
                    let members = run.execution.members();
                    let footprint =
                        members.iter().find(|m| m.id == s.robot_id).and_then(|m| m.footprint.clone());
                    self.app.robots.publish(self.cell, s.clone(), footprint).await;
                }
                _ => changes_plan = true,
            }
        }
        if changes_plan && self.cfg.realtime {
            let now_t = (self.start.elapsed() + ROLLBACK_MARGIN).as_secs_f64() + run.execution.dt();
            run.execution.rollback_to(now_t);
            self.finished = None;
        }
        if !changes_plan && self.finished.is_some() {
            return Ok(false);
        }
        self.read_cellmates(run);
        let now = self.wall_of(run.execution.time());
        if wake.scene_changed {
            let snapshot = self.scene_rx.borrow_and_update().clone();
            run.apply_scene(&snapshot, &self.others, now)?;
            self.stale.observe(&snapshot, &mut self.warnings);
            debug!(version = snapshot.version, t = run.execution.time(), "scene applied");
        } else {
            run.set_cellmates(&self.others, now)?;
        }
        self.stale.note_commands(&wake.commands);
        let e = &mut run.execution;
        for c in wake.commands {
            match c {
                Control::SetGoal(g) => e.set_goal(g)?,
                Control::SetTau(tau) => e.set_tau(tau)?,
                Control::Pause => e.set_holding(true),
                Control::Resume => e.set_holding(false),
                Control::Stop => e.stop(),
                Control::State(_) => {}
            }
        }
        self.stale.enforce(e);
        Ok(changes_plan)
    }

    /// The cell's other robots as they are now.
    fn read_cellmates(&mut self, run: &ServedRun) {
        let first = &run.execution.members()[0].id;
        let now = self.wall_of(run.execution.time());
        self.cell.other_robots_into(first, now, REMOTE_MAX_AGE_S, &mut self.others);
    }

    /// Computes and sends segments: one as fast as read; in real time, up to a refill beyond the lookahead (each
    /// segment goes out as soon as it is computed). The last one ends with the point at exactly `max_duration`.
    /// Within a refill the cell-mates move along their velocities. `Some(reason)` when the stream is over.
    async fn send_due(
        &mut self,
        run: &mut ServedRun,
        changes_plan: bool,
    ) -> Result<Option<&'static str>, ServerError> {
        let (cfg, app) = (self.cfg, self.app);
        let horizon = (self.start.elapsed() + cfg.lookahead + refill(app.open_streams())).as_secs_f64();
        let seg = cfg.segment_points as f64 * cfg.stepping.dt;
        if cfg.realtime {
            // This wake-up ends with the first segment that reaches the horizon: the next change applies there at
            // the earliest.
            let segments = ((horizon - run.execution.time()) / seg).ceil().max(1.0);
            run.execution.limit_knots_to(run.execution.time() + segments * seg);
        }
        let start_unix = cfg.realtime.then_some(self.start_unix);
        let mut first_of_wake = true;
        loop {
            let e = &mut run.execution;
            let stretch = e.advance(cfg.segment_points.min(e.points_to_end()))?;
            let last_point_time = e.time() - e.dt();
            let outcome = stretch.outcome;
            let first = first_of_wake.then(|| FirstPoint::of(&stretch, e.dim()));
            let mut batch = member_segments(run, stretch, self.sequence, segment_status(outcome), start_unix);
            for segment in &mut batch {
                segment.scene_stale = self.stale.is_stale();
            }
            if !self.warnings.is_empty() {
                for segment in &mut batch {
                    segment.warnings.clone_from(&self.warnings);
                }
                self.warnings.clear();
            }
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
                sent = self.tx.send(Ok(batch)) => if sent.is_err() { return Ok(Some("client left")) },
                _ = app.shutdown.cancelled() => return Err(ServerError::ShuttingDown),
            }
            // One state per wake-up: the cell-mates read them at their own wake-ups (once per refill) and
            // extrapolate them with the velocity.
            if let Some(first) = first {
                publish_states(app, self.cell, run, first, start_unix).await;
                first_of_wake = false;
                // A change wakes every stream of the cell at once: let the others send their superseding segment
                // before this one computes the rest of its refill.
                if changes_plan && cfg.realtime {
                    tokio::task::yield_now().await;
                }
            }
            app.counters.segments_sent.fetch_add(members, std::sync::atomic::Ordering::Relaxed);
            self.sequence += 1;
            if let Some(reason) = end_reason(outcome) {
                if !cfg.realtime {
                    return Ok(Some(reason));
                }
                // Keep the stream open until the robot has executed the last point: a change may still supersede
                // it.
                self.finished = Some((last_point_time, reason));
                return Ok(None);
            }
            if !cfg.realtime || run.execution.time() >= horizon {
                return Ok(None);
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
