//! Obstacle-aware orientation: the repulsive terms act on the control points of a held tool, their sum drives the
//! position and their moments the orientation.
//!
//! The paper controls one point and inflates the obstacles by the held object's size; its conclusions leave "the
//! obstacle-aware adaptation of the orientation" as future work. Here the tool is a superquadric in the tool frame
//! ([`Tool`]), sampled by control points ([`ControlPoints`]: its surface, or the axis of a long tool), and each
//! point feels the scene's field exactly as a point robot would ([`crate::field::RepulsiveField`], any of the five
//! methods of [`crate::avoidance`]).
//!
//! # Formula
//! The pose run of `pose-convention` (dimension 6): `x = (p, y)`, `v = tau (ṗ, ẏ)`, `q = exp(y) ⊗ q_ref`,
//! `R = R(q)`, `ω = J(y) ẏ` (`orientation/jacobian.rs`). For each control point `r_i` (tool frame,
//! `i = 1..N`):
//!
//! - `a_i = R r_i`, `c_i = p + a_i`, `tau ċ_i = tau ṗ + (tau ω) × a_i` ([`ToolPose::point`]);
//! - `phi_i = phi(c_i, tau ċ_i)`: the scene's term at the point (with `u = tau ċ_i - tau ȯ` for a moving
//!   obstacle), in the units of `tau dv/dt`.
//!
//! The transformation system (`eq:dmp_acc_obst`) gets, in its position rows and its rotation-vector rows,
//!
//! - `tau v̇_p = K (g - p) - D v_p - K (g - p_0) s + K f(s) + F`, with `F = sum_i phi_i`;
//! - `tau v̇_y = K (g_y - y) - D v_y - K (g_y - y_0) s + K f(s) + J(y)⁻¹ I_w⁻¹ M`, with
//!   `M = sum_i a_i × phi_i`, `I_w = R I Rᵀ` and `I = (1 / N) sum_i (|r_i|² 1 - r_i r_iᵀ)` ([`inertia`]).
//!
//! These are the Newton–Euler equations of a rigid body of unit mass spread evenly over the control points, each
//! pulled by its `phi_i`, written about the tool origin `p`: `F` is the acceleration of the origin (times `tau²`,
//! as in the paper's term) and `I_w⁻¹ M` the angular acceleration `tau² ω̇` (in rad: `phi` is in m, `M` in m², `I`
//! in m²), which `ω̇ = J(y) ÿ + J̇ ẏ` maps to the chart as `tau² ÿ = J(y)⁻¹ tau² ω̇`. Left out, as a Cartesian
//! impedance about a robot's tool centre point leaves them out: the `J̇ ẏ` part (it belongs to the orientation
//! DMP's own motion, not to the coupling), the gyroscopic `ω × I ω`, and the coupling of translation and rotation
//! when the points' centroid is not at `p` (a tool held off its middle). The inertia
//! normalises the moment: a moment in m² becomes an angle, so the orientation gains `K`, `D` (per radian) and the
//! coupling meet in the same units, whatever the tool's size. Where `I` is singular (a tool sampled on its axis:
//! no moment about the axis exists) its pseudo-inverse is used.
//!
//! For a static potential `U` (static point, static volumetric), `phi_i = -grad U(c_i)`, so with
//! `U_tool(p, q) = sum_i U(c_i)`: `F = -dU_tool/dp` and `M = -dU_tool/dθ` for a small rotation `q -> exp(θ) q`
//! (since `d c_i = θ × a_i`). The tests check both against finite differences.
//!
//! Inside an obstacle, each point's term is the scene field's (with `C` floored, capped); `F` and the angular
//! term are capped at [`crate::field::DEFAULT_MAX_PERTURBATION`] too.
//!
//! # Limits
//! Repulsion turns a tool only where the moments point the right way. A long tool met head-on by a gap narrower
//! than it is pushed back where it touches first, which turns it square to its motion: with the static potentials
//! that balance is stable and the run stalls in front of the gap; the dynamic volumetric potential, which also
//! steers each point's velocity around what it approaches, threads it (the experiment in
//! `dmp/tests/properties/bar_through_gap.rs`). A tool exactly square to a symmetric gap feels no moment at all: a
//! local minimum, reported as a stall like the paper's.
//!
//! | concept | module or file |
//! | --- | --- |
//! | control points: surface or axis samples | [`sampling`] |
//! | the tool: shape, offset, control points, inertia | [`Tool`], `tool/body.rs` |
//! | the points' places and velocities at a pose | [`ToolPose`], `tool/kinematics.rs` |
//! | the field on the tool (a [`crate::Perturbation`] of a pose run) | [`ToolField`], `tool/field.rs` |

mod body;
mod clearance;
mod field;
mod kinematics;
pub mod sampling;

pub use body::{Tool, inertia};
pub use clearance::{sampled_clearance, surface_samples};
pub use field::ToolField;
pub(crate) use field::{angular_term, cap};
pub use kinematics::{PointMotion, ToolPose};
pub use sampling::ControlPoints;

#[cfg(test)]
mod tests;
