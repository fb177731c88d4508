//! One run on one phase: a robot, or a group of robots sharing a DMP, stepped segment by segment. Scene, goal and
//! tau changes are applied from the current state (never by a jump), and the run can roll back to a recent point
//! so that a new segment supersedes setpoints already sent.
//!
//! RK4 runs on an internal grid of `step_points` output steps; the output points in between are the quintic
//! Hermite interpolant of the two knots around them ([`dmp::dense`]). Every change restarts the grid at the next
//! output point, so a change takes effect exactly where it would with RK4 at the output rate. With a tolerance
//! ([`Runner::with_tolerance`]) the grid adapts instead: Dormand–Prince 5(4) steps of a whole number of output
//! steps, at most `step_points`, each accepted when its error estimate is within the tolerance
//! ([`dmp::integrate::dormand_prince`]), and never beyond the limit the caller sets ([`Runner::limit_knots_to`]:
//! where its next change can apply, so that no step is computed past it for nothing).

mod fields;
mod grid;
mod history;
mod hold;

use dmp::dense::{Interpolant, Knot, interpolate};
use dmp::field::{Contact, RepulsiveField};
use dmp::stall::{StallConfig, StallDetector};
use dmp::{Avoidance, Integrator, Motion, Obstacle, Perturbation, Primitive, State};
use dmp_proto::v1;

use self::fields::{agents, build_field, build_remote};
pub use self::grid::Work;
use self::history::History;
use crate::error::ServerError;

/// Distance to the goal and speed under which a robot has arrived.
const ARRIVED_DISTANCE: f64 = 1e-3;
const ARRIVED_SPEED: f64 = 1e-3;

/// Largest `dt sqrt(K) / tau` accepted: RK4 on the critically damped transformation system is stable up to about
/// 2.8; this keeps a margin (the paper's K = 1050 at dt = 1 ms allows tau down to 16 ms).
pub const MAX_STIFF_STEP: f64 = 2.0;

/// Checks that RK4 with step `dt` is stable for stiffness `k` and time scale `tau`.
pub fn check_stability(k: &[f64], dt: f64, tau: f64, field: &str) -> Result<(), ServerError> {
    let k_max = k.iter().copied().fold(0.0, f64::max);
    let x = dt * k_max.sqrt() / tau;
    if x > MAX_STIFF_STEP {
        return Err(ServerError::invalid(
            field,
            format!(
                "dt sqrt(K) / tau = {x:.3} exceeds {MAX_STIFF_STEP}: the integration would be unstable (use a smaller dt or a larger tau; tau >= {:.4} s here)",
                dt * k_max.sqrt() / MAX_STIFF_STEP
            ),
        ));
    }
    Ok(())
}

/// A robot of the run and the dimensions of the shared DMP it owns.
#[derive(Debug, Clone)]
pub struct Member {
    /// Its id.
    pub robot_id: String,
    /// The DMP dimensions it owns (contiguous).
    pub dims: std::ops::Range<usize>,
    /// What other robots avoid.
    pub footprint: Option<dmp::Shape>,
    /// The footprint as sent, for its published state.
    pub footprint_proto: Option<v1::Superquadric>,
}

/// How a run avoids things.
#[derive(Debug, Clone)]
pub struct AvoidanceSpec {
    /// Method for obstacles and its boundary sample count.
    pub obstacles: (Avoidance, usize),
    /// Method for other robots (of the group and of the cell) and its sample count.
    pub robots: (Avoidance, usize),
    /// Obstacles of this run only (centres at the start of the run).
    pub extra: Vec<Obstacle>,
    /// Ignore the cell's scene.
    pub ignore_scene: bool,
}

/// What happened over a stretch of steps.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// Moving.
    Running,
    /// Every robot at its goal and at rest.
    GoalReached,
    /// A robot stopped away from its goal.
    Stalled,
    /// A robot is inside an obstacle's true shape or another robot's footprint.
    Collision,
    /// Holding (pause or stop in progress).
    Holding,
}

/// A point of the output: time, position, velocity, acceleration (each of the DMP's dimension).
#[derive(Debug, Clone, Default)]
pub struct Points {
    /// Time of the first point.
    pub start_time: f64,
    /// Positions, row-major.
    pub x: Vec<f64>,
    /// Velocities.
    pub xd: Vec<f64>,
    /// Accelerations.
    pub xdd: Vec<f64>,
    /// The worst outcome met.
    pub outcome: Option<Outcome>,
}

/// Adds two perturbations.
struct Both<'a>(&'a mut RepulsiveField, &'a mut RepulsiveField);

impl Perturbation for Both<'_> {
    fn add(&mut self, t: f64, x: &[f64], v: &[f64], tau: f64, out: &mut [f64]) {
        self.0.add(t, x, v, tau, out);
        self.1.add(t, x, v, tau, out);
    }
}

