//! Where the control points are and how fast they move, from the pose state of a run.

use nalgebra::{Matrix3, UnitQuaternion, Vector3};

use crate::orientation::jacobian::exp_jacobian;
use crate::orientation::quaternion::exp;

/// The tool's pose and its motion at one state of a pose run (pose-convention: the position `p` in dimensions
/// `0..3`, the rotation vector `y` of the chart anchored at `q_ref` in `3..6`). Velocities are the DMP's velocity
/// state, `tau` times the time derivative, like the `v` that [`crate::Perturbation::add`] receives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ToolPose {
    /// `p`.
    pub position: Vector3<f64>,
    /// `R(q)`, `q = exp(y) ⊗ q_ref`: tool frame to world.
    pub rotation: Matrix3<f64>,
    /// `tau ṗ`.
    pub velocity: Vector3<f64>,
    /// `tau ω = J(y) (tau ẏ)`, world frame.
    pub angular_velocity: Vector3<f64>,
    /// `y`.
    pub chart: Vector3<f64>,
}

/// One control point at a pose: its arm `a = R r` from the tool origin, its place `c = p + a` and its velocity
/// `tau ċ = tau ṗ + tau ω × a`, world frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointMotion {
    /// `a = R r`.
    pub arm: Vector3<f64>,
    /// `c = p + R r`.
    pub position: Vector3<f64>,
    /// `tau ċ = tau (ṗ + ω × R r)`.
    pub velocity: Vector3<f64>,
}

impl ToolPose {
    /// The pose of the state `x = (p, y)`, `v = tau (ṗ, ẏ)` (six entries each, the first six used).
    ///
    /// # Formula
    /// `q = exp(y) ⊗ q_ref`, `ω = J(y) ẏ` (`orientation/jacobian.rs`).
    pub fn from_state(x: &[f64], v: &[f64], q_ref: &UnitQuaternion<f64>) -> Self {
        let chart = Vector3::new(x[3], x[4], x[5]);
        let q = exp(&chart) * q_ref;
        let yd = Vector3::new(v[3], v[4], v[5]);
        Self {
            position: Vector3::new(x[0], x[1], x[2]),
            rotation: *q.to_rotation_matrix().matrix(),
            velocity: Vector3::new(v[0], v[1], v[2]),
            angular_velocity: exp_jacobian(&chart) * yd,
            chart,
        }
    }

    /// The control point `r` (tool frame) at this pose.
    pub fn point(&self, r: &Vector3<f64>) -> PointMotion {
        let arm = self.rotation * r;
        PointMotion {
            arm,
            position: self.position + arm,
            velocity: self.velocity + self.angular_velocity.cross(&arm),
        }
    }
}
