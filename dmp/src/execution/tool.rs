//! A tool held by a pose run: the run's field and its cell-mates' act on the tool's control points, their sum
//! drives the position and their moments the orientation ([`crate::tool`], whose module doc has the formula).

use nalgebra::Vector3;

use super::Execution;
use super::blend::Blend;
use super::diagnosis::Diagnosis;
use super::pose::Chart;
use crate::error::InvalidInput;
use crate::field::{Contact, DEFAULT_MAX_PERTURBATION, RepulsiveField};
use crate::integrate::Perturbation;
use crate::tool::{Tool, ToolPose, angular_term, cap};

impl Execution {
    /// Holds `tool` (or nothing): the obstacles and cell-mates act on its control points, which turns the run's
    /// orientation ([`crate::tool`]), and contacts are judged on them. A tool sampled on its axis inflates every
    /// obstacle by [`crate::tool::ControlPoints::reach`] (the run's own now, the cell's as they are set). Only for
    /// a pose run moving in 3-D, once, before its first point and before the cell's obstacles are set; the error
    /// names `tool`. With axis samples, contacts are judged against the inflated obstacles: a contact then means
    /// the tool came within its reach of one (a clearance lost, not necessarily a touch).
    pub fn set_tool(&mut self, tool: Option<Tool>) -> Result<(), InvalidInput> {
        if tool.is_some() && (self.chart.is_none() || self.primitive.position_dim() != 3) {
            return Err(InvalidInput::new(
                "tool",
                "a tool needs a pose primitive (positions and orientations) moving in 3-D",
            ));
        }
        if self.has_last || self.out_t != 0.0 || self.tool.is_some() {
            return Err(InvalidInput::new("tool", "a tool is attached once, before the first point"));
        }
        if self.field.scene().obstacles.len() != self.scene.obstacles.len() {
            return Err(InvalidInput::new("tool", "a tool is attached before the cell's obstacles are set"));
        }
        self.rebase();
        self.tool = tool;
        let margin = self.tool_margin();
        if margin > 0.0 {
            let mut obstacles = Vec::with_capacity(self.scene.obstacles.len());
            for o in &self.scene.obstacles {
                obstacles.push(o.inflated(margin).map_err(|e| InvalidInput::new("tool", e.to_string()))?);
            }
            self.scene.obstacles = obstacles;
            self.field = RepulsiveField::new(self.scene.clone(), self.primitive.dim)
                .and_then(|f| f.keeping_off(self.keep_off()))
                .map_err(|e| InvalidInput::new("tool", e.to_string()))?;
        }
        Ok(())
    }

    /// How much the obstacles are inflated for the tool: its axis samples' reach, 0 otherwise.
    pub(super) fn tool_margin(&self) -> f64 {
        self.tool.as_ref().and_then(|t| t.sampling().reach(t.shape())).unwrap_or(0.0)
    }

    /// The tool held, if any.
    pub fn tool(&self) -> Option<&Tool> {
        self.tool.as_ref()
    }

    /// Adds to `out` the contacts of the tool's control points with the run's obstacles and the cell-mates, at
    /// the `n` points of `x` from `t0` (each point's index once per obstacle or robot).
    pub(super) fn tool_contacts(
        &mut self,
        t0: f64,
        x: &[f64],
        n: usize,
        out: &mut Vec<(usize, Contact)>,
        mates_out: &mut Vec<(usize, Contact)>,
    ) {
        let (Some(tool), Some(chart)) = (&self.tool, &self.chart) else { return };
        let d = self.primitive.dim;
        let dt = self.stepping.dt;
        let mut rows = vec![0.0; n * d];
        let mut found = Vec::new();
        for r in tool.control_points() {
            for k in 0..n {
                let row = &x[k * d..(k + 1) * d];
                let pose = ToolPose::from_state(row, row, chart);
                let c = pose.point(r).position;
                rows[k * d..k * d + 3].copy_from_slice(c.as_slice());
                rows[k * d + 3..(k + 1) * d].copy_from_slice(&row[3..]);
            }
            for (field, out) in [(&mut self.field, &mut *out), (&mut self.cell_mates, &mut *mates_out)] {
                found.clear();
                field.contacts_along(t0, dt, &rows, n, &mut found);
                for (k, c) in found.drain(..) {
                    let same = |(j, e): &(usize, Contact)| *j == k && same_thing(e, &c);
                    if !out.iter().any(same) {
                        out.push((k, c));
                    }
                }
            }
        }
        out.sort_by_key(|(k, _)| *k);
        mates_out.sort_by_key(|(k, _)| *k);
    }
}

/// The same obstacle or robot touched.
fn same_thing(a: &Contact, b: &Contact) -> bool {
    match (a, b) {
        (Contact::Obstacle { obstacle: x, .. }, Contact::Obstacle { obstacle: y, .. }) => x == y,
        (Contact::Robot { other: x, .. }, Contact::Robot { other: y, .. }) => x == y,
        _ => false,
    }
}

/// The fields' terms on `tool` at the pose state `x`, `v = tau dx/dt` (dimension 6): `F = sum_i phi_i` on the
/// position rows and `J(y)⁻¹ R I⁻¹ Rᵀ sum_i (R r_i) × phi_i` on the orientation rows, each capped.
#[allow(clippy::too_many_arguments)]
pub(super) fn add_on_tool(
    field: &mut RepulsiveField,
    blend: &mut Blend,
    mates: &mut RepulsiveField,
    tool: &Tool,
    chart: &Chart,
    t: f64,
    x: &[f64],
    v: &[f64],
    tau: f64,
    out: &mut [f64],
    mut diagnosis: Option<&mut Diagnosis>,
) {
    if x.len() != 6 {
        return;
    }
    let pose = ToolPose::from_state(x, v, chart);
    let (mut force, mut moment) = (Vector3::zeros(), Vector3::zeros());
    let (mut xi, mut vi) = ([0.0; 6], [0.0; 6]);
    let mut nonfinite = false;
    xi[3..].copy_from_slice(&x[3..]);
    vi[3..].copy_from_slice(&v[3..]);
    for r in tool.control_points() {
        let m = pose.point(r);
        xi[..3].copy_from_slice(m.position.as_slice());
        vi[..3].copy_from_slice(m.velocity.as_slice());
        if let Some(d) = diagnosis.as_deref_mut() {
            // As at a point robot: the obstacles whose term is not finite at this control point.
            d.check(field, mates, (t, &xi, &vi, tau));
        }
        let mut phi = [0.0; 6];
        blend.add(field, t, &xi, &vi, tau, &mut phi);
        mates.add(t, &xi, &vi, tau, &mut phi);
        let phi = Vector3::new(phi[0], phi[1], phi[2]);
        if !phi.iter().all(|v| v.is_finite()) {
            // Not summed: one point's term must not zero the others' (the step is diagnosed as not finite).
            nonfinite = true;
            continue;
        }
        force += phi;
        moment += m.arm.cross(&phi);
    }
    let force = cap(force, DEFAULT_MAX_PERTURBATION);
    let angular = cap(angular_term(tool, &pose, &moment), DEFAULT_MAX_PERTURBATION);
    for i in 0..3 {
        out[i] += force[i];
        out[3 + i] += angular[i];
    }
    if nonfinite {
        // The step is then redone under diagnosis, and the obstacles at fault dropped and reported.
        out[0] = f64::NAN;
    }
}
