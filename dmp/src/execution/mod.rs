//! One run on one phase: a robot, or a group of robots sharing a DMP, stepped stretch by stretch to a given time.
//! The offline rollout ([`mod@crate::rollout`]), the scenario runs and the server's streams all step through
//! [`Execution`], so that the offline and the served paths agree by construction.
//!
//! Changes (a new goal or `tau`, pause, resume and stop, new obstacles, the cell-mates' motion) apply from the
//! next output point, never by a jump; the run can roll back to a recent point so that a new stretch supersedes
//! points already handed out.
//!
//! Stepping ([`Stepping`]): RK4 on an internal grid of `step_points` output steps, the output points in between
//! being the quintic Hermite interpolant of the two knots around them (`dense.rs`); every change restarts the
//! grid at the next output point, so a change takes effect exactly where it would with RK4 at the output rate. With
//! a tolerance the grid adapts instead: Dormand–Prince 5(4) steps of a whole number of output steps, at most
//! `step_points`, each accepted when its error estimate is within the tolerance
//! (`integrate/dormand_prince.rs`), and never beyond the limit the caller sets
//! ([`Execution::limit_knots_to`]: where its next change can apply, so that no step is computed past it for
//! nothing).
//!
//! Outcomes ([`Outcome`]): arrival, stall, contact, holding, stop and the end time, judged on the points handed out.
//!
//! Without jumps: a new goal is approached through the goal filter (`goal_changes.rs`,
//! [`crate::integrate::goal_filter`]), and a change of the obstacles is blended in (`blend.rs`), so that the
//! acceleration stays continuous. A robot's [`Limits`] are kept at every point handed out (`limiting.rs`): the phase
//! slows first (temporal coupling), a limiter holds each setpoint within them, and the robot brakes to rest where
//! the DMP asks for far more ([`Stretch::limit`]). A safety distance ([`Execution::set_margin`], `guard.rs`) keeps it
//! off the obstacles' true shapes: the field acts on them inflated, and a robot that can brake brakes to rest before
//! the margin where the field cannot keep it ([`LimitAction::Blocked`]); each stretch reports its clearance
//! (`clearance.rs`).

mod advance;
mod blend;
mod changes;
mod clearance;
mod diagnosis;
mod field_sum;
mod fields;
mod goal_changes;
mod goal_tolerance;
mod grid;
mod group;
mod guard;
mod history;
mod hold;
mod ignored;
mod limiter;
mod limiting;
mod limits;
mod pose;
mod stepping;
#[cfg(feature = "orientation")]
mod tool;
mod tracking;

use crate::avoidance::Avoidance;
use crate::dense::{Interpolant, Knot};
use crate::error::Result;
use crate::field::{Agent, Contact, RepulsiveField, Scene};
use crate::integrate::goal_filter::{DEFAULT_GOAL_ALPHA, GoalFilter};
use crate::integrate::{Integrator, Motion, State};
use crate::primitive::Primitive;
use crate::stall::{Stall, StallConfig, StallDetector};

use self::blend::Blend;
pub use self::blend::DEFAULT_OBSTACLE_BLEND;
pub use self::clearance::EXACT_WITHIN as CLEARANCE_EXACT_WITHIN;
pub use self::goal_tolerance::GoalTolerance;
pub use self::group::{GroupMember, join_group};
use self::guard::Guard;
use self::history::History;
use self::ignored::Ignored;
pub use self::ignored::IgnoredObstacle;
use self::limiter::Limiter;
pub use self::limiting::{KEEP_OFF, LimitAction, Limits};
pub use self::pose::OrientationPoints;
pub(crate) use self::stepping::check_stability;
pub use self::stepping::{IntegrationCost, MAX_STIFF_STEP, Stepping};
use self::tracking::Tracker;

/// The default speed under which a robot has arrived, and the speed under which a stop has come to rest.
pub(crate) const ARRIVED_SPEED: f64 = GoalTolerance::DEFAULT.speed;

/// What a stretch of points came to. Later variants are not "worse": see [`Execution::advance`] for the order in
/// which they are judged.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Outcome {
    /// Moving.
    #[default]
    Running,
    /// Holding (a pause, or a stop still decelerating).
    Holding,
    /// A robot stopped away from its goal.
    Stalled,
    /// A robot is inside an obstacle's true shape or another robot's footprint.
    Collision,
    /// Every robot at its goal and at rest: the run is complete.
    GoalReached,
    /// A stop came to rest: the run is complete.
    Stopped,
    /// The last point is at the end time ([`Execution::set_end_time`]): the run is complete.
    EndTime,
}

impl Outcome {
    /// True when the run is complete after this stretch.
    pub fn is_final(self) -> bool {
        matches!(self, Outcome::GoalReached | Outcome::Stopped | Outcome::EndTime)
    }
}