/// The state machine of a run.
#[derive(Debug)]
pub struct Runner {
    members: Vec<Member>,
    primitive: Primitive,
    integrator: Integrator,
    motion: Motion,
    /// The grid point the output is in, and the next one (None until computed after a change).
    knot0: Knot,
    knot1: Option<Knot>,
    /// Buffers of a knot dropped by a change, for the next one.
    spare: Option<Knot>,
    /// `knot0.xdd` is the acceleration at `knot0` under the current field and motion (it was computed as the
    /// previous step's end knot and nothing changed since): the next RK4 step reuses it as its first stage.
    acc0_current: bool,
    /// The interpolant of `knot0` and `knot1`, fitted when `knot1` is computed.
    interpolant: Interpolant,
    /// Scratch acceleration of an interpolated point.
    xdd: Vec<f64>,
    /// Where RK4 computes the next knot.
    scratch: State,
    /// Time of the next output point.
    out_t: f64,
    dt: f64,
    /// Internal RK4 step, in output steps (with a tolerance: the largest adaptive step).
    step_points: usize,
    /// Adaptive step: the local error tolerance (None: RK4 at `step_points`).
    tolerance: Option<f64>,
    /// Adaptive step: the next step to try, in output steps.
    next_points: usize,
    /// No knot beyond this time (adaptive step).
    knot_limit: f64,
    avoidance: AvoidanceSpec,
    /// The scene's obstacles and the group's robots.
    field: RepulsiveField,
    /// The cell's other robots.
    remote: RepulsiveField,
    scene_version: u64,
    /// The recent output points (their states), for rollbacks.
    history: History,
    /// The phases of the points of an `advance`, for the history.
    seg_s: Vec<f64>,
    holding: bool,
    stall: Vec<StallDetector>,
    contacts: Vec<Contact>,
    /// Scratch for a remote robot's centre.
    c0: Vec<f64>,
    /// Everything touched so far: obstacle ids and robot ids.
    touched: std::collections::BTreeSet<String>,
    /// What the integration cost so far.
    work: Work,
}

impl Runner {
    /// A run of `primitive` (dimension = the members' dims together) with `motion`, output step `dt` and RK4 every
    /// `step_points` output steps. Keeps the last `history_len` output points for rollbacks.
    pub fn new(
        members: Vec<Member>,
        primitive: Primitive,
        motion: Motion,
        dt: f64,
        step_points: usize,
        avoidance: AvoidanceSpec,
        history_len: usize,
    ) -> Result<Self, ServerError> {
        motion.validate(primitive.dim).map_err(|e| ServerError::from(e).within("motion"))?;
        if !(dt.is_finite() && dt > 0.0 && dt <= 0.1) {
            return Err(ServerError::invalid("dt", "must be greater than 0 and at most 0.1 s"));
        }
        let step_points = step_points.max(1);
        check_stability(&primitive.k, dt * step_points as f64, motion.tau, "tau")?;
        let integrator = Integrator::new(&primitive)?;
        let state = State::at_rest(&motion.start);
        let knot0 =
            Knot { t: 0.0, s: 1.0, x: state.x.clone(), xd: state.xd.clone(), xdd: vec![0.0; primitive.dim] };
        let agents = agents(&members);
        let field = build_field(&agents, &avoidance, Vec::new(), primitive.dim)?;
        let remote = build_remote(&agents, &avoidance, Vec::new(), primitive.dim)?;
        let stall = members
            .iter()
            .map(|m| StallDetector::new(StallConfig::default(), m.dims.clone().collect()))
            .collect();
        let dim = primitive.dim;
        Ok(Self {
            members,
            primitive,
            integrator,
            motion,
            knot0,
            knot1: None,
            spare: None,
            acc0_current: false,
            interpolant: Interpolant::default(),
            xdd: vec![0.0; dim],
            scratch: state,
            out_t: 0.0,
            dt,
            step_points,
            tolerance: None,
            next_points: step_points,
            knot_limit: f64::INFINITY,
            avoidance,
            field,
            remote,
            scene_version: 0,
            history: History::new(dim, dt, history_len),
            seg_s: Vec::new(),
            holding: false,
            stall,
            contacts: Vec::new(),
            c0: Vec::new(),
            touched: Default::default(),
            work: Work::default(),
        })
    }

    /// Adapts the internal step to `tolerance` (the local error tolerance of Dormand–Prince 5(4), metres on
    /// positions and metres per second on velocities, relative to `1 + |value|`), with steps of at most
    /// `step_points` output steps. Fails unless the tolerance is finite and above zero.
    pub fn with_tolerance(mut self, tolerance: f64) -> Result<Self, ServerError> {
        if !(tolerance.is_finite() && tolerance > 0.0) {
            return Err(ServerError::invalid(
                "integration_tolerance",
                "must be a finite number greater than zero",
            ));
        }
        self.tolerance = Some(tolerance);
        Ok(self)
    }

