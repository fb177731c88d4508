//! Full rollouts: fixed step, a row per step, contacts and stalls reported.

use crate::error::{InvalidInput, Result};
use crate::field::{Contact, RepulsiveField};
use crate::integrate::{Integrator, Motion, State};
use crate::primitive::Primitive;
use crate::stall::{Stall, StallConfig, StallDetector};

/// The longest rollout accepted, in steps (1000 s at the reference step of 1 ms).
pub const MAX_ROLLOUT_STEPS: usize = 1_000_000;

/// A sampled trajectory: `len()` rows at `t = k dt`, each with position, velocity `dx/dt` and acceleration.
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory {
    dim: usize,
    /// Times.
    pub t: Vec<f64>,
    /// Positions, row-major.
    pub x: Vec<f64>,
    /// Velocities `dx/dt`, row-major.
    pub xd: Vec<f64>,
    /// Accelerations `d2x/dt2`, row-major.
    pub xdd: Vec<f64>,
}

impl Trajectory {
    /// An empty trajectory of dimension `dim` with room for `rows` rows.
    pub fn with_capacity(dim: usize, rows: usize) -> Self {
        Self {
            dim,
            t: Vec::with_capacity(rows),
            x: Vec::with_capacity(rows * dim),
            xd: Vec::with_capacity(rows * dim),
            xdd: Vec::with_capacity(rows * dim),
        }
    }

    /// Appends a row.
    pub fn push(&mut self, t: f64, x: &[f64], xd: &[f64], xdd: &[f64]) {
        self.t.push(t);
        self.x.extend_from_slice(x);
        self.xd.extend_from_slice(xd);
        self.xdd.extend_from_slice(xdd);
    }

    /// Dimension.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// True without rows.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// Position of row `k`.
    pub fn position(&self, k: usize) -> &[f64] {
        &self.x[k * self.dim..(k + 1) * self.dim]
    }

    /// Velocity of row `k`.
    pub fn velocity(&self, k: usize) -> &[f64] {
        &self.xd[k * self.dim..(k + 1) * self.dim]
    }

    /// Acceleration of row `k`.
    pub fn acceleration(&self, k: usize) -> &[f64] {
        &self.xdd[k * self.dim..(k + 1) * self.dim]
    }

    /// True when every number is finite.
    pub fn is_finite(&self) -> bool {
        self.t.iter().chain(&self.x).chain(&self.xd).chain(&self.xdd).all(|v| v.is_finite())
    }
}

/// A finished rollout.
#[derive(Debug, Clone, PartialEq)]
pub struct Rollout {
    /// `steps + 1` rows, from `t = 0`.
    pub trajectory: Trajectory,
    /// Every contact, with the row it happened at.
    pub contacts: Vec<(usize, Contact)>,
    /// Stalls, with the index of the robot.
    pub stalls: Vec<(usize, Stall)>,
}

/// Rolls `primitive` out from rest at `motion.start` for `steps` steps of `dt`, under the field `field`.
pub fn rollout(
    primitive: &Primitive,
    motion: &Motion,
    field: &mut RepulsiveField,
    dt: f64,
    steps: usize,
) -> Result<Rollout> {
    let mut integrator = Integrator::new(primitive)?;
    motion.validate(primitive.dim)?;
    if !(dt.is_finite() && dt > 0.0) {
        return Err(InvalidInput::new("rollout.dt", "must be a finite number greater than zero").into());
    }
    if steps > MAX_ROLLOUT_STEPS {
        return Err(InvalidInput::new(
            "rollout.duration",
            format!("gives {steps} steps, more than the limit of {MAX_ROLLOUT_STEPS}"),
        )
        .into());
    }
    let d = primitive.dim;
    let mut state = State::at_rest(&motion.start);
    let mut traj = Trajectory::with_capacity(d, steps + 1);
    let mut acc = vec![0.0; d];
    let mut contacts = Vec::new();
    let mut scratch = Vec::new();
    let mut stalls = Vec::new();
    let mut detectors: Vec<StallDetector> =
        field.agents().iter().map(|a| StallDetector::new(StallConfig::default(), a.dims.clone())).collect();
    for k in 0..=steps {
        // The row of time k dt: position and velocity now, the acceleration once the step has evaluated it.
        state.t = k as f64 * dt;
        traj.push(state.t, &state.x, &state.xd, &acc);
        if k < steps {
            integrator.step(motion, field, &mut state, dt, &mut acc);
        } else {
            integrator.acceleration(motion, field, state.t, state.s, &state.x, &state.xd, &mut acc);
        }
        traj.xdd[k * d..(k + 1) * d].copy_from_slice(&acc);
        let (t, x, xd) = (traj.t[k], traj.position(k), traj.velocity(k));
        scratch.clear();
        if field.contacts(t, x, &mut scratch) {
            contacts.extend(scratch.iter().map(|c| (k, *c)));
        }
        for (i, det) in detectors.iter_mut().enumerate() {
            if let Some(s) = det.update(t, x, xd, &motion.goal) {
                stalls.push((i, s));
            }
        }
    }
    Ok(Rollout { trajectory: traj, contacts, stalls })
}
