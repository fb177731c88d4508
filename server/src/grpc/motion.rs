//! The motion service: whole plans, streamed executions, sessions and groups on one phase.

use std::pin::Pin;
use std::sync::Arc;
use std::time::Duration;

use dmp::Stepping;
use dmp::execution::{GoalTolerance, GroupMember, join_group};
use dmp::field::Agent;
use dmp_proto::status::segment_status_limited;
use dmp_proto::v1;
use dmp_proto::v1::motion_service_server::MotionService;
use tokio::sync::mpsc;
use tokio_stream::wrappers::ReceiverStream;
use tokio_stream::{Stream, StreamExt};
use tonic::transport::server::TcpConnectInfo;
use tonic::{Request, Response, Status, Streaming};
use tracing::{debug, info};

use crate::access::{Action, Caller, Grant};
use crate::audit;
use crate::cells::cell::Cell;
use crate::connections::stream_permits::{Peer, StreamKind};
use crate::connections::write_batching::{BatchedConnectInfo, Urgency};
use crate::error::ServerError;
use crate::grpc::shared::ServiceState;
use crate::runs::compute::admission::ComputeReservation;
use crate::runs::control::Control;
use crate::runs::endpoints::{End, GoalGuard, Placed, refuse_inside};
use crate::runs::executing::Claim;
use crate::runs::ignored::push_obstacle_warnings;
use crate::runs::pacing::StreamConfig;
use crate::runs::pacing::{MAX_REFILL, history_len, refill_segments};
use crate::runs::plan::advance_cancellable;
use crate::runs::segments::{Batch, member_segments};
use crate::runs::served_run::ServedRun;
use crate::runs::stream::{Admitted, run_stream};
use crate::runs::stream_memory::StreamBytes;
use crate::runs::verdict::{Ending, Judge, verdict};

use super::limits_in_force;
use super::resolved_motion::{Intent, ResolvedMotion};
use super::session_commands::SessionCommands;
use super::stream_request::{DEFAULT_DT, StreamRequest};

/// Implements `dmp.v1.MotionService`.
#[derive(Debug, Clone)]
pub(crate) struct MotionServiceImpl {
    pub(super) state: Arc<ServiceState>,
}

impl MotionServiceImpl {
    /// The service over the shared state.
    pub(crate) fn new(state: Arc<ServiceState>) -> Self {
        Self { state }
    }
}

/// Whose a stream is: its robots, claimed until it ends, and what the access file allows it.
struct Owner {
    claim: Claim,
    grant: Grant,
}

type SegmentStream = Pin<Box<dyn Stream<Item = Result<v1::Segment, Status>> + Send + 'static>>;
type GroupStream = Pin<Box<dyn Stream<Item = Result<v1::GroupSegment, Status>> + Send + 'static>>;

/// Numbers per point per kind (position, velocity, acceleration) that a segment of `p` carries, rounded up: a pose
/// run's `n` positions and 4 + 3 + 3 orientation values fit in `3 (n + 4)`.
fn columns(p: &dmp::Primitive) -> usize {
    p.position_dim() + if p.orientation.is_some() { 4 } else { 0 }
}

impl MotionServiceImpl {
    /// The run of one robot.
    fn single_robot_run(
        &self,
        r: ResolvedMotion,
        stepping: Stepping,
        history: usize,
    ) -> Result<ServedRun, ServerError> {
        let dim = r.primitive.position_dim();
        let member = Agent { id: r.robot_id, dims: (0..dim).collect(), footprint: r.footprint };
        let mut run = ServedRun::new(
            r.primitive,
            r.motion,
            vec![(member, r.footprint_proto)],
            r.avoidance,
            stepping,
            history,
        )?;
        run.execution.set_goal_tolerance(r.goal_tolerance)?;
        if r.start_velocity.iter().any(|v| *v != 0.0) {
            run.execution
                .set_start_velocity(r.start_velocity)
                .map_err(|e| ServerError::from(e).within("motion"))?;
        }
        if let Some(chart) = r.chart {
            run.execution.set_orientation_chart(chart)?;
        }
        run.execution.set_tool(r.tool)?;
        run.execution.set_limits(r.in_force.limits, r.chart.is_some())?;
        run.execution.set_margin(r.in_force.margin)?;
        run.execution.set_goal_filter(r.goal_filter_alpha)?;
        Ok(run)
    }

