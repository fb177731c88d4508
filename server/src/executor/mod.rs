//! Executions: the [`runner::Runner`] state machine (pure stepping, scene and command changes, rollbacks) and the
//! [`stream`] loop that paces it and feeds a gRPC stream.

pub mod runner;
pub mod stream;
