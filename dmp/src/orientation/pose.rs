//! Pose primitives: a position DMP and an orientation DMP on one phase, run as one primitive of dimension `n + 3`
//! whose last three dimensions are the rotation vector of the orientation in a chart ([`crate::OrientationChart`]).
//!
//! # Formula
//! The orientation part is Koutras and Doulgeri's DMP ([`super`]): with `q_ref` the chart's reference,
//! `y = log(q ⊗ q̄_ref)` follows the transformation system of the position DMP (Ginesi et al., `eq:dmp_acc_obst`)
//! dimension by dimension, and `q = exp(y) ⊗ q_ref`, `ω = J(y) ẏ`, `ω̇ = J(y) ÿ + J̇ ẏ` (`orientation/jacobian.rs`).
//! With the chart at the goal (what [`learn_pose`] stores and [`pose_motion`] builds for a replay) the orientation
//! part of a pose run is exactly an [`super::OrientationRun`]; since both parts share the phase `s` and `tau`,
//! a change of `tau`, a pause or a stop acts on both at once, and the one [`crate::Execution`] runs both.
//! A new goal orientation `q_new` during a run is the goal `log(q_new ⊗ q̄_ref)` of the chart (the sign of `q_new`
//! nearest the reference). The chart covers every orientation less than π from `q_ref`, but its straight lines
//! only follow the short way between orientations that are both well inside it: from `y = 60° z` to a goal
//! `210° z`, charted as `-150° z`, the straight line turns 210° instead of 150°. So a goal change re-charts
//! (`ChartChange`) when the current orientation or the new goal is more than [`WELL_INSIDE`] from the chart's
//! centre: the new centre is halfway along the short rotation between them, so that both lie on one line through
//! it, `y'_g = -y'_c`, and that line is the short rotation.

use nalgebra::{UnitQuaternion, Vector3};

use super::jacobian::{angular_motion, exp_jacobian, log_jacobian};
use super::quaternion::{angle_between, closest_sign, exp, from_xyzw, log, to_xyzw};
#[cfg(feature = "learn")]
use super::{OrientationDemonstration, learn_orientation};
use crate::error::{InvalidInput, Result};
use crate::execution::OrientationPoints;
use crate::integrate::Motion;
#[cfg(feature = "learn")]
use crate::learn::{Demonstration, LearnConfig, learn, per_dimension};
#[cfg(feature = "learn")]
use crate::primitive::OrientationChart;
use crate::primitive::Primitive;

/// The chart of a pose primitive, as a quaternion; `None` for a position-only primitive.
pub fn chart_of(p: &Primitive) -> Result<Option<UnitQuaternion<f64>>, InvalidInput> {
    p.orientation.map(|c| from_xyzw("orientation.reference", c.reference)).transpose()
}

/// The chart coordinates `log(q ⊗ q̄_ref)` of `q`, in the sign of `q` nearest `q_ref` (angle at most π).
pub(crate) fn to_chart(reference: &UnitQuaternion<f64>, q: &UnitQuaternion<f64>) -> Vector3<f64> {
    log(&(closest_sign(q, reference) * reference.conjugate()))
}

/// The orientation of the chart coordinates `y`: `exp(y) ⊗ q_ref`.
pub fn from_chart(reference: &UnitQuaternion<f64>, y: &Vector3<f64>) -> UnitQuaternion<f64> {
    exp(y) * reference
}

/// How far from its chart's centre an orientation may be for a goal change to keep the chart (radians): π/2. Two
/// orientations within it are at most π apart and the straight line between their coordinates stays within it
/// (a ball is convex), far from the cut at π where the chart turns the long way.
pub const WELL_INSIDE: f64 = std::f64::consts::FRAC_PI_2;