/// How the cell's other robots are avoided: they are moving obstacles of this method.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellMateAvoidance {
    /// The method.
    pub method: Avoidance,
    /// Boundary samples of a footprint for the point methods.
    pub point_samples: usize,
}

impl CellMateAvoidance {
    /// Cell-mates are not avoided.
    pub const NONE: Self = Self { method: Avoidance::NONE, point_samples: 0 };
}

/// Another robot of the cell, seen `age` seconds before the run's current time at `position`, moving at
/// `velocity`, with its footprint: a moving obstacle for every member.
#[derive(Debug, Clone, Copy)]
pub struct CellMate<'a> {
    /// Its id.
    pub id: &'a str,
    /// What the members avoid, centred on its position.
    pub footprint: &'a crate::Shape,
    /// Where it was.
    pub position: &'a [f64],
    /// Its velocity then.
    pub velocity: &'a [f64],
    /// How long before the run's current time it was there.
    pub age: f64,
}

/// The output points of one [`Execution::advance`], one output step apart.
#[derive(Debug, Clone, Default)]
pub struct Stretch {
    /// Time of the first point.
    pub start_time: f64,
    /// Positions, row-major (the DMP's dimension per point).
    pub x: Vec<f64>,
    /// Velocities `dx/dt`.
    pub xd: Vec<f64>,
    /// Accelerations.
    pub xdd: Vec<f64>,
    /// What the stretch came to.
    pub outcome: Outcome,
    /// Contacts with the run's obstacles and between its members, with the index of the point (within the
    /// stretch); the indices are those of [`Execution::field`].
    pub contacts: Vec<(usize, Contact)>,
    /// Contacts with the cell-mates, with the index of the point.
    pub cell_mate_contacts: Vec<(usize, Contact)>,
    /// Stalls detected, with the index of the member.
    pub stalls: Vec<(usize, Stall)>,
    /// Obstacles (and cell-mates) the run stopped avoiding since the last stretch, and why: each is reported once.
    pub ignored: Vec<IgnoredObstacle>,
    /// A pose run's orientations at the points (empty otherwise).
    pub orientation: OrientationPoints,
    /// What keeping the run's limits did in the stretch ([`Execution::set_limits`]): the most that happened.
    pub limit: LimitAction,
    /// Per member: the smallest distance over the stretch's points from its point to an obstacle's true shape,
    /// exact under [`clearance::EXACT_WITHIN`] and a lower bound beyond (`execution/clearance.rs`);
    /// `f64::INFINITY` without obstacles.
    pub min_clearance: Vec<f64>,
}

/// One run of a primitive on one phase: the state machine that the offline rollout and the server's streams step.
#[derive(Debug)]
pub struct Execution {
    primitive: Primitive,
    integrator: Integrator,
    motion: Motion,
    stepping: Stepping,
    /// The fields being replaced by `field`, blended out ([`blend`]).
    blend: Blend,
    /// How far back a rollback can go, seconds.
    history_span: f64,
    /// The fixed part of the field: the run's own obstacles, its members and their methods.
    scene: Scene,
    /// How the cell-mates are avoided.
    cell_mate_avoidance: CellMateAvoidance,
    /// Obstacles of the cell (set by [`Execution::set_obstacles`]) then the run's own, and the members.
    field: RepulsiveField,
    /// The cell's other robots.
    cell_mates: RepulsiveField,
    /// The grid point the output is in, and the next one (None until computed after a change).
    knot0: Knot,
    knot1: Option<Knot>,
    /// Buffers of a knot dropped by a change, for the next one.
    spare: Option<Knot>,
    /// `knot0.xdd` is the acceleration at `knot0` under the current field and motion (it was computed as the
    /// previous step's end knot and nothing changed since): the next step reuses it as its first stage.
    acc0_current: bool,
    /// `knot1.xdd` is the acceleration at `knot1`'s own state under the field and motion of its step (not a fine
    /// step's that did not evaluate it).
    knot1_acc: bool,
    /// The interpolant of `knot0` and `knot1`, fitted when `knot1` is computed.
    interpolant: Interpolant,
    /// Scratch acceleration of an interpolated point.
    xdd: Vec<f64>,
    /// Where a step computes the next knot.
    scratch: State,
    /// Time of the next output point.
    out_t: f64,
    /// Adaptive step: the next step to try, in output steps.
    next_points: usize,
    /// No knot beyond this time (adaptive step).
    knot_limit: f64,
    /// The run is complete at this time.
    end_time: f64,
    /// The recent output points (their states), for rollbacks.
    history: History,
    /// The phases of the points of an `advance`, for the history.
    stretch_s: Vec<f64>,
    /// Whether each point of the stretch came from the final stage's generator.
    stretch_generated: Vec<bool>,
    holding: bool,
    stopping: bool,
    stall: Vec<StallDetector>,
    /// The last output point handed out (when `has_last`): position and velocity.
    last_x: Vec<f64>,
    last_xd: Vec<f64>,
    has_last: bool,
    /// The members' ids (never a cell-mate).
    member_ids: Vec<String>,
    /// Scratch for a cell-mate's centre.
    c0: Vec<f64>,
    /// Every obstacle or robot touched so far.
    touched: std::collections::BTreeSet<String>,
    /// "At the goal and at rest".
    goal_tolerance: GoalTolerance,
    /// Since when every member has been within `goal_tolerance`, up to the last point handed out.
    goal_met_since: Option<f64>,
    /// Obstacles left out of the run, and the reports not yet handed out.
    ignored: Ignored,
    cost: IntegrationCost,
    /// A pose run: the chart of its last three dimensions.
    #[cfg_attr(not(feature = "orientation"), allow(dead_code))]
    chart: Option<pose::Chart>,
    /// A pose run's tool: the field acts on its control points ([`crate::tool`]).
    #[cfg_attr(not(feature = "orientation"), allow(dead_code))]
    tool: Option<pose::HeldTool>,
    /// The filtered goal at the points of an `advance`, for the history; the one restored by a rollback.
    stretch_g: Vec<f64>,
    rollback_g: Vec<f64>,
    /// The limits kept, and the limiter that keeps them.
    limits: Limits,
    limiter: Limiter,
    /// Scratch: the limiter's last points.
    recent: Vec<f64>,
    /// The final stage: tracks the DMP within the limits where it does not keep them.
    tracker: Tracker,
    /// The safety distance kept from the obstacles' true shapes ([`Execution::set_margin`]).
    guard: Guard,
    /// The safety distance, metres.
    margin: f64,
    /// Scratch: which groups' points keep their bounds.
    keeps: Vec<bool>,
    /// `tau` as set, and the temporal coupling's factor on it (applied, and wanted).
    base_tau: f64,
    tau_scale: f64,
    tau_scale_target: f64,
    /// The relative rate `tau' / tau` of the coupling in force: its term in the acceleration ([`limiting`]).
    tau_rate: f64,
}

