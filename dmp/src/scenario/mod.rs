//! The scenario format of `shared/scenarios/SPEC.md`: one reproducible experiment (a demonstration, a DMP
//! configuration, obstacles, an avoidance method, a rollout). This module holds the data model, its validation with
//! errors naming the field, and the offline run; parsing the JSON text is the caller's business.

mod model;
#[cfg(feature = "learn")]
mod run;
mod to_engine;

pub use model::{
    DemonstrationSpec, DmpSpec, FootprintSpec, NestedSpec, ObstacleSpec, OneOrMany, RobotSpec, RolloutSpec,
    Scenario,
};
#[cfg(feature = "learn")]
pub use run::{Prepared, ScenarioOutcome, prepare, run};
