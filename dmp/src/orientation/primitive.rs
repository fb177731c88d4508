//! The learned orientation primitive: a three-dimensional [`Primitive`] on the rotation vector of the orientation
//! error, with the demonstration's start and goal orientations.

use nalgebra::UnitQuaternion;
use serde::{Deserialize, Serialize};

#[cfg(feature = "learn")]
use super::demonstration::OrientationDemonstration;
use super::quaternion::from_xyzw;
#[cfg(feature = "learn")]
use super::quaternion::{log, to_xyzw};
use crate::error::{InvalidInput, Result};
#[cfg(feature = "learn")]
use crate::learn::{Demonstration, LearnConfig, learn};
use crate::primitive::Primitive;

/// An orientation DMP learned from one demonstration (Koutras and Doulgeri's formulation, see
/// [`crate::orientation`]).
///
/// `dmp` is an ordinary DMP of dimension 3 on `y = log(q ⊗ q̄_g)` (the rotation vector taking the goal to `q`, in
/// the world frame): its `start` is `y` at the demonstration's first sample and its `goal` is `0`. `start` and
/// `goal` are the demonstration's orientations, `[x, y, z, w]`, signs consistent with each other (the goal is in
/// the sign the demonstration reached it with). It replays identically after a save and a load (serialize with
/// exact float round-trips, e.g. `serde_json` with `float_roundtrip`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OrientationPrimitive {
    /// The DMP on the rotation vector `y`, radians.
    pub dmp: Primitive,
    /// The demonstration's first orientation, `[x, y, z, w]`.
    pub start: [f64; 4],
    /// The demonstration's last orientation, `[x, y, z, w]`.
    pub goal: [f64; 4],
}

impl OrientationPrimitive {
    /// Checks a primitive that came from outside (a file, a store, the network): a valid [`Primitive`] of
    /// dimension 3 whose goal is `0`, and unit quaternions.
    pub fn validate(&self) -> Result<()> {
        self.dmp.validate().map_err(|e| e.within("dmp"))?;
        if self.dmp.dim != 3 {
            return Err(InvalidInput::new(
                "dmp.dim",
                format!("must be 3 (the rotation vector), found {}", self.dmp.dim),
            )
            .into());
        }
        if self.dmp.goal.iter().any(|g| *g != 0.0) {
            return Err(
                InvalidInput::new("dmp.goal", "must be 0 (the state is the error to the goal)").into()
            );
        }
        from_xyzw("start", self.start)?;
        from_xyzw("goal", self.goal)?;
        Ok(())
    }

    /// The demonstration's first orientation.
    pub fn start_orientation(&self) -> Result<UnitQuaternion<f64>, InvalidInput> {
        from_xyzw("start", self.start)
    }

    /// The demonstration's last orientation.
    pub fn goal_orientation(&self) -> Result<UnitQuaternion<f64>, InvalidInput> {
        from_xyzw("goal", self.goal)
    }
}

/// Learns an orientation primitive from one demonstration (Koutras and Doulgeri, "the proposed formulation").
///
/// # Formula
/// With `q_g` the demonstration's last sample (signs made consistent by [`OrientationDemonstration::new`]),
/// `y_k = log(q_k ⊗ q̄_g)` ([`super::quaternion::log`], continuous along the demonstration, `y = 0` at the goal).
/// The three coordinates of `y` are then learned as a position demonstration by [`crate::learn()`]: `tau` the
/// duration, `ẏ` and `ÿ` by second-order finite differences, the forcing weights by least squares of
/// `f(s_k) = (tau² ÿ_k + D tau ẏ_k - K (0 - y_k) + K (0 - y_0) s_k) / K`. The gains `K`, `D` act on radians.
///
/// A demonstration whose net rotation exceeds 180° is learned as made (`|y_0| > π`), but a replay always turns
/// from its start to its goal the short way ([`super::OrientationRun`]), so such a demonstration is not replayed
/// as made even from its own start.
#[cfg(feature = "learn")]
pub fn learn_orientation(
    demo: &OrientationDemonstration,
    config: &LearnConfig,
) -> Result<OrientationPrimitive> {
    let goal = demo.goal();
    let goal_conj = goal.conjugate();
    let y: Vec<Vec<f64>> =
        demo.quaternions().iter().map(|q| log(&(q * goal_conj)).iter().copied().collect()).collect();
    let tangent = Demonstration::new(demo.times().to_vec(), y)?;
    let mut dmp = learn(&tangent, config)?;
    // log(q_g ⊗ q̄_g) is 0 up to the rounding of the product; the goal of the error is exactly 0.
    dmp.goal = vec![0.0; 3];
    Ok(OrientationPrimitive { dmp, start: to_xyzw(&demo.start()), goal: to_xyzw(&goal) })
}
