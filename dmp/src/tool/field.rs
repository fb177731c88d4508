//! The repulsive field of a scene on a held tool: forces on its control points, summed for the position, their
//! moments for the orientation.

use nalgebra::{UnitQuaternion, Vector3};

use super::body::Tool;
use super::kinematics::ToolPose;
use crate::error::{InvalidInput, Result};
use crate::field::{DEFAULT_MAX_PERTURBATION, RepulsiveField, Scene};
use crate::integrate::Perturbation;
use crate::orientation::jacobian::log_jacobian;

/// Dimension of a pose run's state: position (3) and rotation vector (3).
pub(crate) const POSE_DIM: usize = 6;

/// The summed force and moment of the scene on the tool, world frame, in units of `tau dv/dt` (times metres for
/// the moment).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Wrench {
    /// `F = sum_i phi_i`.
    pub(crate) force: Vector3<f64>,
    /// `M = sum_i (R r_i) × phi_i`, about the tool origin `p`.
    pub(crate) moment: Vector3<f64>,
}

/// A scene's repulsive field acting on a [`Tool`], for a pose run of dimension 6 (position, then the rotation
/// vector `y` of the chart anchored at `q_ref`; see the module's formula).
///
/// Each control point is a robot of [`RepulsiveField`]: the same five methods, the same relative velocity of
/// moving obstacles, the same floor on `C` inside an obstacle and the same cap on each point's term. The summed
/// force and the angular term are each capped at [`DEFAULT_MAX_PERTURBATION`] too, so no state with finite entries
/// gives a term that is not finite (`J(y)⁻¹` grows without bound as `|y|` nears `2π`, where the chart ends; the
/// cap holds there).
#[derive(Debug, Clone)]
pub struct ToolField {
    field: RepulsiveField,
    tool: Tool,
    q_ref: UnitQuaternion<f64>,
    max_perturbation: f64,
}

impl ToolField {
    /// Compiles `scene` (3-D obstacles, no robots of its own: the tool is the one robot) for `tool`, in the chart
    /// anchored at `q_ref`. Errors name the field (`q_ref`, `robots`, `obstacles[i]`, `avoidance.*`,
    /// `point_samples`).
    pub fn new(tool: Tool, scene: Scene, q_ref: UnitQuaternion<f64>) -> Result<Self> {
        if q_ref.coords.iter().any(|c| !c.is_finite()) {
            return Err(InvalidInput::new("q_ref", "must be a unit quaternion of finite numbers").into());
        }
        if !scene.agents.is_empty() {
            return Err(InvalidInput::new(
                "robots",
                "a tool field moves one robot, the tool's: the scene must name no robots",
            )
            .into());
        }
        let field = RepulsiveField::new(scene, 3)?;
        Ok(Self { field, tool, q_ref, max_perturbation: DEFAULT_MAX_PERTURBATION })
    }

    /// The tool.
    pub fn tool(&self) -> &Tool {
        &self.tool
    }

    /// The chart's anchor.
    pub fn q_ref(&self) -> UnitQuaternion<f64> {
        self.q_ref
    }

    /// The compiled field of the scene, which each control point feels.
    pub fn field(&self) -> &RepulsiveField {
        &self.field
    }

    /// The summed force and moment at the state `x = (p, y)`, `v = tau (ṗ, ẏ)`, time `t` (uncapped sums of the
    /// points' terms, each capped by the scene's field).
    #[cfg(test)]
    pub(crate) fn wrench(&mut self, t: f64, x: &[f64], v: &[f64], tau: f64) -> Wrench {
        let pose = ToolPose::from_state(x, v, &self.q_ref);
        self.wrench_at(t, &pose, tau)
    }

    fn wrench_at(&mut self, t: f64, pose: &ToolPose, tau: f64) -> Wrench {
        let mut w = Wrench { force: Vector3::zeros(), moment: Vector3::zeros() };
        for r in self.tool.control_points() {
            let m = pose.point(r);
            let mut phi = [0.0; 3];
            self.field.add(t, m.position.as_slice(), m.velocity.as_slice(), tau, &mut phi);
            let phi = Vector3::from(phi);
            w.force += phi;
            w.moment += m.arm.cross(&phi);
        }
        w
    }

    /// The angular term in chart coordinates for a moment `M` at `pose`: `J(y)⁻¹ R I⁻¹ Rᵀ M` (module formula).
    pub(crate) fn angular_term(&self, pose: &ToolPose, moment: &Vector3<f64>) -> Vector3<f64> {
        angular_term(&self.tool, pose, moment)
    }
}

impl Perturbation for ToolField {
    /// Adds `F` to `out[0..3]` and `J(y)⁻¹ R I⁻¹ Rᵀ M` to `out[3..6]` (each capped). A state of another dimension
    /// adds nothing.
    fn add(&mut self, t: f64, x: &[f64], v: &[f64], tau: f64, out: &mut [f64]) {
        if x.len() != POSE_DIM || v.len() != POSE_DIM || out.len() != POSE_DIM {
            return;
        }
        let pose = ToolPose::from_state(x, v, &self.q_ref);
        let w = self.wrench_at(t, &pose, tau);
        let force = cap(w.force, self.max_perturbation);
        let angular = cap(self.angular_term(&pose, &w.moment), self.max_perturbation);
        for i in 0..3 {
            out[i] += force[i];
            out[3 + i] += angular[i];
        }
    }
}

/// The angular term in chart coordinates for a moment `M` on `tool` at `pose`: `J(y)⁻¹ R I⁻¹ Rᵀ M` (module
/// formula).
pub(crate) fn angular_term(tool: &Tool, pose: &ToolPose, moment: &Vector3<f64>) -> Vector3<f64> {
    let r = &pose.rotation;
    log_jacobian(&pose.chart) * (r * (tool.inertia_inverse() * (r.transpose() * moment)))
}

/// `v` scaled down to norm `max` when longer; a vector that is not finite (the sums of capped terms never are,
/// unless the state is not) becomes zero, as a term with no direction.
pub(crate) fn cap(v: Vector3<f64>, max: f64) -> Vector3<f64> {
    let n = v.norm();
    if !n.is_finite() {
        Vector3::zeros()
    } else if n > max {
        v * (max / n)
    } else {
        v
    }
}
