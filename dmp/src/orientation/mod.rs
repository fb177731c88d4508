//! Orientation DMPs on unit quaternions, after Koutras and Doulgeri, "A correct formulation for the orientation
//! dynamic movement primitives for robot control in the Cartesian space" (CoRL 2019, PMLR 100:293–302).
//!
//! # The formulation
//! An ordinary DMP of this crate (same canonical system, Gaussian basis, stiffness `K` and damping `D`) runs on
//! the orientation error in the tangent space, `y = log(q ⊗ q̄_g)`, which is zero at the goal, and the output is
//! `q = exp(y) ⊗ q_g`: every output is a unit quaternion, and `y` has the role a position has in the position DMP,
//! with `ẏ` and `ÿ` its true time derivatives. The angular velocity and acceleration follow from `(y, ẏ, ÿ)`
//! exactly, through the Jacobian of the exponential map (`orientation/jacobian.rs`). See [`OrientationRun`] for the equations.
//!
//! # What Ude et al.'s form gets wrong
//! Ude, Nemec, Petrič and Morimoto, "Orientation in Cartesian Space Dynamic Movement Primitives" (ICRA 2014),
//! drive the angular velocity, `tau η̇ = α_z (β_z 2 log(q_g ⊗ q̄) - η) + f(s)` with `η = tau ω`, and integrate
//! `q(t + dt) = exp(dt ω / 2) ⊗ q(t)`, with `f` learned from the demonstration's `ω` and `ω̇`. The spring acts on
//! `2 log(q_g ⊗ q̄)` but the damper and the forcing term act on `ω`, which is not (up to sign) the time derivative
//! of that logarithm: they differ by the Jacobian of the logarithm, the identity only while `ω` is parallel to the
//! axis of the error. Koutras and Doulgeri show that this is not the exact counterpart of the position DMP: with a
//! new start or goal the motion can oscillate and depart far from the demonstrated shape. Their remedy,
//! implemented here, puts position, velocity and acceleration in the same tangent coordinates, so the position
//! DMP's properties (convergence to the goal, time scaling, the spatial generalisation of [`crate::Integrator`])
//! carry over unchanged.
//!
//! Equation numbers are left out until they are checked against the full texts (only the abstracts were at hand).
//!
//! # Conventions
//! Wire order `[x, y, z, w]`; the logarithm is the rotation vector (angle times axis, radians), so `K` is per
//! radian; `ω` and `ω̇` are in the world (base) frame, `q̇ = ½ (0, ω) ⊗ q`; a goal and its opposite give the same
//! run (the sign nearest the start is used, so no run turns the long way). Details in [`quaternion`].
//!
//! | concept | module or file |
//! | --- | --- |
//! | wire order, log and exp, double cover, angles | [`quaternion`] |
//! | Jacobians of exp and log, angular velocity and acceleration | `orientation/jacobian.rs` |
//! | a demonstration, checked and sign-consistent | [`OrientationDemonstration`], `orientation/demonstration.rs` |
//! | the learned primitive, learning | [`OrientationPrimitive`], `orientation/primitive.rs` |
//! | a run, stepped by the caller | [`OrientationRun`], `orientation/run.rs` |
//! | full rollouts | [`rollout_orientation`], `orientation/rollout.rs` |
//! | pose primitives (position and orientation on one phase), learning and replay | [`pose`] |

pub(crate) mod demonstration;
pub(crate) mod jacobian;
pub mod pose;
pub(crate) mod primitive;
pub mod quaternion;
pub(crate) mod rollout;
pub(crate) mod run;

pub use demonstration::OrientationDemonstration;
pub use primitive::OrientationPrimitive;
#[cfg(feature = "learn")]
pub use primitive::learn_orientation;
pub use rollout::{OrientationTrajectory, rollout_orientation};
pub use run::{OrientationMotion, OrientationRun, OrientationSample};
