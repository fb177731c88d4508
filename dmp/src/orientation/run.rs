//! Stepping an orientation primitive: the DMP integrates the rotation vector `y`; every sample maps it back to a
//! unit quaternion with its angular velocity and acceleration, exactly.

use nalgebra::{UnitQuaternion, Vector3};

use super::jacobian::{angular_motion, log_jacobian};
use super::primitive::OrientationPrimitive;
use super::quaternion::{closest_sign, exp, from_xyzw, log};
use crate::error::{DmpError, InvalidInput, Result, ensure_positive};
use crate::execution::check_stability;
use crate::integrate::{Integrator, Motion, NoPerturbation, State};

/// What a replay may change: the start and goal orientations and the time scale `tau`.
#[derive(Debug, Clone, PartialEq)]
pub struct OrientationMotion {
    /// The orientation the run starts from.
    pub start: UnitQuaternion<f64>,
    /// The goal; its sign does not matter ([`OrientationRun::new`] picks the one nearer the start).
    pub goal: UnitQuaternion<f64>,
    /// `tau`: larger is slower.
    pub tau: f64,
}

impl OrientationMotion {
    /// Checks a motion from the wire: `start` and `goal` as `[x, y, z, w]` (errors name `start`, `goal`, `tau`).
    pub fn new(start: [f64; 4], goal: [f64; 4], tau: f64) -> Result<Self, InvalidInput> {
        ensure_positive(|| "tau".into(), tau)?;
        Ok(Self { start: from_xyzw("start", start)?, goal: from_xyzw("goal", goal)?, tau })
    }

    /// The demonstration's own start, goal and duration.
    pub fn of(p: &OrientationPrimitive) -> Result<Self, InvalidInput> {
        Self::new(p.start, p.goal, p.dmp.tau)
    }
}

/// One output point: time, orientation, and the angular velocity and acceleration in the world frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrientationSample {
    /// Time since the start of the run, seconds.
    pub t: f64,
    /// The orientation; continuous along a run and equal to the given start at `t = 0` (sign included).
    pub q: UnitQuaternion<f64>,
    /// Angular velocity `ω`, world frame, rad/s: `q̇ = ½ (0, ω) ⊗ q`.
    pub omega: Vector3<f64>,
    /// Angular acceleration `ω̇`, world frame, rad/s².
    pub omega_dot: Vector3<f64>,
}

/// A run of an [`OrientationPrimitive`], stepped by the caller at a step of its choosing (RK4, phase in closed
/// form, as the position DMP's [`Integrator`]).
///
/// # Formula
/// Koutras and Doulgeri's formulation on this crate's DMP: with `q_g` the goal in the sign nearest the start,
/// - the state is `y = log(q ⊗ q̄_g)` (rotation vector, [`super::quaternion`]), `y_0 = log(q_0 ⊗ q̄_g)`,
///   `|y_0| <= π`;
/// - `y` follows the position DMP with goal `0` and start `y_0`:
///   `tau² ÿ = K (0 - y) - D tau ẏ - K (0 - y_0) s + K f(s)` (Ginesi et al., `eq:dmp_acc_obst` without
///   obstacles; see [`Integrator::acceleration`]), `tau ṡ = -alpha s`;
/// - the output is `q = exp(y) ⊗ q_g`, a unit quaternion by construction, and, with `J` the Jacobian of the
///   exponential map (`orientation/jacobian.rs`), `ω = J(y) ẏ` and `ω̇ = J(y) ÿ + J̇ ẏ` in the world frame: since
///   `q_g` is constant, `2 q̇ ⊗ q̄ = 2 (d/dt exp(y)) ⊗ exp(y)⁻¹`.
#[derive(Debug, Clone)]
pub struct OrientationRun {
    integrator: Integrator,
    motion: Motion,
    goal: UnitQuaternion<f64>,
    /// The stiffness, for the stability bound on the step.
    k: Vec<f64>,
    state: State,
    /// `ÿ` at `state`.
    acc: Vec<f64>,
}

impl OrientationRun {
    /// A run at rest at `motion.start`.
    pub fn new(primitive: &OrientationPrimitive, motion: &OrientationMotion) -> Result<Self> {
        Self::moving(primitive, motion, Vector3::zeros())
    }

    /// A run that starts at `motion.start` turning at `omega` (world frame, rad/s), e.g. to take over from a
    /// motion in progress: `ẏ_0 = J⁻¹(y_0) ω` (`log_jacobian`, `orientation/jacobian.rs`).
    pub fn moving(
        primitive: &OrientationPrimitive,
        motion: &OrientationMotion,
        omega: Vector3<f64>,
    ) -> Result<Self> {
        primitive.validate()?;
        ensure_positive(|| "tau".into(), motion.tau)?;
        if omega.iter().any(|w| !w.is_finite()) {
            return Err(InvalidInput::new("omega", "must be three finite numbers").into());
        }
        let goal = closest_sign(&motion.goal, &motion.start);
        let y0 = log(&(motion.start * goal.conjugate()));
        let yd0 = log_jacobian(&y0) * omega;
        let mut integrator = Integrator::new(&primitive.dmp)?;
        let motion = Motion { start: y0.iter().copied().collect(), goal: vec![0.0; 3], tau: motion.tau };
        let state = State { t: 0.0, s: 1.0, x: motion.start.clone(), xd: yd0.iter().copied().collect() };
        let mut acc = vec![0.0; 3];
        integrator.acceleration(
            &motion,
            &mut NoPerturbation,
            state.t,
            state.s,
            &state.x,
            &state.xd,
            &mut acc,
        );
        Ok(Self { integrator, motion, goal, k: primitive.dmp.k.clone(), state, acc })
    }

    /// Time since the start of the run.
    pub fn time(&self) -> f64 {
        self.state.t
    }

    /// The phase `s`.
    pub fn phase(&self) -> f64 {
        self.state.s
    }

    /// The goal, in the sign nearest the start: the run's orientation tends to it (not to its opposite).
    pub fn goal(&self) -> UnitQuaternion<f64> {
        self.goal
    }

    /// The tangent-space state: `y`, `ẏ`, `ÿ`.
    pub(crate) fn tangent(&self) -> [Vector3<f64>; 3] {
        [&self.state.x, &self.state.xd, &self.acc].map(|v| Vector3::from_column_slice(v))
    }

    /// The current output point.
    pub fn sample(&self) -> OrientationSample {
        let [y, yd, ydd] = self.tangent();
        let (omega, omega_dot) = angular_motion(&y, &yd, &ydd);
        OrientationSample { t: self.state.t, q: exp(&y) * self.goal, omega, omega_dot }
    }

    /// Advances by `dt` (one RK4 step). `dt` must be finite, positive and stable for the stiffness and `tau`
    /// (`dt sqrt(max K) / tau` at most [`crate::execution::MAX_STIFF_STEP`]); a state that stops being finite is reported as [`DmpError::Diverged`].
    pub fn step(&mut self, dt: f64) -> Result<()> {
        ensure_positive(|| "dt".into(), dt)?;
        check_stability(&self.k, dt, self.motion.tau, "dt")?;
        self.integrator.step_from(
            &self.motion,
            &mut NoPerturbation,
            &mut self.state,
            dt,
            &mut self.acc,
            true,
        );
        let s = &self.state;
        self.integrator.acceleration(&self.motion, &mut NoPerturbation, s.t, s.s, &s.x, &s.xd, &mut self.acc);
        if self.state.x.iter().chain(&self.state.xd).chain(&self.acc).any(|v| !v.is_finite()) {
            return Err(DmpError::Diverged { t: self.state.t });
        }
        Ok(())
    }
}