    /// Adaptive step: no knot is placed after run time `t` (where the caller's next change can apply: a change
    /// restarts the grid there, and a step past it would be computed for nothing). Ignored when `t` is less than
    /// one output step ahead of the current knot.
    pub fn limit_knots_to(&mut self, t: f64) {
        self.knot_limit = t;
    }

    /// What the integration cost so far.
    pub fn work(&self) -> Work {
        self.work
    }

    /// The members.
    pub fn members(&self) -> &[Member] {
        &self.members
    }

    /// Time of the next output point.
    pub fn time(&self) -> f64 {
        self.out_t
    }

    /// The DMP's dimension (the members' together).
    pub fn dim(&self) -> usize {
        self.primitive.dim
    }

    /// The internal RK4 step, in output steps.
    pub fn step_points(&self) -> usize {
        self.step_points
    }

    /// The scene version the field was built with.
    pub fn scene_version(&self) -> u64 {
        self.scene_version
    }

    /// The motion (start, goal, tau).
    pub fn motion(&self) -> &Motion {
        &self.motion
    }

    /// Output step.
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// Changes the goal from now on (position and velocity stay continuous).
    pub fn set_goal(&mut self, goal: Vec<f64>) -> Result<(), ServerError> {
        crate::convert::vector("goal", &goal, self.primitive.dim)?;
        self.rebase();
        self.motion.goal = goal;
        Ok(())
    }

    /// Changes tau from now on (the state keeps dx/dt, so the velocity is continuous).
    pub fn set_tau(&mut self, tau: f64) -> Result<(), ServerError> {
        if !(tau.is_finite() && tau > 0.0) {
            return Err(ServerError::invalid("tau", "must be a finite number greater than zero"));
        }
        check_stability(&self.primitive.k, self.dt * self.step_points as f64, tau, "tau")?;
        self.rebase();
        self.motion.tau = tau;
        Ok(())
    }

    /// Holds (decelerates to rest, phase frozen) or resumes.
    pub fn set_holding(&mut self, holding: bool) {
        if holding != self.holding {
            self.rebase();
        }
        self.holding = holding;
    }

    /// True while holding.
    pub fn is_holding(&self) -> bool {
        self.holding
    }

    /// Rolls back to the first recorded state at or after `t` (no-op when `t` is at or past the current time, or
    /// older than the history). Returns the time the run continues from.
    pub fn rollback_to(&mut self, t: f64) -> f64 {
        if t >= self.out_t {
            return self.out_t;
        }
        let mut restored = std::mem::replace(&mut self.scratch, State::at_rest(&[]));
        if self.history.rollback_into(t, 0.5 * self.dt, &mut restored) {
            self.restart_at(&restored);
        }
        self.scratch = restored;
        self.out_t
    }

    /// Restarts the internal grid at `s` (an output point): the next knot is computed afresh.
    fn restart_at(&mut self, s: &State) {
        self.knot0.t = s.t;
        self.knot0.s = s.s;
        self.knot0.x.clone_from(&s.x);
        self.knot0.xd.clone_from(&s.xd);
        self.spare = self.knot1.take().or(self.spare.take());
        self.acc0_current = false;
        self.out_t = s.t;
    }

    /// Restarts the internal grid at the next output point, so that a change applies from there: the point is
    /// interpolated between the current knots (it is what RK4 at the output rate would hold there, to the
    /// interpolation's accuracy).
    fn rebase(&mut self) {
        // Whatever changes, the field or the motion no longer gives the acceleration stored at knot0.
        self.acc0_current = false;
        let Some(k1) = self.knot1.take() else { return };
        if self.out_t > self.knot0.t {
            // Into the scratch state, then the knot: no allocation (this runs every segment with cell-mates).
            let st = &mut self.scratch;
            st.s = interpolate(&self.knot0, &k1, self.out_t, &mut st.x, &mut st.xd, &mut self.xdd);
            self.knot0.t = self.out_t;
            self.knot0.s = st.s;
            self.knot0.x.copy_from_slice(&st.x);
            self.knot0.xd.copy_from_slice(&st.xd);
        }
        // The next knot is computed afresh, in these buffers.
        self.spare = Some(k1);
    }

    /// Every obstacle or robot touched so far.
    pub fn touched(&self) -> &std::collections::BTreeSet<String> {
        &self.touched
    }

    /// The last output point (the start, before any).
    fn last(&self) -> (&[f64], &[f64]) {
        self.history.last().unwrap_or((&self.knot0.x, &self.knot0.xd))
    }

