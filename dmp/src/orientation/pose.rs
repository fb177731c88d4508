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
//! A new goal orientation `q_new` during a run is the goal `log(q_new ⊗ q̄_ref)` of the same chart (the sign of
//! `q_new` nearest the reference): the chart covers every orientation less than π from `q_ref`.

use nalgebra::{UnitQuaternion, Vector3};

use super::jacobian::angular_motion;
use super::quaternion::{closest_sign, exp, from_xyzw, log, to_xyzw};
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
