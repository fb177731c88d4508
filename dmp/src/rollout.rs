//! Full rollouts: fixed step, a row per step, contacts and stalls reported.

use crate::error::{InvalidInput, Result};
use crate::execution::{CellMateAvoidance, Execution, OrientationPoints, Stepping, Stretch};
use crate::field::{Contact, RepulsiveField};
use crate::integrate::Motion;
use crate::primitive::Primitive;
use crate::stall::Stall;

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
    /// A pose run's orientations, angular velocities and accelerations at every row (empty otherwise).
    pub orientations: OrientationPoints,
}

/// Rolls `primitive` out from rest at `motion.start` for `steps` steps of `dt` (RK4 at `dt`), avoiding the scene
/// of `field`: an [`Execution`] advanced once over the whole run, so that an offline rollout and a served run step
/// the same way.
pub fn rollout(
    primitive: &Primitive,
    motion: &Motion,
    field: &RepulsiveField,
    dt: f64,
    steps: usize,
) -> Result<Rollout> {
    rollout_with(primitive, motion, field, dt, steps, |_| Ok(()))
}

/// [`rollout`] of a pose primitive, its orientation dimensions in the chart `chart` (see
/// [`crate::orientation::pose::pose_motion`]), holding `tool` if given ([`Execution::set_tool`]).
#[cfg(all(feature = "learn", feature = "orientation"))]
pub(crate) fn rollout_pose(
    primitive: &Primitive,
    motion: &Motion,
    field: &RepulsiveField,
    dt: f64,
    steps: usize,
    chart: nalgebra::UnitQuaternion<f64>,
    tool: Option<crate::tool::Tool>,
) -> Result<Rollout> {
    rollout_with(primitive, motion, field, dt, steps, |run| {
        run.set_orientation_chart(chart)?;
        Ok(run.set_tool(tool)?)
    })
}

fn rollout_with(
    primitive: &Primitive,
    motion: &Motion,
    field: &RepulsiveField,
    dt: f64,
    steps: usize,
    set_up: impl FnOnce(&mut Execution) -> Result<()>,
) -> Result<Rollout> {
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
    let mut run = Execution::new(
        primitive.clone(),
        motion.clone(),
        field.scene().clone(),
        CellMateAvoidance::NONE,
        Stepping::rk4(dt),
        0,
    )?;
    set_up(&mut run)?;
    let Stretch { x, xd, xdd, mut contacts, stalls, orientation, .. } = run.advance(steps + 1)?;
    // By row, and in the field's order within a row.
    contacts.sort_by_key(|&(k, _)| k);
    let t = (0..=steps).map(|k| k as f64 * dt).collect();
    let trajectory = Trajectory { dim: primitive.dim, t, x, xd, xdd };
    Ok(Rollout { trajectory, contacts, stalls, orientations: orientation })
}
