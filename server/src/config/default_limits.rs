//! `[defaults.limits]` and `[defaults] margin_m`: the server's default profile, what a motion keeps where neither
//! its request nor its robot's record sets a limit or a safety distance (`grpc::limits_in_force` resolves them).

use serde::{Deserialize, Serialize};

use crate::error::ServerError;

/// The limits a run keeps on the fields that neither its request nor its robot's record sets, in SI units. A
/// field set negative means no default for it (the field has no limit unless the request or the record sets one);
/// 0 is refused, being "not set" on the wire.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DefaultLimits {
    /// Speed, m/s.
    pub max_speed: f64,
    /// Acceleration, m/s².
    pub max_acceleration: f64,
    /// Jerk, m/s³.
    pub max_jerk: f64,
    /// Angular speed, rad/s.
    pub max_angular_speed: f64,
    /// Angular acceleration, rad/s².
    pub max_angular_acceleration: f64,
    /// Angular jerk, rad/s³.
    pub max_angular_jerk: f64,
}

impl Default for DefaultLimits {
    /// Conservative: below every robot profile of the engine but the dVRK's (`dmp::Limits`), so that a robot
    /// nobody described moves gently.
    fn default() -> Self {
        Self {
            max_speed: 1.0,
            max_acceleration: 5.0,
            max_jerk: 50.0,
            max_angular_speed: 2.0,
            max_angular_acceleration: 10.0,
            max_angular_jerk: 100.0,
        }
    }
}

impl DefaultLimits {
    /// Each field by its name in `v1::Limits`, in the message's order.
    pub(crate) fn fields(&self) -> [(&'static str, f64); 6] {
        [
            ("max_speed", self.max_speed),
            ("max_acceleration", self.max_acceleration),
            ("max_jerk", self.max_jerk),
            ("max_angular_speed", self.max_angular_speed),
            ("max_angular_acceleration", self.max_angular_acceleration),
            ("max_angular_jerk", self.max_angular_jerk),
        ]
    }

    /// Every field finite and not 0; the error names the key (`defaults.limits.max_speed`).
    pub(crate) fn check(&self) -> Result<(), ServerError> {
        for (field, v) in self.fields() {
            if !(v.is_finite() && v != 0.0) {
                return Err(ServerError::invalid(
                    format!("defaults.limits.{field}"),
                    format!(
                        "must be a finite number, above 0 (the default) or negative (no default), not {v}"
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// The default safety distance, `[defaults] margin_m`: finite and not 0 (negative: none); the error names the key.
pub(crate) fn check_margin(margin_m: f64) -> Result<(), ServerError> {
    let max = *dmp::ranges::MARGIN_M.end();
    if !(margin_m.is_finite() && margin_m != 0.0 && margin_m <= max) {
        return Err(ServerError::invalid(
            "defaults.margin_m",
            format!(
                "must be a finite number of metres, above 0 and at most {max} (negative: none), not {margin_m}"
            ),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_defaults_pass_and_a_zero_or_non_finite_field_is_refused_by_its_key() {
        DefaultLimits::default().check().unwrap();
        DefaultLimits { max_jerk: -1.0, ..DefaultLimits::default() }.check().unwrap();
        for (bad, key) in [
            (DefaultLimits { max_speed: 0.0, ..DefaultLimits::default() }, "defaults.limits.max_speed"),
            (
                DefaultLimits { max_angular_jerk: f64::NAN, ..DefaultLimits::default() },
                "defaults.limits.max_angular_jerk",
            ),
            (
                DefaultLimits { max_acceleration: f64::INFINITY, ..DefaultLimits::default() },
                "defaults.limits.max_acceleration",
            ),
        ] {
            let e = bad.check().unwrap_err().to_string();
            assert!(e.starts_with(key), "{e}");
        }
        check_margin(0.01).unwrap();
        check_margin(-1.0).unwrap();
        for bad in [0.0, f64::NAN, 1e4] {
            assert!(check_margin(bad).unwrap_err().to_string().starts_with("defaults.margin_m"));
        }
    }
}