    /// Refuses (FAILED_PRECONDITION) a run of `r` whose start or goal is inside one of the obstacles known now: the
    /// cell's scene (unless the run ignores it) and the run's own; `prefix` names the motion in the request.
    fn refuse_ends_in_collision(&self, r: &ResolvedMotion, prefix: &str) -> Result<(), ServerError> {
        let snapshot = (!r.avoidance.ignore_scene).then(|| r.cell.snapshot());
        let scene = snapshot.iter().flat_map(|s| s.obstacles.values().map(|o| &o.engine));
        let obstacles: Vec<&dmp::Obstacle> = scene.chain(&r.avoidance.extra).collect();
        if obstacles.is_empty() {
            return Ok(());
        }
        let n = r.primitive.position_dim();
        for (end, x) in [(End::Start, &r.motion.start), (End::Goal, &r.motion.goal)] {
            let orientation = r.chart.as_ref().and_then(|chart| {
                let y = x.get(n..n + 3)?;
                Some(dmp::orientation::pose::from_chart(chart, &nalgebra::Vector3::from_column_slice(y)))
            });
            let at = Placed { position: &x[..n.min(x.len())], orientation, tool: r.tool.as_ref() };
            refuse_inside(obstacles.iter().copied(), at, end, &format!("{prefix}.{}", end.field()))?;
        }
        Ok(())
    }

    /// Refuses, before any work, an answer that would exceed the message size: `values` numbers of position,
    /// velocity and acceleration (8 bytes each).
    fn check_message_size(&self, field: &str, values: usize) -> Result<(), ServerError> {
        let bytes = values.saturating_mul(3 * 8).saturating_add(1024);
        let max = self.state.config.limits.max_message_bytes;
        if bytes > max {
            return Err(ServerError::ResourceExhausted(format!(
                "{field}: the answer would take about {bytes} bytes, more than the limit of {max}"
            )));
        }
        Ok(())
    }
    /// Costs a stream in its cell as it is now and admits it: a real-time stream reserves its rate of the real-time
    /// budget while it runs; an as-fast-as-read one must fit the limit of one request.
    fn admit_stream(
        &self,
        run: &ServedRun,
        cell: &Cell,
        cfg: &StreamConfig,
    ) -> Result<Option<ComputeReservation>, ServerError> {
        let robots = cell.robot_count_besides(run.execution.members().iter().map(|m| m.id.as_str()));
        let w = run.workload(cell.snapshot().obstacles.len(), robots);
        let admission = &self.state.runs.compute.admission;
        let dt = cfg.stepping.dt;
        let segment = cfg.segment_points as f64;
        if cfg.realtime {
            // The longest wake-up: the scene rebuilt, then a lookahead and a refill of segments.
            let per_job =
                w.per_scene + w.of_points(segment + ((cfg.lookahead + MAX_REFILL).as_secs_f64() / dt).ceil());
            Ok(Some(admission.realtime(w.per_second(dt), per_job, "motion")?))
        } else {
            admission.check_job(w.per_scene + w.of_points(segment), "segment_s")?;
            admission.check_request(w.of_points(cfg.max_duration / dt), "max_duration_s")?;
            Ok(None)
        }
    }

    /// The grant of a stream executing `robots` in `cell`: it ends when a reload of the access file no longer allows
    /// it.
    fn grant(&self, caller: Caller, cell: &Cell, robots: Vec<String>) -> Result<Grant, ServerError> {
        let cell = cell.name().to_owned();
        self.state.access.grant(caller, move |c, access| {
            let robots: Vec<&str> = robots.iter().map(String::as_str).collect();
            c.check_again(access, &Action::Execute { cell: &cell, robots: &robots })
        })
    }

