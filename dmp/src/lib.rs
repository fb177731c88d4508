//! Dynamic Movement Primitives with volumetric obstacle avoidance, after Ginesi et al., "Dynamic Movement
//! Primitives: Volumetric Obstacle Avoidance Using Dynamic Potential Functions" (and its ERRATA.md).
//!
//! Pure math: no I/O, no clock, no async. Time and `dt` are arguments.
//!
//! | concept | module or file |
//! | --- | --- |
//! | canonical system (phase in closed form) | [`canonical`] |
//! | Gaussian basis and forcing term | `basis.rs` |
//! | learning from one demonstration | [`Demonstration`], `learn.rs`, `derivatives.rs` |
//! | the stored primitive | [`primitive`] |
//! | RK4 integration, step by step | [`integrate`] |
//! | one run of one robot or a group: stepping, changes, rollbacks, outcomes | [`execution`] |
//! | isopotentials (superquadrics) | [`isopotential`] |
//! | obstacles (pose, motion, boundary samples) | [`Obstacle`], `obstacle.rs` |
//! | the five repulsive terms | [`avoidance`] |
//! | a whole scene, robots as moving obstacles | [`field`] |
//! | rollouts, stalls | [`mod@rollout`], [`stall`] |
//! | the ranges that keep every term finite | [`ranges`] |
//! | orientation DMPs on unit quaternions (feature `orientation`) | [`orientation`] |
//! | a held tool: repulsive terms on its control points drive position and orientation | [`tool`] |

#![warn(missing_docs)]
#![warn(unreachable_pub)]

pub mod avoidance;
pub(crate) mod basis;
pub mod canonical;
pub(crate) mod dense;
#[cfg(feature = "learn")]
pub(crate) mod derivatives;
pub(crate) mod directions;
pub mod distance;
pub(crate) mod error;
pub mod execution;
pub mod field;
pub mod integrate;
pub mod isopotential;
pub(crate) mod learn;
#[cfg(all(feature = "learn", feature = "orientation"))]
pub mod metrics;
pub(crate) mod obstacle;
#[cfg(feature = "orientation")]
pub mod orientation;
pub mod primitive;
pub mod ranges;
pub mod rollout;
pub mod scenario;
pub mod stall;
#[cfg(feature = "orientation")]
pub mod tool;

pub use avoidance::{Avoidance, Method};
pub use error::{DmpError, InvalidInput, Result};
pub use execution::{Execution, LimitAction, Limits, Outcome, Stepping};
pub use field::{Agent, Contact, RepulsiveField, Scene};
pub use integrate::{Integrator, Motion, NoPerturbation, Perturbation, State};
pub use isopotential::{Isopotential, NestedSuperquadric, Shape, Superquadric};
#[cfg(feature = "learn")]
pub use learn::learn;
pub use learn::{Demonstration, LearnConfig};
pub use obstacle::Obstacle;
#[cfg(all(feature = "orientation", feature = "learn"))]
pub use orientation::learn_orientation;
#[cfg(feature = "orientation")]
pub use orientation::{
    OrientationDemonstration, OrientationMotion, OrientationPrimitive, OrientationRun, OrientationSample,
    OrientationTrajectory, rollout_orientation,
};
pub use primitive::{OrientationChart, Primitive};
pub use rollout::{Rollout, Trajectory, rollout};
