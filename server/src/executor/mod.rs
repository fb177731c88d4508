//! Served runs: the engine's [`dmp::Execution`] with what the server adds around it ([`served_run`]), paced into a
//! gRPC stream ([`stream`], [`pacing`]) as segments ([`segments`]). The clock, the channels, supersession and pacing
//! live here; the stepping, the changes and the outcomes live in the engine.

pub mod ignored;
pub mod pacing;
pub mod plan;
pub mod segments;
pub mod served_run;
pub mod step;
pub mod stream;
pub mod stream_memory;

#[cfg(test)]
mod tests;

#[cfg(test)]
mod rejection_tests;