    /// Claims `robots` of `cell` for a new stream (see [`crate::runs::executing`]).
    async fn claim(&self, cell: &Cell, robots: &[&str], take_over: bool) -> Result<Claim, ServerError> {
        self.state.executing.claim(cell.name(), robots, take_over).await
    }

    /// Spawns the producer of a stream of `peer`, which holds `claim` until it ends, and returns the receiving end.
    /// The stream's permit, its memory (estimated now, refused when over a limit) and its compute reservation live
    /// in the producer task: all are released when it ends. Taken over, the stream ends at once with ABORTED (its
    /// robots' states stay: the stream taking over goes on with them).
    fn spawn(
        &self,
        run: ServedRun,
        cell: Cell,
        cfg: StreamConfig,
        control: Option<mpsc::Receiver<Control>>,
        peer: &Peer,
        Owner { claim, grant }: Owner,
    ) -> Result<mpsc::Receiver<Result<Batch, Status>>, ServerError> {
        // Real time: room for every segment computed in one wake-up (see `stream::MAX_REFILL`).
        let buffer = self.state.config.limits.stream_buffer.max(1)
            + if cfg.realtime { refill_segments(&cfg) } else { 0 };
        let memory = StreamBytes::estimate(&cfg, run.execution.dim(), buffer)
            .admit(&self.state.config.limits, &self.state.memory)?;
        let permit = self.state.stream_permit(StreamKind::Execution, peer)?;
        let budget = self.admit_stream(&run, &cell, &cfg)?;
        let (tx, rx) = mpsc::channel(buffer);
        let app = self.state.runs.clone();
        // A cell served for a dead server (fail-over): its streams end when it goes back.
        let given_back = self.state.cells.stream_guard(cell.name())?;
        let cell_name = cell.name().to_owned();
        tokio::spawn(async move {
            let taken_over = claim.taken_over();
            let moved = crate::cells::taken::moved(given_back, &cell_name);
            let shutdown = app.shutdown.clone();
            let ended = tokio::select! {
                _ = run_stream(app, run, cell, cfg, tx.clone(), control, Admitted { budget, grant: Some(grant) }) => None,
                _ = taken_over => Some(ServerError::Aborted("taken over by another stream".into())),
                moved = moved => Some(moved),
            };
            // Let go first: the stream taking over waits for it.
            drop(claim);
            if let Some(why) = ended {
                info!(reason = %why, "stream ended by another stream or a fail-over");
                let aborted = why.into();
                // A reader that stopped reading is not waited for long.
                tokio::select! {
                    _ = tx.send(Err(aborted)) => {}
                    _ = tokio::time::sleep(Duration::from_secs(1)) => {}
                    _ = shutdown.cancelled() => {}
                }
            }
            drop((permit, memory));
        });
        Ok(rx)
    }
}

/// The stream of a one-robot run: the only segment of each batch, the first one carrying the limits in force.
fn one_robot_stream(rx: mpsc::Receiver<Result<Batch, Status>>, limits: v1::LimitsInForce) -> SegmentStream {
    Box::pin(ReceiverStream::new(rx).map(move |r| r.map(|b| with_limits(b, &limits).remove(0))))
}

/// `batch`, each member's first segment (sequence 0) carrying the run's limits in force.
fn with_limits(mut batch: Batch, limits: &v1::LimitsInForce) -> Batch {
    for s in batch.iter_mut().filter(|s| s.sequence == 0) {
        s.limits = Some(limits.clone());
    }
    batch
}

