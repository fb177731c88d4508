//! The scenario format of `shared/scenarios/SPEC.md`: one reproducible experiment (a demonstration, a DMP
//! configuration, obstacles, an avoidance method, a rollout). This module holds the data model, its validation with
//! errors naming the field, and the offline run; parsing the JSON text is the caller's business.

mod model;
#[cfg(all(feature = "learn", feature = "orientation"))]
mod pose;
#[cfg(all(feature = "learn", feature = "orientation"))]
mod run;
mod to_engine;

pub use model::{
    DemonstrationSpec, DmpSpec, FootprintSpec, NestedSpec, ObstacleSpec, OneOrMany, RobotSpec, RolloutSpec,
    Scenario, ToolPointsKind, ToolSpec,
};
#[cfg(all(feature = "learn", feature = "orientation"))]
pub use pose::PoseSetup;
#[cfg(all(feature = "learn", feature = "orientation"))]
pub use run::{Prepared, ScenarioOutcome, prepare, run};