    /// Whether every member is at its goal and at rest (at the last output point).
    pub fn arrived(&self) -> bool {
        let (x, xd) = self.last();
        self.members.iter().all(|m| {
            let dist: f64 = m.dims.clone().map(|i| (x[i] - self.motion.goal[i]).powi(2)).sum::<f64>().sqrt();
            let speed: f64 = m.dims.clone().map(|i| xd[i].powi(2)).sum::<f64>().sqrt();
            dist <= ARRIVED_DISTANCE && speed <= ARRIVED_SPEED
        })
    }

    /// True when every member is at rest (at the last output point).
    pub fn at_rest(&self) -> bool {
        self.last().1.iter().map(|v| v * v).sum::<f64>().sqrt() <= ARRIVED_SPEED
    }

    /// Computes the next `n` output points, advancing the run. Fails if the state stops being finite (which the
    /// stability check on the step and `tau` should prevent).
    pub fn advance(&mut self, n: usize) -> Result<Points, ServerError> {
        let d = self.primitive.dim;
        let mut p = Points {
            start_time: self.out_t,
            x: vec![0.0; n * d],
            xd: vec![0.0; n * d],
            xdd: vec![0.0; n * d],
            outcome: None,
        };
        let mut worst = Outcome::Running;
        self.seg_s.clear();
        for k in 0..n {
            let t = self.out_t;
            if self.knot1.as_ref().is_none_or(|k1| t >= k1.t - 0.5 * self.dt) {
                if let Some(k1) = self.knot1.take() {
                    // Step to the next knot: the old one is done with.
                    let old = std::mem::replace(&mut self.knot0, k1);
                    self.knot1 = Some(old);
                    // Its acceleration was evaluated at its exact state (a coarse step) under the field and
                    // motion still in force (a change would have rebased and dropped it).
                    self.acc0_current = (self.step_points > 1 || self.tolerance.is_some()) && !self.holding;
                }
                self.next_knot();
                let k1 = self.knot1.as_ref().expect("computed above");
                self.interpolant.fit(&self.knot0, k1);
            }
            let k1 = self.knot1.as_ref().expect("computed above");
            let range = k * d..(k + 1) * d;
            let s = self.interpolant.eval(
                &self.knot0,
                k1,
                t,
                &mut p.x[range.clone()],
                &mut p.xd[range.clone()],
                &mut p.xdd[range.clone()],
            );
            if !p.x[range.clone()]
                .iter()
                .chain(&p.xd[range.clone()])
                .chain(&p.xdd[range.clone()])
                .all(|v| v.is_finite())
            {
                return Err(ServerError::FailedPrecondition(format!(
                    "the integration diverged at t = {t:.3} s (no setpoint was sent from there)"
                )));
            }
            self.seg_s.push(s);
            self.out_t = ((t + self.dt) / self.dt).round() * self.dt;

            // Stalls at the point the robot is sent to (checked at its time); contacts below, for all points.
            let x = &p.x[range.clone()];
            if self.holding {
                // At rest on purpose: not a stall.
                for (det, m) in self.stall.iter_mut().zip(&self.members) {
                    *det = StallDetector::new(StallConfig::default(), m.dims.clone().collect());
                }
            } else {
                for det in &mut self.stall {
                    if det.update(t, x, &p.xd[range.clone()], &self.motion.goal).is_some()
                        && worst == Outcome::Running
                    {
                        worst = Outcome::Stalled;
                    }
                }
            }
        }
        self.history.push(p.start_time, &self.seg_s, &p.x, &p.xd);
        // Contacts at every point the robot is sent to (each checked at its time); obstacles no point can reach are
        // skipped as a whole.
        self.contacts.clear();
        let local = self.field.contacts_along(p.start_time, self.dt, &p.x, n, &mut self.contacts);
        let n_local = self.contacts.len();
        if local | self.remote.contacts_along(p.start_time, self.dt, &p.x, n, &mut self.contacts) {
            worst = Outcome::Collision;
            for (i, c) in self.contacts.iter().enumerate() {
                let f = if i < n_local { &self.field } else { &self.remote };
                let id = match *c {
                    Contact::Obstacle { obstacle, .. } => f.scene().obstacles[obstacle].id(),
                    Contact::Robot { other, .. } => f.agents()[other].id.as_str(),
                };
                if !self.touched.contains(id) {
                    self.touched.insert(id.to_string());
                }
            }
        }
        p.outcome = Some(if self.holding && worst == Outcome::Running {
            Outcome::Holding
        } else if worst == Outcome::Running && self.arrived() {
            Outcome::GoalReached
        } else {
            worst
        });
        Ok(p)
    }
}
