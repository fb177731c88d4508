//! The producer task of a streamed execution: one task and one bounded channel per stream (the bound is the
//! backpressure: a slow reader holds the producer, never grows memory). Real-time pacing keeps the segments sent
//! between `lookahead` and `lookahead + refill` ahead of the wall clock, waking once per refill rather than once
//! per segment; a scene change or a command is applied from the robot's current time by rolling back and sending a
//! segment that supersedes the points already sent. The stepping itself is the engine's ([`dmp::Execution`]), and
//! it runs on a compute thread ([`crate::runs::compute`]): real-time streams on the real-time pool, the others on the
//! batch pool; this task only waits, sends and publishes.

use std::sync::Arc;
use std::time::Duration;

use dmp_proto::status::end_reason;
use dmp_proto::v1;
use tokio::sync::{mpsc, watch};
use tokio::time::Instant;
use tracing::{debug, info, warn};

use super::context::RunContext;
use super::control::Control;
use super::pacing::{FIRST_POINT_DELAY, ROLLBACK_MARGIN, StreamConfig, refill};
use super::segments::Batch;
use super::served_run::ServedRun;
use super::step::{Step, Stepped, compute};
use crate::access::Grant;
use crate::cells::cell::{Cell, ObstacleSet, SeenRobot};
use crate::cells::staleness::StaleGuard;
use crate::error::ServerError;
use crate::runs::compute::admission::ComputeReservation;
use crate::runs::compute::pool::Pool;

/// Robot states older than this are ignored.
const REMOTE_MAX_AGE_S: f64 = 0.5;

/// What a stream was admitted with, held until it ends.
#[derive(Debug, Default)]
pub(crate) struct Admitted {
    /// Real time: its compute reservation.
    pub budget: Option<ComputeReservation>,
    /// What the access file allows it (none: nothing to check again).
    pub grant: Option<Grant>,
}