/// The chart for a goal change from the current orientation `current` to `goal`: `None` when both are within
/// [`WELL_INSIDE`] of `reference` (the chart is kept), otherwise the orientation halfway along the short rotation
/// from `current` to `goal`, `q_mid = exp(½ log(ĝ ⊗ q̄_c)) ⊗ q_c` with `ĝ` the sign of `goal` nearest `current`
/// (the slerp at ½), in the sign of `current` (a non-negative 4-dot product, so that the output quaternions keep
/// their sign across the change).
pub(crate) fn chart_for_goal(
    reference: &UnitQuaternion<f64>,
    current: &UnitQuaternion<f64>,
    goal: &UnitQuaternion<f64>,
) -> Option<UnitQuaternion<f64>> {
    if angle_between(current, reference) <= WELL_INSIDE && angle_between(goal, reference) <= WELL_INSIDE {
        return None;
    }
    let g = closest_sign(goal, current);
    let mid = exp(&(log(&(g * current.conjugate())) * 0.5)) * current;
    Some(closest_sign(&mid, current))
}

/// A change of chart, from the one at `from` to the one at `to`: the coordinates of the same orientation, angular
/// velocity and angular acceleration in the new chart.
///
/// # Formula
/// With `Φ(y) = log(exp(y) ⊗ q_from ⊗ q̄_to)` (the sign nearest `q_to`, so `|y'| <= π`):
/// - `y' = Φ(y)`;
/// - `ẏ' = J⁻¹(y') J(y) ẏ`: both sides are the world-frame angular velocity `ω` (`orientation/jacobian.rs`);
/// - `ÿ' = J⁻¹(y') (ω̇ - J̇(y', ẏ') ẏ')`, with `ω̇ = J(y) ÿ + J̇(y, ẏ) ẏ`: the angular acceleration is the same
///   in both charts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ChartChange {
    /// The old chart's reference.
    pub(crate) from: UnitQuaternion<f64>,
    /// The new chart's reference.
    pub(crate) to: UnitQuaternion<f64>,
}

impl ChartChange {
    /// `y' = Φ(y)`.
    pub(crate) fn point(&self, y: &Vector3<f64>) -> Vector3<f64> {
        to_chart(&self.to, &from_chart(&self.from, y))
    }

    /// `(y', ẏ')` of `(y, ẏ)`.
    pub(crate) fn velocity(&self, y: &Vector3<f64>, yd: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
        let y2 = self.point(y);
        (y2, log_jacobian(&y2) * (exp_jacobian(y) * yd))
    }

    /// `(y', ẏ', ÿ')` of `(y, ẏ, ÿ)`.
    pub(crate) fn motion(
        &self,
        y: &Vector3<f64>,
        yd: &Vector3<f64>,
        ydd: &Vector3<f64>,
    ) -> [Vector3<f64>; 3] {
        let (y2, yd2) = self.velocity(y, yd);
        let (_, omega_dot) = angular_motion(y, yd, ydd);
        let (_, jdot_yd) = angular_motion(&y2, &yd2, &Vector3::zeros());
        [y2, yd2, log_jacobian(&y2) * (omega_dot - jdot_yd)]
    }
}

/// Learns a pose primitive from positions and orientations sampled at the same times.
///
/// The position part is [`learn()`] of `positions`, the orientation part [`learn_orientation`] of `orientations`
/// (its chart at the demonstration's last orientation), with the same basis, `alpha` and `tau`; `config.k` and
/// `config.d` give one value for every dimension, or `n + 3` values (the positions' then the orientation's, per
/// radian).
#[cfg(feature = "learn")]
pub fn learn_pose(
    positions: &Demonstration,
    orientations: &OrientationDemonstration,
    config: &LearnConfig,
) -> Result<Primitive> {
    let n = positions.dim();
    if positions.times() != orientations.times() {
        return Err(InvalidInput::new(
            "demonstration.orientations",
            "must be sampled at the times of the positions, one orientation per position",
        )
        .into());
    }
    let k = per_dimension("k", &config.k, n + 3)?;
    let d = config.d.as_ref().map(|d| per_dimension("d", d, n + 3)).transpose()?;
    let part = |range: std::ops::Range<usize>| LearnConfig {
        k: k[range.clone()].to_vec(),
        d: d.as_ref().map(|d| d[range].to_vec()),
        ..config.clone()
    };
    let p = learn(positions, &part(0..n))?;
    let o = learn_orientation(orientations, &part(n..n + 3))?;
    let mut joined = p;
    joined.dim = n + 3;
    joined.k.extend_from_slice(&o.dmp.k);
    joined.d.extend_from_slice(&o.dmp.d);
    joined.start.extend_from_slice(&o.dmp.start);
    joined.goal.extend_from_slice(&o.dmp.goal);
    joined.weights.extend(o.dmp.weights);
    joined.orientation = Some(OrientationChart { reference: o.goal });
    joined.validate()?;
    Ok(joined)
}

