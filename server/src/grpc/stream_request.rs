//! What a streamed execution asks for (the fields ExecuteRequest and ExecuteGroupRequest share), its defaults
//! and its validation.

use std::time::Duration;

use dmp::Stepping;
use dmp_proto::v1;

use crate::config::Config;
use crate::connections::write_batching::Urgency;
use crate::error::ServerError;
use crate::runs::pacing::StreamConfig;

/// Default output step.
pub(super) const DEFAULT_DT: f64 = 0.001;
/// Default segment length, seconds.
const DEFAULT_SEGMENT_S: f64 = 0.01;
/// Default real-time lookahead, seconds.
const DEFAULT_LOOKAHEAD_S: f64 = 0.05;
/// Largest adaptive-step tolerance accepted (a looser one would not be an accurate trajectory).
const MAX_TOLERANCE: f64 = 1e-2;

/// How a stream was asked to run: the fields ExecuteRequest and ExecuteGroupRequest share (0 means the default).
pub(super) struct StreamRequest {
    pub(super) dt: f64,
    pub(super) segment_s: f64,
    pub(super) pacing: i32,
    pub(super) lookahead_s: f64,
    pub(super) max_duration_s: f64,
    pub(super) integration_step_s: f64,
    pub(super) integration_tolerance: f64,
}

/// The shared fields of an ExecuteRequest or an ExecuteGroupRequest (two messages with the same field names).
macro_rules! stream_fields {
    ($r:expr) => {
        StreamRequest {
            dt: $r.dt,
            segment_s: $r.segment_s,
            pacing: $r.pacing,
            lookahead_s: $r.lookahead_s,
            max_duration_s: $r.max_duration_s,
            integration_step_s: $r.integration_step_s,
            integration_tolerance: $r.integration_tolerance,
        }
    };
}

impl StreamRequest {
    pub(super) fn of(r: &v1::ExecuteRequest) -> Self {
        stream_fields!(r)
    }

    pub(super) fn of_group(r: &v1::ExecuteGroupRequest) -> Self {
        stream_fields!(r)
    }

    /// Fills in the defaults and checks every field (the error names it): the stream's configuration for a motion
    /// of time scale `tau`, sent on a connection of `urgency` (when it batches its writes).
    pub(super) fn config(
        self,
        tau: f64,
        config: &Config,
        urgency: Option<Urgency>,
    ) -> Result<StreamConfig, ServerError> {
        let StreamRequest {
            dt,
            segment_s,
            pacing,
            lookahead_s,
            max_duration_s,
            integration_step_s,
            integration_tolerance,
        } = self;
        let dt = if dt == 0.0 { DEFAULT_DT } else { dt };
        if !(dt.is_finite() && dt > 0.0 && dt <= 0.1) {
            return Err(ServerError::invalid("dt", "must be greater than 0 and at most 0.1 s"));
        }
        let segment_s = if segment_s == 0.0 { DEFAULT_SEGMENT_S } else { segment_s };
        if !(segment_s.is_finite() && segment_s >= dt && segment_s <= 10.0) {
            return Err(ServerError::invalid("segment_s", "must be between dt and 10 s"));
        }
        let lookahead_s = if lookahead_s == 0.0 { DEFAULT_LOOKAHEAD_S } else { lookahead_s };
        if !(lookahead_s.is_finite() && (0.0..=10.0).contains(&lookahead_s)) {
            return Err(ServerError::invalid("lookahead_s", "must be between 0 and 10 s"));
        }
        let max_duration = if max_duration_s == 0.0 { 3.0 * tau } else { max_duration_s };
        if !(max_duration.is_finite() && max_duration > 0.0) {
            return Err(ServerError::invalid("max_duration_s", "must be a finite number >= 0"));
        }
        if max_duration / dt > config.limits.max_steps as f64 {
            return Err(ServerError::ResourceExhausted(format!(
                "max_duration_s / dt exceeds the limit of {} steps",
                config.limits.max_steps
            )));
        }
        let realtime = match v1::Pacing::try_from(pacing) {
            Ok(v1::Pacing::Realtime) => true,
            Ok(v1::Pacing::Unspecified | v1::Pacing::AsFastAsRead) => false,
            Err(_) => return Err(ServerError::invalid("pacing", format!("unknown value {pacing}"))),
        };
        let segment_points = (segment_s / dt).round().max(1.0) as usize;
        let step =
            if integration_step_s == 0.0 { config.defaults.integration_step_s } else { integration_step_s };
        if !(step.is_finite() && step > 0.0 && step <= 0.1) {
            return Err(ServerError::invalid(
                "integration_step_s",
                "must be greater than 0 and at most 0.1 s",
            ));
        }
        let tolerance = match integration_tolerance {
            0.0 => None,
            tol if tol.is_finite() && tol > 0.0 && tol <= MAX_TOLERANCE => Some(tol),
            _ => {
                return Err(ServerError::invalid(
                    "integration_tolerance",
                    format!("must be 0 (a fixed step) or above 0 and at most {MAX_TOLERANCE}"),
                ));
            }
        };
        // A whole number of output steps, at least one; at most one segment for a fixed step.
        let step_points = match tolerance {
            None => ((step / dt).round() as usize).clamp(1, segment_points),
            Some(_) => ((step / dt).round() as usize).max(1),
        };
        Ok(StreamConfig {
            stepping: Stepping { dt, step_points, tolerance },
            segment_points,
            realtime,
            lookahead: Duration::from_secs_f64(lookahead_s),
            max_duration,
            urgency,
        })
    }
}