#[tonic::async_trait]
impl MotionService for MotionServiceImpl {
    async fn plan(&self, request: Request<v1::PlanRequest>) -> Result<Response<v1::PlanResponse>, Status> {
        let caller = self.state.caller(&request)?;
        let req = request.into_inner();
        let r = ResolvedMotion::resolve(&self.state, &caller, Intent::Plan, req.motion.as_ref(), "motion")
            .await?;
        self.refuse_ends_in_collision(&r, "motion")?;
        let dt = if req.dt == 0.0 { DEFAULT_DT } else { req.dt };
        if !(dt.is_finite() && dt > 0.0 && dt <= 0.1) {
            return Err(ServerError::invalid("dt", "must be greater than 0 and at most 0.1 s").into());
        }
        let duration = if req.duration == 0.0 { 1.2 * r.motion.tau } else { req.duration };
        if !(duration.is_finite() && duration > 0.0) {
            return Err(ServerError::invalid("duration", "must be a finite number greater than zero").into());
        }
        let steps_f = (duration / dt).round();
        if steps_f > self.state.config.limits.max_steps as f64 {
            return Err(ServerError::ResourceExhausted(format!(
                "duration / dt = {steps_f} steps, more than the limit of {}",
                self.state.config.limits.max_steps
            ))
            .into());
        }
        let steps = (steps_f as usize).max(1);
        self.check_message_size("duration", (steps + 1) * columns(&r.primitive))?;
        let robot_id = r.robot_id.clone();
        let cell = r.cell.clone();
        let limits = r.in_force.reported.clone();
        // A plan is RK4 at the output rate, as the engine's own rollout; it ends at its last point.
        let chart = r.chart;
        let mut run = self.single_robot_run(r, Stepping::rk4(dt), 0)?;
        run.execution.set_end_time(steps as f64 * dt);
        run.judge = Judge::new(format!("at the plan's duration, t = {:.3} s", steps as f64 * dt), chart);
        let now = self.state.runs.clock.now_unix_s();
        let snapshot = cell.snapshot();
        let others = cell.other_robots(&robot_id, now, 0.5);
        let w = run.workload(snapshot.obstacles.len(), others.len());
        let _budget = self
            .state
            .runs
            .compute
            .admission
            .batch(w.per_scene + w.of_points((steps + 1) as f64), "duration")?;
        // On the batch pool: dropping this future (the client cancelled, left or passed its deadline) stops it.
        let (stretch, mut run) = self
            .state
            .runs
            .compute
            .batch
            .run(move |job| {
                let stretch = run
                    .apply_scene(&snapshot, &others, now)
                    .and_then(|()| advance_cancellable(&mut run.execution, steps + 1, job));
                (stretch, run)
            })
            .await
            .map_err(|e| ServerError::Internal(e.to_string()))?;
        let mut stretch = stretch?;
        let mut warnings = Vec::new();
        push_obstacle_warnings(&mut stretch.ignored, &mut warnings);
        let collisions: Vec<String> = run.execution.touched().iter().cloned().collect();
        let stalled = !stretch.stalls.is_empty();
        let status = segment_status_limited(stretch.outcome, stretch.limit);
        let ending = Ending::of(stretch.outcome).unwrap_or(Ending::OutOfTime);
        let batch = member_segments(&mut run, stretch, 0, status, None);
        // The plan's last point is its end: a plan that stopped short says so even when the engine's outcome does
        // not end it.
        let verdict = batch
            .first()
            .and_then(|s| s.verdict.clone())
            .unwrap_or_else(|| verdict(&run.execution, &run.judge, &batch, ending));
        let trajectory = batch.into_iter().next().map(|mut s| {
            s.verdict = Some(verdict.clone());
            s
        });
        let outcome = verdict.outcome().as_str_name();
        info!(robot = %robot_id, steps, collisions = collisions.len(), stalled, outcome, "planned");
        Ok(Response::new(v1::PlanResponse {
            trajectory,
            collisions,
            stalled,
            warnings,
            verdict: Some(verdict),
            limits: Some(limits),
        }))
    }

    type ExecuteStream = SegmentStream;

