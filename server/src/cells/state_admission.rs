//! Which robot states a cell takes. A state from outside the server (Zenoh `dmp/<cell>/robots/<id>/state`, or a
//! Session's `state`) becomes a moving obstacle for every robot of the cell, so one stamped far in the future would
//! stay forever and one out of the workspace would sit anywhere: such a state is dropped and counted.
//!
//! A state is admitted when its stamp is within `limits.max_state_skew_s` of the server's clock (either way), every
//! coordinate of its position is within the workspace box (`limits.workspace_m`) and every coordinate of its
//! velocity within `limits.max_state_speed_m_s`. The states the server computes itself are not checked here.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use dmp_proto::WireError;
use dmp_proto::check::check_in_workspace;
use dmp_proto::v1;

use crate::config::RequestLimits;

/// The bounds a robot state must keep, and the count of those dropped. Cheap to clone (the count is shared).
#[derive(Debug, Clone)]
pub(crate) struct StateAdmission {
    max_skew_s: f64,
    workspace_m: f64,
    max_speed_m_s: f64,
    dropped: Arc<AtomicU64>,
}

impl StateAdmission {
    /// The bounds of `limits`, nothing dropped yet.
    pub(crate) fn new(limits: &RequestLimits) -> Self {
        Self {
            max_skew_s: limits.max_state_skew_s,
            workspace_m: limits.workspace_m,
            max_speed_m_s: limits.max_state_speed_m_s,
            dropped: Arc::default(),
        }
    }

    /// Checks `state` (already checked for shape: finite numbers, one dimension) at `now_unix_s` on the server's
    /// clock; the error names the field and the bound. Counts nothing.
    pub(crate) fn check(&self, state: &v1::RobotState, now_unix_s: f64) -> Result<(), WireError> {
        let skew = state.stamp_unix_s - now_unix_s;
        if skew.is_nan() || skew.abs() > self.max_skew_s {
            return Err(WireError::new(
                "stamp_unix_s",
                format!(
                    "is {skew:+.3} s from the server's clock; at most {} s either way is accepted",
                    self.max_skew_s
                ),
            ));
        }
        check_in_workspace("position", &state.position, self.workspace_m)?;
        if let Some(i) = state.velocity.iter().position(|v| v.is_nan() || v.abs() > self.max_speed_m_s) {
            return Err(WireError::new(
                format!("velocity[{i}]"),
                format!(
                    "must be between -{max} and {max} m/s, found {}",
                    state.velocity[i],
                    max = self.max_speed_m_s
                ),
            ));
        }
        Ok(())
    }

    /// [`StateAdmission::check`], counting the state as dropped when it fails.
    pub(crate) fn admit(&self, state: &v1::RobotState, now_unix_s: f64) -> Result<(), WireError> {
        self.check(state, now_unix_s).inspect_err(|_| {
            self.dropped.fetch_add(1, Ordering::Relaxed);
        })
    }

    /// How many states were dropped so far.
    pub(crate) fn dropped(&self) -> u64 {
        self.dropped.load(Ordering::Relaxed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state(stamp: f64, x: f64, v: f64) -> v1::RobotState {
        v1::RobotState {
            robot_id: "r".into(),
            stamp_unix_s: stamp,
            position: vec![x, 0.0],
            velocity: vec![0.0, v],
            footprint: None,
            ..Default::default()
        }
    }

    #[test]
    fn states_within_the_bounds_are_admitted() {
        let a = StateAdmission::new(&RequestLimits::default());
        let now = 1.7e9;
        for s in [state(now, 1.0, 1.0), state(now + 0.9, -999.0, -9.0), state(now - 1.0, 0.0, 10.0)] {
            assert!(a.admit(&s, now).is_ok(), "{s:?}");
        }
        let mut still = state(now, 0.0, 0.0);
        still.velocity.clear();
        assert!(a.admit(&still, now).is_ok());
        assert_eq!(a.dropped(), 0);
    }

    #[test]
    fn states_out_of_the_bounds_are_dropped_and_counted() {
        let a = StateAdmission::new(&RequestLimits::default());
        let now = 1.7e9;
        let cases = [
            (state(now + 1e7, 0.0, 0.0), "stamp_unix_s", "+10000000.000 s"),
            (state(now - 1.5, 0.0, 0.0), "stamp_unix_s", "at most 1 s"),
            (state(now, 1000.5, 0.0), "position[0]", "-1000 to 1000 m"),
            (state(now, 0.0, -10.5), "velocity[1]", "-10 and 10 m/s"),
        ];
        for (s, field, words) in &cases {
            let e = a.admit(s, now).unwrap_err();
            assert_eq!(&e.field, field);
            assert!(e.rule.contains(words), "{}", e.rule);
        }
        assert_eq!(a.dropped(), cases.len() as u64);
        // Clones share the count.
        let b = a.clone();
        assert!(b.admit(&state(f64::NAN, 0.0, 0.0), now).is_err());
        assert_eq!(a.dropped(), cases.len() as u64 + 1);
    }
}
