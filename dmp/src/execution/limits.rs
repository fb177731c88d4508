//! A robot's limits: the largest speed, acceleration and jerk of its position, and of its orientation in a pose
//! run, with the profiles of the cell's robots and their sources.

use serde::{Deserialize, Serialize};

use crate::error::InvalidInput;

/// The limits a run's setpoints keep, in SI units (metres, radians, seconds); 0 means no limit.
///
/// The linear limits apply to the Euclidean norm of each robot's position part; the angular ones to the
/// orientation of a pose run (its last three dimensions, the rotation vector `y`: see
/// [`Execution::set_limits`](super::Execution::set_limits)). They are measured as the setpoints' backward finite
/// differences at the output rate.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Limits {
    /// m/s.
    pub max_speed: f64,
    /// m/s².
    pub max_acceleration: f64,
    /// m/s³.
    pub max_jerk: f64,
    /// rad/s.
    pub max_angular_speed: f64,
    /// rad/s².
    pub max_angular_acceleration: f64,
    /// rad/s³.
    pub max_angular_jerk: f64,
}

/// One set of bounds (speed, acceleration, jerk), `f64::INFINITY` where there is none.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Bounds {
    pub(super) v: f64,
    pub(super) a: f64,
    pub(super) j: f64,
}

impl Bounds {
    fn of(v: f64, a: f64, j: f64) -> Self {
        let inf = |x: f64| if x > 0.0 { x } else { f64::INFINITY };
        Self { v: inf(v), a: inf(a), j: inf(j) }
    }

    pub(super) fn is_none(&self) -> bool {
        self.v.is_infinite() && self.a.is_infinite() && self.j.is_infinite()
    }
}

impl Limits {
    /// No limit at all.
    pub const NONE: Self = Self {
        max_speed: 0.0,
        max_acceleration: 0.0,
        max_jerk: 0.0,
        max_angular_speed: 0.0,
        max_angular_acceleration: 0.0,
        max_angular_jerk: 0.0,
    };

    /// Franka Emika Panda, Cartesian limits of the end effector, from Franka's documentation (FCI, "Robot and
    /// interface specifications", limits in Cartesian space): translation 1.7 m/s, 13 m/s², 6500 m/s³; rotation
    /// 2.5 rad/s, 25 rad/s², 12500 rad/s³.
    pub const PANDA: Self = Self {
        max_speed: 1.7,
        max_acceleration: 13.0,
        max_jerk: 6500.0,
        max_angular_speed: 2.5,
        max_angular_acceleration: 25.0,
        max_angular_jerk: 12500.0,
    };

    /// The da Vinci Research Kit's PSM (patient side manipulator). Neither Intuitive Surgical nor the dVRK publish
    /// Cartesian limits of the instrument tip; these are the project's conservative working figures for
    /// manipulation in a workspace of about 0.4 m (0.2 m/s, reached in 0.1 s with the acceleration, which is
    /// reached in 20 ms with the jerk), to be replaced by measured ones.
    pub const DVRK_PSM: Self = Self {
        max_speed: 0.2,
        max_acceleration: 2.0,
        max_jerk: 100.0,
        max_angular_speed: 3.0,
        max_angular_acceleration: 30.0,
        max_angular_jerk: 1500.0,
    };

    /// The KUKA youBot's omnidirectional base: top speed about 0.8 m/s (KUKA's youBot data sheet, "base: speed
    /// 0.8 m/s"). KUKA gives no acceleration, jerk or yaw rate; 1 m/s², 10 m/s³ and a yaw of 1.5 rad/s, 3 rad/s²,
    /// 30 rad/s³ are the project's working figures (a mecanum base on a smooth floor: at 0.8 m/s on its wheels'
    /// 0.47 m diagonal, turning on the spot at 1.5 rad/s drives a wheel at about 0.35 m/s), to be replaced by
    /// measured ones.
    pub const YOUBOT_BASE: Self = Self {
        max_speed: 0.8,
        max_acceleration: 1.0,
        max_jerk: 10.0,
        max_angular_speed: 1.5,
        max_angular_acceleration: 3.0,
        max_angular_jerk: 30.0,
    };

    /// The profile of a robot kind by name (`panda`, `dvrk_psm`, `youbot_base`).
    pub fn profile(name: &str) -> Option<Self> {
        match name {
            "panda" => Some(Self::PANDA),
            "dvrk_psm" | "psm" => Some(Self::DVRK_PSM),
            "youbot_base" | "youbot" => Some(Self::YOUBOT_BASE),
            _ => None,
        }
    }

    /// Each field finite and zero or greater; the error names the field.
    pub fn validate(&self) -> Result<(), InvalidInput> {
        for (field, v) in [
            ("max_speed", self.max_speed),
            ("max_acceleration", self.max_acceleration),
            ("max_jerk", self.max_jerk),
            ("max_angular_speed", self.max_angular_speed),
            ("max_angular_acceleration", self.max_angular_acceleration),
            ("max_angular_jerk", self.max_angular_jerk),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(InvalidInput::new(
                    field,
                    format!("must be a finite number, zero (no limit) or greater, not {v}"),
                ));
            }
        }
        Ok(())
    }

    /// True when nothing is limited.
    pub fn is_none(&self) -> bool {
        self.linear().is_none() && self.angular().is_none()
    }

    pub(super) fn linear(&self) -> Bounds {
        Bounds::of(self.max_speed, self.max_acceleration, self.max_jerk)
    }

    pub(super) fn angular(&self) -> Bounds {
        Bounds::of(self.max_angular_speed, self.max_angular_acceleration, self.max_angular_jerk)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validation_names_the_field_and_zero_is_no_limit() {
        assert!(Limits::PANDA.validate().is_ok() && Limits::NONE.is_none() && !Limits::PANDA.is_none());
        let bad = Limits { max_angular_jerk: -1.0, ..Limits::PANDA };
        assert_eq!(bad.validate().unwrap_err().field, "max_angular_jerk");
        let nan = Limits { max_speed: f64::NAN, ..Limits::NONE };
        assert_eq!(nan.validate().unwrap_err().field, "max_speed");
        assert_eq!(Limits::profile("panda"), Some(Limits::PANDA));
        assert!(Limits { max_jerk: 5.0, ..Limits::NONE }.linear().v.is_infinite());
    }
}