    async fn execute(
        &self,
        request: Request<v1::ExecuteRequest>,
    ) -> Result<Response<Self::ExecuteStream>, Status> {
        let (urgency, peer) = (urgency_of(&request), Peer::of(&request));
        let caller = self.state.caller(&request)?;
        let req = request.into_inner();
        let r = ResolvedMotion::resolve(&self.state, &caller, Intent::Execute, req.motion.as_ref(), "motion")
            .await?;
        self.refuse_ends_in_collision(&r, "motion")?;
        let cfg = StreamRequest::of(&req).config(r.motion.tau, &self.state.config, urgency)?;
        info!(robot = %r.robot_id, cell = r.cell.name(), realtime = cfg.realtime, "execute");
        self.check_message_size("segment_s", cfg.segment_points * columns(&r.primitive))?;
        let cell = r.cell.clone();
        let claim = self.claim(&cell, &[&r.robot_id], req.take_over).await?;
        audit!(caller, "execute", cell = cell.name(), robot = %r.robot_id, take_over = req.take_over);
        let grant = self.grant(caller, &cell, vec![r.robot_id.clone()])?;
        let (chart, limits) = (r.chart, r.in_force.reported.clone());
        let mut run = self.single_robot_run(r, cfg.stepping, history_len(&cfg))?;
        run.judge = Judge::new(end_label(req.max_duration_s, &cfg), chart);
        let rx = self.spawn(run, cell, cfg, None, &peer, Owner { claim, grant })?;
        Ok(Response::new(one_robot_stream(rx, limits)))
    }

    type SessionStream = SegmentStream;

    async fn session(
        &self,
        request: Request<Streaming<v1::SessionRequest>>,
    ) -> Result<Response<Self::SessionStream>, Status> {
        use v1::session_request::Message as M;
        let (urgency, peer) = (urgency_of(&request), Peer::of(&request));
        let caller = self.state.caller(&request)?;
        let mut inbound = request.into_inner();
        let first = tokio::time::timeout(Duration::from_secs(10), inbound.message())
            .await
            .map_err(|_| ServerError::invalid("message", "no `start` message within 10 s"))??;
        let Some(v1::SessionRequest { message: Some(M::Start(req)) }) = first else {
            return Err(
                ServerError::invalid("message", "the first message of a session must be `start`").into()
            );
        };
        let r = ResolvedMotion::resolve(
            &self.state,
            &caller,
            Intent::Execute,
            req.motion.as_ref(),
            "start.motion",
        )
        .await?;
        self.refuse_ends_in_collision(&r, "start.motion")?;
        let cfg = StreamRequest::of(&req)
            .config(r.motion.tau, &self.state.config, urgency)
            .map_err(|e| e.within("start"))?;
        let robot_id = r.robot_id.clone();
        let (dim, pose) = (r.primitive.position_dim(), r.chart.is_some());
        self.check_message_size("start.segment_s", cfg.segment_points * columns(&r.primitive))?;
        let cell = r.cell.clone();
        let claim = self.claim(&cell, &[&r.robot_id], req.take_over).await.map_err(|e| e.within("start"))?;
        audit!(caller, "session", cell = cell.name(), robot = %robot_id, take_over = req.take_over);
        let grant = self.grant(caller.clone(), &cell, vec![robot_id.clone()])?;
        let (chart, in_force) = (r.chart, r.in_force.reported.clone());
        let goals = GoalGuard {
            cell: cell.clone(),
            extra: r.avoidance.extra.clone(),
            ignore_scene: r.avoidance.ignore_scene,
            tool: r.tool.clone(),
        };
        let mut run = self.single_robot_run(r, cfg.stepping, history_len(&cfg))?;
        run.judge = Judge::new(end_label(req.max_duration_s, &cfg), chart);
        let (ctl_tx, ctl_rx) = mpsc::channel(64);
        let rx = self.spawn(run, cell, cfg, Some(ctl_rx), &peer, Owner { claim, grant })?;
        let shutdown = self.state.runs.shutdown.clone();
        let limits = &self.state.config.limits;
        let commands = SessionCommands::new(
            robot_id.clone(),
            dim,
            pose,
            limits.workspace_m,
            self.state.state_admission.clone(),
            self.state.runs.clock,
        );
        // Reads the robot's messages; a bad one is rejected with a warning on the reply stream (the run goes on),
        // the end of the inbound stream stops nothing (the robot may just have nothing more to say).
        tokio::spawn(async move {
            loop {
                let msg = tokio::select! {
                    m = inbound.message() => m,
                    _ = shutdown.cancelled() => break,
                };
                let Ok(Some(msg)) = msg else { break };
                let control = match commands.control(msg.message) {
                    // A goal inside an obstacle is refused as a command: the run goes on to its former goal.
                    Control::SetGoal(goal, q) => match goals.rejected(&goal, q) {
                        Some(w) => Control::Rejected(w),
                        None => Control::SetGoal(goal, q),
                    },
                    c => c,
                };
                match &control {
                    Control::Rejected(w) => {
                        debug!(field = %w.field, reason = %w.reason, "session message rejected")
                    }
                    Control::SetGoal(goal, orientation) => {
                        audit!(caller, "set goal", robot = %robot_id, ?goal, ?orientation)
                    }
                    Control::SetTau(tau) => audit!(caller, "set tau", robot = %robot_id, tau),
                    Control::Pause => audit!(caller, "pause", robot = %robot_id),
                    Control::Resume => audit!(caller, "resume", robot = %robot_id),
                    Control::Stop => audit!(caller, "stop", robot = %robot_id),
                    Control::State(_) => {}
                }
                if ctl_tx.send(control).await.is_err() {
                    break;
                }
            }
        });
        Ok(Response::new(one_robot_stream(rx, in_force)))
    }