/// Runs `run` until the goal, a stop, `max_duration`, the client leaving or shutdown. Items go to `tx` (mapped by
/// the caller's stream); errors end the stream with a status.
pub(crate) async fn run_stream(
    app: Arc<RunContext>,
    mut run: ServedRun,
    cell: Cell,
    cfg: StreamConfig,
    tx: mpsc::Sender<Result<Batch, tonic::Status>>,
    control: Option<mpsc::Receiver<Control>>,
    admitted: Admitted,
) {
    run.execution.set_end_time(cfg.max_duration);
    let _in_cell = cell.stream_opened();
    let ids: Vec<String> = run.execution.members().iter().map(|m| m.id.clone()).collect();
    let stale = StaleGuard::new(cell.staleness(), run.ignore_scene);
    let mut producer = Producer::new(&app, &cell, &cfg, &tx, control, run);
    producer.stale = stale;
    producer.budget = admitted.budget;
    producer.grant = admitted.grant;
    let result = producer.produce().await;
    let t = producer.time;
    drop(producer);
    for id in &ids {
        app.robots.retire(&cell, id).await;
    }
    app.ros2_out.ended(cell.name(), &ids);
    match result {
        Ok(reason) => info!(robots = ?ids, reason, t, "stream ended"),
        Err(ServerError::Cancelled(reason)) => info!(robots = ?ids, reason, t, "stream ended"),
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
    app: &'a RunContext,
    cell: &'a Cell,
    cfg: &'a StreamConfig,
    tx: &'a mpsc::Sender<Result<Batch, tonic::Status>>,
    control: Option<mpsc::Receiver<Control>>,
    /// The run; on a compute thread while a wake-up computes (`None` only if that computation failed). Boxed: it
    /// goes to a compute thread and back at every wake-up, and a pointer is cheaper to move than the run.
    run: Option<Box<ServedRun>>,
    /// Where the run is computed: the real-time pool or the batch pool.
    pool: &'a Pool,
    /// The run's current time (its next point).
    time: f64,
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
    /// Real time: the run's compute reservation, resized to its scene as it changes.
    budget: Option<ComputeReservation>,
    /// The real-time budget was over its limit at the last resize (warned once per crossing).
    over_budget: bool,
    /// What the access file allows the stream: it ends with PERMISSION_DENIED once a reload no longer does.
    grant: Option<Grant>,
    /// Real time: when the scene change applied at this wake-up was received (Unix seconds), until the first
    /// segment computed with it is sent (`dmp_obstacle_update_to_segment_seconds`).
    scene_update_unix_s: Option<f64>,
}

impl<'a> Producer<'a> {
    fn new(
        app: &'a RunContext,
        cell: &'a Cell,
        cfg: &'a StreamConfig,
        tx: &'a mpsc::Sender<Result<Batch, tonic::Status>>,
        control: Option<mpsc::Receiver<Control>>,
        run: ServedRun,
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
            time: run.execution.time(),
            run: Some(Box::new(run)),
            pool: if cfg.realtime { &app.compute.realtime } else { &app.compute.batch },
            scene_rx: cell.subscribe(),
            others: Vec::new(),
            start: app.clock.now() + delay,
            start_unix: app.clock.now_unix_s() + delay.as_secs_f64(),
            sequence: 0,
            finished: None,
            warnings: Vec::new(),
            stale: StaleGuard::new(cell.staleness(), false),
            budget: None,
            over_budget: false,
            grant: None,
            scene_update_unix_s: None,
        }
    }

    /// The loop: wait, apply what changed, send what is due.
    async fn produce(&mut self) -> Result<&'static str, ServerError> {
        let mut wake = Wake { scene_changed: true, commands: Vec::new() };
        // The first wake-up applies the scene as it is now.
        self.scene_rx.borrow_and_update();
        let mut first = true;
        loop {
            if let Some(reason) = self.wake_up(std::mem::take(&mut wake), first).await? {
                return Ok(reason);
            }
            first = false;
            match self.wait().await? {
                Ok(w) => wake = w,
                Err(reason) => return Ok(reason),
            }
        }
    }

    /// Real time: sleeps until the next segment is due (or the run's last point executed) while reacting to
    /// changes; as fast as read: takes what is pending. `Err(reason)` when the stream is over.
    async fn wait(&mut self) -> Result<Result<Wake, &'static str>, ServerError> {
        let mut wake = Wake::default();
        if self.cfg.realtime {
            let due = match self.finished {
                Some((t_end, _)) => self.start + Duration::from_secs_f64(t_end),
                None => (self.start + Duration::from_secs_f64(self.time))
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
                denied = revoked(&mut self.grant) => return Err(denied),
            }
        } else {
            if self.app.shutdown.is_cancelled() {
                return Err(ServerError::ShuttingDown);
            }
            if let Some(g) = self.grant.as_mut() {
                g.check_now()?;
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

    /// Applies a wake-up's changes from the robot's current time (rolling back what was computed ahead of it) and
    /// sends what is due: one segment as fast as read; in real time, up to a refill beyond the lookahead (a
    /// superseding segment goes out on its own first). Measured states are published and change nothing in the
    /// plan. `Some(reason)` when the stream is over.
    async fn wake_up(&mut self, wake: Wake, first: bool) -> Result<Option<&'static str>, ServerError> {
        // Real time: a wake-up by messages alone (states, rejections) sends nothing ahead of time; what they leave
        // goes with the next segment, due within a refill.
        let messages_only = self.cfg.realtime && !wake.scene_changed && !wake.commands.is_empty();
        let mut changes_plan = wake.scene_changed && !first;
        let mut commands = Vec::with_capacity(wake.commands.len());
        for c in wake.commands {
            match c {
                Control::State(s) => self.publish_measured(s).await,
                Control::Rejected(w) => {
                    self.warnings.push(w);
                    // Once the last segment is sent, only a superseding one can still carry it.
                    changes_plan |= self.finished.is_some();
                }
                c => {
                    changes_plan = true;
                    commands.push(c);
                }
            }
        }
        if messages_only && !changes_plan {
            return Ok(None);
        }
        let realtime = self.cfg.realtime;
        let rollback_to = (changes_plan && realtime)
            .then(|| (self.start.elapsed() + ROLLBACK_MARGIN).as_secs_f64() + self.cfg.stepping.dt);
        if rollback_to.is_some() {
            self.finished = None;
        }
        if !changes_plan && self.finished.is_some() {
            return Ok(None);
        }
        let scene = wake.scene_changed.then(|| self.scene_rx.borrow_and_update().clone());
        if let Some(s) = &scene {
            self.stale.observe(s, &mut self.warnings);
            self.recost(s.obstacles.len());
            debug!(version = s.version, "scene applied");
            if realtime && !first && s.updated_unix_s > 0.0 {
                self.scene_update_unix_s = Some(s.updated_unix_s);
            }
        }
        for c in &commands {
            match c {
                Control::Pause => self.stale.note_paused(true),
                Control::Resume => self.stale.note_paused(false),
                _ => {}
            }
        }
        let horizon = realtime.then(|| {
            (self.start.elapsed() + self.cfg.lookahead + refill(self.app.open_streams())).as_secs_f64()
        });
        // A segment that supersedes points already sent goes out on its own, before the rest of the refill.
        let supersedes = changes_plan && realtime;
        let mut step = Step {
            rollback_to,
            scene,
            others: self.cell_mates(rollback_to.unwrap_or(self.time)),
            start_unix: realtime.then_some(self.start_unix),
            now_unix_s: self.app.clock.now_unix_s(),
            commands,
            hold: self.stale.hold(),
            horizon,
            max_segments: if supersedes || !realtime { 1 } else { usize::MAX },
            segment_points: self.cfg.segment_points,
            sequence: self.sequence,
        };
        let stepped = self.on_pool(step).await?;
        let sent = self.send(stepped, supersedes).await?;
        // Measured at the first segment sent after the change, if this wake-up sent one; never at a later one.
        self.scene_update_unix_s = None;
        if let Some(reason) = sent {
            return Ok(Some(reason));
        }
        if supersedes && self.finished.is_none() && horizon.is_some_and(|h| self.time < h) {
            // A change wakes every stream of the cell at once: the others send their superseding segment before
            // this one computes the rest of its refill.
            tokio::task::yield_now().await;
            step = Step {
                rollback_to: None,
                scene: None,
                others: self.cell_mates(self.time),
                start_unix: Some(self.start_unix),
                now_unix_s: self.app.clock.now_unix_s(),
                commands: Vec::new(),
                hold: None,
                horizon,
                max_segments: usize::MAX,
                segment_points: self.cfg.segment_points,
                sequence: self.sequence,
            };
            let stepped = self.on_pool(step).await?;
            return self.send(stepped, false).await;
        }
        Ok(None)
    }

    /// Real time: resizes the run's reservation to the scene it now avoids (`obstacles` in the cell), so that new
    /// runs are admitted against the true load. A run is never stopped for it (it must go on avoiding what is
    /// there): when the reservations go over the real-time budget, the robot is warned once, and again after they
    /// fit and go over once more.
    fn recost(&mut self, obstacles: usize) {
        let (Some(budget), Some(run)) = (self.budget.as_mut(), self.run.as_ref()) else { return };
        let robots = self.cell.robot_count_besides(run.execution.members().iter().map(|m| m.id.as_str()));
        let per_second = run.workload(obstacles, robots).per_second(self.cfg.stepping.dt);
        let within = budget.resize(per_second);
        if !within && !self.over_budget {
            warn!(
                cell = self.cell.name(),
                obstacles, per_second, "real-time runs are over the compute budget"
            );
            self.warnings.push(v1::Warning {
                kind: v1::warning::Kind::ComputeOverBudget as i32,
                field: String::new(),
                reason: format!(
                    "the cell's scene grew to {obstacles} obstacles after this run was admitted: it now needs \
                     {per_second:.2e} work units per second and the real-time runs reserve more than the budget \
                     (`compute.realtime_work_per_thread_s`); it goes on avoiding every obstacle, new real-time runs \
                     are refused until the reservations fit"
                ),
                obstacle_id: String::new(),
            });
        }
        self.over_budget = !within;
    }

    /// Runs one wake-up's computation on the stream's pool.
    async fn on_pool(&mut self, step: Step) -> Result<Stepped, ServerError> {
        let mut run = self.run.take().ok_or_else(|| ServerError::Internal("the run was lost".into()))?;
        let (run, stepped) = tokio::select! {
            r = self.pool.run(move |job| {
                let stepped = compute(&mut run, step, job);
                (run, stepped)
            }) => r.map_err(|e| ServerError::Internal(e.to_string()))?,
            _ = self.app.shutdown.cancelled() => return Err(ServerError::ShuttingDown),
            // Dropping the computation cancels it: nobody reads what it would compute.
            _ = self.tx.closed() => return Err(ServerError::Cancelled("client left".into())),
        };
        self.time = run.execution.time();
        self.run = Some(run);
        stepped
    }

    /// Sends the segments computed, then publishes the members' states at the first one. `Some(reason)` when the
    /// stream is over.
    async fn send(&mut self, stepped: Stepped, urgent: bool) -> Result<Option<&'static str>, ServerError> {
        let Stepped { segments, states, warnings } = stepped;
        self.warnings.extend(warnings);
        let app = self.app;
        for (k, mut computed) in segments.into_iter().enumerate() {
            for segment in &mut computed.batch {
                segment.scene_stale = self.stale.is_stale();
            }
            if !self.warnings.is_empty() {
                for segment in &mut computed.batch {
                    segment.warnings.clone_from(&self.warnings);
                }
                self.warnings.clear();
            }
            let members = computed.batch.len() as u64;
            // A segment that supersedes points already sent cannot wait for the connection's batched write.
            if urgent
                && k == 0
                && let Some(urgency) = &self.cfg.urgency
            {
                urgency.write_now();
            }
            // The robot first: publishing the states may wait on Zenoh (a robot's first state declares its
            // publisher).
            let first_point_unix_s = computed.batch.first().map(|s| s.start_unix_s);
            let for_ros2 = app.ros2_out.copy_of(&computed.batch);
            tokio::select! {
                sent = self.tx.send(Ok(computed.batch)) => if sent.is_err() { return Ok(Some("client left")) },
                _ = app.shutdown.cancelled() => return Err(ServerError::ShuttingDown),
            }
            app.ros2_out.offer(self.cell.name(), for_ros2, app.clock.now_unix_s());
            if self.cfg.realtime {
                let (now, update) = (app.clock.now_unix_s(), self.scene_update_unix_s.take());
                app.histograms.handed_over(now, first_point_unix_s, update);
            }
            if k == 0 {
                // One state per wake-up: the cell-mates read them at their own wake-ups (once per refill) and
                // extrapolate them with the velocity.
                for (state, footprint) in &states {
                    app.robots.publish(self.cell, state.clone(), footprint.clone()).await;
                }
            }
            app.counters.segments_sent.fetch_add(members, std::sync::atomic::Ordering::Relaxed);
            self.sequence += 1;
            if let Some(reason) = end_reason(computed.outcome) {
                if !self.cfg.realtime {
                    return Ok(Some(reason));
                }
                // Keep the stream open until the robot has executed the last point: a change may still supersede
                // it.
                self.finished = Some((computed.last_point_time, reason));
            }
        }
        Ok(None)
    }

    /// Publishes a state the robot measured (it changes nothing in the plan).
    async fn publish_measured(&self, s: v1::RobotState) {
        let footprint = self.run.as_ref().and_then(|run| {
            run.execution.members().iter().find(|m| m.id == s.robot_id).and_then(|m| m.footprint.clone())
        });
        self.app.robots.publish(self.cell, s, footprint).await;
    }

    /// The cell's other robots as they are at run time `t`.
    fn cell_mates(&mut self, t: f64) -> Vec<Arc<SeenRobot>> {
        let Some(first) = self.run.as_ref().and_then(|r| r.execution.members().first()) else {
            return Vec::new();
        };
        let now = if self.cfg.realtime { self.start_unix + t } else { self.app.clock.now_unix_s() };
        self.cell.other_robots_into(&first.id, now, REMOTE_MAX_AGE_S, &mut self.others);
        self.others.clone()
    }
}

async fn revoked(grant: &mut Option<Grant>) -> ServerError {
    match grant {
        Some(g) => g.revoked().await,
        None => std::future::pending().await,
    }
}

async fn recv(control: &mut Option<mpsc::Receiver<Control>>) -> Option<Control> {
    match control {
        Some(rx) => rx.recv().await,
        None => std::future::pending().await,
    }
}