impl Execution {
    /// A run of `primitive` with `motion`, avoiding `scene` (the run's own obstacles, centred at time zero, and its
    /// members: a group on one phase when it names several robots, one implicit robot owning every dimension when
    /// it names none) and the cell-mates ([`Execution::set_cell_mates`]) with `cell_mates`. Keeps the last
    /// `history` output points for rollbacks.
    pub fn new(
        primitive: Primitive,
        motion: Motion,
        scene: Scene,
        cell_mates: CellMateAvoidance,
        stepping: Stepping,
        history: usize,
    ) -> Result<Self> {
        motion.validate(primitive.dim).map_err(|e| e.within("motion"))?;
        stepping.validate()?;
        let chart = pose::chart_of(&primitive)?;
        let mut scene = scene;
        if chart.is_some() {
            // The run's one robot owns the position dimensions: the orientation is not a place in the scene.
            let position = (0..primitive.position_dim()).collect();
            match scene.agents.as_mut_slice() {
                [] => scene.agents = vec![Agent { id: "robot".into(), dims: position, footprint: None }],
                [robot] => robot.dims = position,
                _ => {
                    return Err(crate::InvalidInput::new(
                        "robots",
                        "a pose primitive runs alone, not in a group (its robot owns the position dimensions)",
                    )
                    .into());
                }
            }
        }
        check_stability(&primitive.k, stepping.internal_step(), motion.tau, "tau")?;
        let mut integrator = Integrator::new(&primitive)?;
        *integrator.goal_filter_mut() = GoalFilter::new(DEFAULT_GOAL_ALPHA, &motion.goal);
        let dim = primitive.dim;
        let field = RepulsiveField::new(scene.clone(), dim)?;
        let cell_mate_field = cell_mate_field(field.agents(), cell_mates, Vec::new(), dim)?;
        let stall = field
            .agents()
            .iter()
            .map(|a| StallDetector::new(StallConfig::default(), a.dims.clone()))
            .collect();
        let member_ids = field.agents().iter().map(|a| a.id.clone()).collect();
        let state = State::at_rest(&motion.start);
        let knot0 = Knot { t: 0.0, s: 1.0, x: state.x.clone(), xd: state.xd.clone(), xdd: vec![0.0; dim] };
        let limiter = Limiter::new(Vec::new(), dim, stepping.dt, &knot0.x);
        Ok(Self {
            blend: Blend::new(DEFAULT_OBSTACLE_BLEND, dim),
            history_span: history as f64 * stepping.dt,
            stretch_g: Vec::new(),
            rollback_g: Vec::new(),
            limits: Limits::NONE,
            limiter,
            recent: Vec::new(),
            tracker: Tracker::default(),
            guard: Guard::default(),
            margin: 0.0,
            keeps: Vec::new(),
            base_tau: motion.tau,
            tau_scale: 1.0,
            tau_scale_target: 1.0,
            tau_rate: 0.0,
            integrator,
            motion,
            scene,
            cell_mate_avoidance: cell_mates,
            field,
            cell_mates: cell_mate_field,
            knot0,
            knot1: None,
            spare: None,
            acc0_current: false,
            knot1_acc: false,
            interpolant: Interpolant::default(),
            xdd: vec![0.0; dim],
            scratch: state,
            out_t: 0.0,
            next_points: stepping.step_points,
            knot_limit: f64::INFINITY,
            end_time: f64::INFINITY,
            history: History::new(dim, stepping.dt, history),
            stretch_s: Vec::new(),
            stretch_generated: Vec::new(),
            holding: false,
            stopping: false,
            stall,
            last_x: vec![0.0; dim],
            last_xd: vec![0.0; dim],
            has_last: false,
            member_ids,
            c0: Vec::new(),
            touched: Default::default(),
            goal_tolerance: GoalTolerance::DEFAULT,
            goal_met_since: None,
            ignored: Ignored::default(),
            cost: IntegrationCost::default(),
            chart,
            tool: None,
            primitive,
            stepping,
        })
    }