/// A replay of a pose primitive: the motion of its `n + 3` dimensions and the chart they are in.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseMotion {
    /// Start and goal in the chart's coordinates, and `tau`.
    pub motion: Motion,
    /// The chart: the goal orientation (Koutras and Doulgeri's state, zero at the goal).
    pub chart: UnitQuaternion<f64>,
}

/// The motion of a pose primitive from a position motion (`n` dimensions) and optional start and goal orientations
/// (`[x, y, z, w]`; `None`: the primitive's). The chart is at the goal orientation, so the orientation part starts
/// at `log(q_0 ⊗ q̄_g)` (the sign of the goal nearest the start: no turn of more than π) and ends at `0`.
/// Errors name `start_orientation` and `goal_orientation`.
pub fn pose_motion(
    p: &Primitive,
    position: Motion,
    start: Option<[f64; 4]>,
    goal: Option<[f64; 4]>,
) -> Result<PoseMotion, InvalidInput> {
    let reference = chart_of(p)?.ok_or_else(|| {
        InvalidInput::new(
            "goal_orientation",
            "the primitive has no orientation (it was learned from positions only)",
        )
    })?;
    let n = p.position_dim();
    let demo = |i: usize| from_chart(&reference, &Vector3::new(p.start[i], p.start[i + 1], p.start[i + 2]));
    let q0 = match start {
        Some(q) => from_xyzw("start_orientation", q)?,
        None => demo(n),
    };
    let qg = match goal {
        Some(q) => from_xyzw("goal_orientation", q)?,
        None => from_chart(&reference, &Vector3::new(p.goal[n], p.goal[n + 1], p.goal[n + 2])),
    };
    let chart = closest_sign(&qg, &q0);
    let y0 = log(&(q0 * chart.conjugate()));
    let mut motion = position;
    motion.start.truncate(n);
    motion.goal.truncate(n);
    motion.start.extend(y0.iter());
    motion.goal.extend([0.0; 3]);
    Ok(PoseMotion { motion, chart })
}

impl OrientationPoints {
    /// Appends the orientation of the point `x`, `xd`, `xdd` (all `dim` wide, the last three in the chart at
    /// `chart`).
    pub fn push(&mut self, chart: &UnitQuaternion<f64>, x: &[f64], xd: &[f64], xdd: &[f64]) {
        let at = |v: &[f64]| Vector3::from_column_slice(&v[v.len() - 3..]);
        let (y, yd, ydd) = (at(x), at(xd), at(xdd));
        let (omega, omega_dot) = angular_motion(&y, &yd, &ydd);
        let mut q = from_chart(chart, &y);
        // Continuous in sign: the chart covers angles up to π from the reference, where both signs meet.
        if let Some(prev) = self.q.len().checked_sub(4).map(|i| &self.q[i..]) {
            let dot = q.i * prev[0] + q.j * prev[1] + q.k * prev[2] + q.w * prev[3];
            if dot < 0.0 {
                q = UnitQuaternion::new_unchecked(-q.into_inner());
            }
        }
        self.q.extend(to_xyzw(&q));
        self.omega.extend(omega.iter());
        self.omega_dot.extend(omega_dot.iter());
    }

    /// The orientations of `x`, `xd`, `xdd` (row-major, `dim` per point).
    pub fn of(chart: &UnitQuaternion<f64>, dim: usize, x: &[f64], xd: &[f64], xdd: &[f64]) -> Self {
        let mut out = Self::default();
        for ((x, xd), xdd) in x.chunks_exact(dim).zip(xd.chunks_exact(dim)).zip(xdd.chunks_exact(dim)) {
            out.push(chart, x, xd, xdd);
        }
        out
    }
}