    type ExecuteGroupStream = GroupStream;

    async fn execute_group(
        &self,
        request: Request<v1::ExecuteGroupRequest>,
    ) -> Result<Response<Self::ExecuteGroupStream>, Status> {
        let (urgency, peer) = (urgency_of(&request), Peer::of(&request));
        let caller = self.state.caller(&request)?;
        let req = request.into_inner();
        if req.members.len() < 2 {
            return Err(ServerError::invalid("members", "a group needs at least two members").into());
        }
        if req.members.len() > 64 {
            return Err(ServerError::ResourceExhausted("members: at most 64 robots per group".into()).into());
        }
        let mut resolved = Vec::with_capacity(req.members.len());
        for (i, m) in req.members.iter().enumerate() {
            let prefix = format!("members[{i}].motion");
            let r =
                ResolvedMotion::resolve(&self.state, &caller, Intent::Execute, m.motion.as_ref(), &prefix)
                    .await?;
            if r.cell.name() != resolved.first().map_or(r.cell.name(), |f: &ResolvedMotion| f.cell.name()) {
                return Err(ServerError::invalid(
                    format!("members[{i}].motion.cell"),
                    format!(
                        "must be the first member's cell `{}`: a group works in one cell",
                        resolved[0].cell.name()
                    ),
                )
                .into());
            }
            self.refuse_ends_in_collision(&r, &prefix)?;
            resolved.push(r);
        }
        let tau =
            if req.tau == 0.0 { resolved.iter().map(|r| r.motion.tau).fold(0.0, f64::max) } else { req.tau };
        if !(tau.is_finite() && tau > 0.0) {
            return Err(ServerError::invalid("tau", "must be a finite number greater than zero").into());
        }
        // One DMP: the members' primitives side by side (the paper's 6-D youBot DMP).
        let group: Vec<GroupMember<'_>> = resolved
            .iter()
            .map(|r| GroupMember {
                id: &r.robot_id,
                primitive: &r.primitive,
                motion: &r.motion,
                footprint: r.footprint.as_ref(),
            })
            .collect();
        let (primitive, motion, agents) = join_group(&group, Some(tau)).map_err(|e| {
            // The engine names a member's fields; the request holds them in its motion.
            match ServerError::from(e) {
                ServerError::InvalidArgument { field, reason } => ServerError::InvalidArgument {
                    field: field.replacen("].", "].motion.", 1).replace(".motion.id", ".motion.robot_id"),
                    reason,
                },
                other => other,
            }
        })?;
        let cfg = StreamRequest::of_group(&req).config(tau, &self.state.config, urgency)?;
        let cell = resolved[0].cell.clone();
        // The members' extra obstacles, once each (members often repeat the same ones).
        let mut avoidance = resolved[0].avoidance.clone();
        avoidance.extra.clear();
        for r in &resolved {
            for o in &r.avoidance.extra {
                if !avoidance.extra.iter().any(|e| e.id() == o.id()) {
                    avoidance.extra.push(o.clone());
                }
            }
        }
        // Every member within its own tolerance: the tightest of each.
        let goal_tolerance =
            resolved.iter().map(|r| r.goal_tolerance).fold(resolved[0].goal_tolerance, |a, b| {
                GoalTolerance {
                    position: a.position.min(b.position),
                    speed: a.speed.min(b.speed),
                    angle: a.angle.min(b.angle),
                    angular_speed: a.angular_speed.min(b.angular_speed),
                }
            });
        // One phase, one set of limits: the tightest of the members'; the goal filter of the first member.
        let in_force = limits_in_force::group(&resolved.iter().map(|r| &r.in_force).collect::<Vec<_>>());
        let goal_filter_alpha = resolved[0].goal_filter_alpha;
        let members =
            agents.into_iter().zip(resolved.into_iter().map(|r| r.footprint_proto)).collect::<Vec<_>>();
        info!(robots = members.len(), realtime = cfg.realtime, "execute group");
        self.check_message_size("segment_s", cfg.segment_points * primitive.dim)?;
        let ids: Vec<&str> = members.iter().map(|(agent, _)| agent.id.as_str()).collect();
        let claim = self.claim(&cell, &ids, req.take_over).await?;
        audit!(caller, "execute group", cell = cell.name(), robots = ?ids, take_over = req.take_over);
        let grant = self.grant(caller, &cell, ids.iter().map(|id| id.to_string()).collect())?;
        let mut run = ServedRun::new(primitive, motion, members, avoidance, cfg.stepping, history_len(&cfg))?;
        run.execution.set_goal_tolerance(goal_tolerance).map_err(ServerError::from)?;
        run.execution.set_limits(in_force.limits, false).map_err(ServerError::from)?;
        run.execution.set_margin(in_force.margin).map_err(ServerError::from)?;
        run.execution.set_goal_filter(goal_filter_alpha).map_err(ServerError::from)?;
        run.judge = Judge::new(end_label(req.max_duration_s, &cfg), None);
        let rx = self.spawn(run, cell, cfg, None, &peer, Owner { claim, grant })?;
        let limits = in_force.reported;
        let stream = ReceiverStream::new(rx).map(move |r| {
            r.map(|segments| v1::GroupSegment {
                sequence: segments.first().map(|s| s.sequence).unwrap_or(0),
                segments: with_limits(segments, &limits),
            })
        });
        Ok(Response::new(Box::pin(stream)))
    }
}

/// How a stream's time is bounded, for the verdict of a run that ran out of it: `max_duration_s` as requested (0: 3
/// tau), `cfg` as resolved.
fn end_label(max_duration_s: f64, cfg: &StreamConfig) -> String {
    if max_duration_s == 0.0 {
        format!("at 3 tau, t = {:.3} s", cfg.max_duration)
    } else {
        format!("at max_duration_s, t = {:.3} s", cfg.max_duration)
    }
}

/// The urgency of the connection a request came on, when it batches its writes (`write_batching`).
fn urgency_of<T>(request: &Request<T>) -> Option<Urgency> {
    request.extensions().get::<BatchedConnectInfo<TcpConnectInfo>>().map(|c| c.urgency.clone())
}