    /// The robots of the run (one implicit robot when the scene named none).
    pub fn members(&self) -> &[Agent] {
        self.field.agents()
    }

    /// The field of the run's obstacles and members (what [`Stretch::contacts`] index).
    pub fn field(&self) -> &RepulsiveField {
        &self.field
    }

    /// Time of the next output point.
    pub fn time(&self) -> f64 {
        self.out_t
    }

    /// The DMP's dimension (the members' together).
    pub fn dim(&self) -> usize {
        self.primitive.dim
    }

    /// How the run steps.
    pub fn stepping(&self) -> &Stepping {
        &self.stepping
    }

    /// Output step.
    pub fn dt(&self) -> f64 {
        self.stepping.dt
    }

    /// The motion (start, goal, tau). Its `tau` is the one in force: the one set times the temporal coupling's
    /// factor ([`Execution::tau_scale`]).
    pub fn motion(&self) -> &Motion {
        &self.motion
    }

    /// What the integration cost so far.
    pub fn cost(&self) -> IntegrationCost {
        self.cost
    }

    /// Every obstacle or robot touched so far, by id.
    pub fn touched(&self) -> &std::collections::BTreeSet<String> {
        &self.touched
    }

    /// True while holding (a pause, or a stop).
    #[cfg(test)]
    pub(crate) fn is_holding(&self) -> bool {
        self.holding
    }

    /// The run is complete at run time `t` (its last point is there).
    pub fn set_end_time(&mut self, t: f64) {
        self.end_time = t;
    }

    /// Output points from the current time to the end time, inclusive (at least one).
    pub fn points_to_end(&self) -> usize {
        let dt = self.stepping.dt;
        ((self.end_time - self.out_t) / dt).round().clamp(0.0, usize::MAX as f64 / 2.0) as usize + 1
    }

    /// Adaptive step: no knot is placed after run time `t` (where the caller's next change can apply: a change
    /// restarts the grid there, and a step past it would be computed for nothing). Ignored when `t` is less than
    /// one output step ahead of the current knot.
    pub fn limit_knots_to(&mut self, t: f64) {
        self.knot_limit = t;
    }

    /// The last output point (the start, before any).
    fn last(&self) -> (&[f64], &[f64]) {
        if self.has_last { (&self.last_x, &self.last_xd) } else { (&self.knot0.x, &self.knot0.xd) }
    }

    /// Whether every member is at its goal and at rest (at the last output point), within
    /// [`Execution::goal_tolerance`].
    pub fn arrived(&self) -> bool {
        let (x, xd) = self.last();
        self.within_goal_tolerance(x, xd)
    }

    /// True when every member is at rest (at the last output point).
    pub fn at_rest(&self) -> bool {
        self.last().1.iter().map(|v| v * v).sum::<f64>().sqrt() <= ARRIVED_SPEED
    }
}

/// The cell's other robots, as moving obstacles of the cell-mate method.
fn cell_mate_field(
    agents: &[Agent],
    a: CellMateAvoidance,
    obstacles: Vec<crate::Obstacle>,
    dim: usize,
) -> Result<RepulsiveField> {
    let scene = Scene {
        obstacles,
        avoidance: a.method,
        agents: agents.to_vec(),
        robot_avoidance: Avoidance::NONE,
        point_samples: a.point_samples,
    };
    RepulsiveField::new(scene, dim)
}

#[cfg(test)]
mod tests;

#[cfg(test)]
mod change_tests;

#[cfg(test)]
mod guard_tests;
