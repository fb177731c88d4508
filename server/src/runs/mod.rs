//! Served runs: the engine's [`dmp::Execution`] with what the server adds around it ([`served_run`]), paced into a
//! gRPC stream ([`stream`], [`pacing`]) as segments ([`segments`]). The clock, the channels, supersession and pacing
//! live here; the stepping, the changes and the outcomes live in the engine.

pub mod compute;
pub(crate) mod context;
pub(crate) mod control;
pub(crate) mod endpoints;
pub(crate) mod executing;
pub(crate) mod histograms;
pub(crate) mod ignored;
pub(crate) mod outbox;
pub mod pacing;
pub(crate) mod plan;
pub(crate) mod segments;
pub(crate) mod served_run;
pub(crate) mod step;
pub(crate) mod stream;
pub mod stream_memory;
pub(crate) mod verdict;

#[cfg(test)]
mod tests;

#[cfg(test)]
mod accuracy_tests;

#[cfg(test)]
mod rejection_tests;
