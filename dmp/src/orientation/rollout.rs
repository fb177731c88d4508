//! Full orientation rollouts: fixed step, one row per step.

use nalgebra::{UnitQuaternion, Vector3};

use super::primitive::OrientationPrimitive;
use super::run::{OrientationMotion, OrientationRun, OrientationSample};
use crate::error::{InvalidInput, Result, ensure_positive};
use crate::rollout::MAX_ROLLOUT_STEPS;

/// A sampled orientation trajectory: `len()` rows at `t = k dt`, each with the orientation `[x, y, z, w]`, the
/// angular velocity and the angular acceleration (world frame, rad/s and rad/s²).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct OrientationTrajectory {
    /// Times.
    pub t: Vec<f64>,
    /// Orientations `[x, y, z, w]`, continuous in sign, starting with the motion's start as given.
    pub q: Vec<[f64; 4]>,
    /// Angular velocities `ω`, world frame.
    pub omega: Vec<[f64; 3]>,
    /// Angular accelerations `ω̇`, world frame.
    pub omega_dot: Vec<[f64; 3]>,
}

impl OrientationTrajectory {
    /// Appends a row.
    pub fn push(&mut self, s: &OrientationSample) {
        self.t.push(s.t);
        self.q.push(super::quaternion::to_xyzw(&s.q));
        self.omega.push(s.omega.into());
        self.omega_dot.push(s.omega_dot.into());
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// True without rows.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// Orientation of row `k`.
    pub fn orientation(&self, k: usize) -> UnitQuaternion<f64> {
        let [x, y, z, w] = self.q[k];
        UnitQuaternion::new_unchecked(nalgebra::Quaternion::new(w, x, y, z))
    }

    /// Angular velocity of row `k`.
    pub fn angular_velocity(&self, k: usize) -> Vector3<f64> {
        self.omega[k].into()
    }

    /// Angular acceleration of row `k`.
    pub fn angular_acceleration(&self, k: usize) -> Vector3<f64> {
        self.omega_dot[k].into()
    }
}

/// Rolls `primitive` out from rest at `motion.start` for `steps` steps of `dt` (RK4 at `dt`): `steps + 1` rows
/// from `t = 0`. See [`OrientationRun`] for the formulation.
pub fn rollout_orientation(
    primitive: &OrientationPrimitive,
    motion: &OrientationMotion,
    dt: f64,
    steps: usize,
) -> Result<OrientationTrajectory> {
    ensure_positive(|| "rollout.dt".into(), dt)?;
    if steps > MAX_ROLLOUT_STEPS {
        return Err(InvalidInput::new(
            "rollout.duration",
            format!("gives {steps} steps, more than the limit of {MAX_ROLLOUT_STEPS}"),
        )
        .into());
    }
    let mut run = OrientationRun::new(primitive, motion)?;
    let mut out = OrientationTrajectory {
        t: Vec::with_capacity(steps + 1),
        q: Vec::with_capacity(steps + 1),
        omega: Vec::with_capacity(steps + 1),
        omega_dot: Vec::with_capacity(steps + 1),
    };
    out.push(&run.sample());
    for k in 1..=steps {
        run.step(dt).map_err(|e| e.within("rollout"))?;
        let mut sample = run.sample();
        // Times on the grid, not accumulated sums of dt.
        sample.t = k as f64 * dt;
        out.push(&sample);
    }
    Ok(out)
}
