//! A robot's limits and the goal filter, wire to engine.

use dmp::Limits;
use dmp::integrate::goal_filter::DEFAULT_GOAL_ALPHA;

use crate::WireError;
use crate::v1;

/// A request's or a robot record's limits that turn every limit off, explicitly (every field negative): what a run
/// that must follow the DMP exactly (the paper's experiments, a comparison with the engine) asks for, since an
/// unset field takes the server's default profile.
pub const NO_LIMITS: v1::Limits = v1::Limits {
    max_speed: -1.0,
    max_acceleration: -1.0,
    max_jerk: -1.0,
    max_angular_speed: -1.0,
    max_angular_acceleration: -1.0,
    max_angular_jerk: -1.0,
};

/// The engine's limits of `l` (unset: none), each field checked (finite, 0 or more), an error naming it.
pub fn limits_from_proto(l: Option<&v1::Limits>) -> Result<Limits, WireError> {
    let Some(l) = l else { return Ok(Limits::NONE) };
    let limits = Limits {
        max_speed: l.max_speed,
        max_acceleration: l.max_acceleration,
        max_jerk: l.max_jerk,
        max_angular_speed: l.max_angular_speed,
        max_angular_acceleration: l.max_angular_acceleration,
        max_angular_jerk: l.max_angular_jerk,
    };
    limits.validate()?;
    Ok(limits)
}

/// The wire's limits of `l`.
pub fn limits_to_proto(l: &Limits) -> v1::Limits {
    v1::Limits {
        max_speed: l.max_speed,
        max_acceleration: l.max_acceleration,
        max_jerk: l.max_jerk,
        max_angular_speed: l.max_angular_speed,
        max_angular_acceleration: l.max_angular_acceleration,
        max_angular_jerk: l.max_angular_jerk,
    }
}

/// The tightest of two limits, field by field (0 being no limit).
pub fn tightest(a: &Limits, b: &Limits) -> Limits {
    let t = |x: f64, y: f64| match (x > 0.0, y > 0.0) {
        (true, true) => x.min(y),
        (true, false) => x,
        _ => y,
    };
    Limits {
        max_speed: t(a.max_speed, b.max_speed),
        max_acceleration: t(a.max_acceleration, b.max_acceleration),
        max_jerk: t(a.max_jerk, b.max_jerk),
        max_angular_speed: t(a.max_angular_speed, b.max_angular_speed),
        max_angular_acceleration: t(a.max_angular_acceleration, b.max_angular_acceleration),
        max_angular_jerk: t(a.max_angular_jerk, b.max_angular_jerk),
    }
}

/// The limits of a robot's record (`base`) overridden field by field by a request's (`over`): a field of `over`
/// above 0 replaces the record's, a field left 0 keeps it.
pub fn overridden(base: &Limits, over: &Limits) -> Limits {
    let o = |b: f64, r: f64| if r > 0.0 { r } else { b };
    Limits {
        max_speed: o(base.max_speed, over.max_speed),
        max_acceleration: o(base.max_acceleration, over.max_acceleration),
        max_jerk: o(base.max_jerk, over.max_jerk),
        max_angular_speed: o(base.max_angular_speed, over.max_angular_speed),
        max_angular_acceleration: o(base.max_angular_acceleration, over.max_angular_acceleration),
        max_angular_jerk: o(base.max_angular_jerk, over.max_angular_jerk),
    }
}

/// The engine's `alpha_g` of `MotionSpec.goal_filter_alpha`: 0 is the default, a negative value is off (0 in the
/// engine); not finite is refused (field `goal_filter_alpha`).
pub fn goal_filter_alpha(v: f64) -> Result<f64, WireError> {
    if !v.is_finite() {
        return Err(WireError::new(
            "goal_filter_alpha",
            "must be a finite number (0: the default, negative: off)",
        ));
    }
    Ok(if v == 0.0 { DEFAULT_GOAL_ALPHA } else { v.max(0.0) })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_and_alpha_convert_and_bad_ones_name_their_field() {
        assert_eq!(limits_from_proto(None).unwrap(), Limits::NONE);
        let panda = limits_to_proto(&Limits::PANDA);
        assert_eq!(limits_from_proto(Some(&panda)).unwrap(), Limits::PANDA);
        let bad = v1::Limits { max_jerk: -3.0, ..panda };
        assert_eq!(limits_from_proto(Some(&bad)).unwrap_err().field, "max_jerk");
        assert_eq!(goal_filter_alpha(0.0).unwrap(), DEFAULT_GOAL_ALPHA);
        assert_eq!(goal_filter_alpha(-1.0).unwrap(), 0.0);
        assert_eq!(goal_filter_alpha(25.0).unwrap(), 25.0);
        assert_eq!(goal_filter_alpha(f64::NAN).unwrap_err().field, "goal_filter_alpha");
        let some = Limits { max_speed: 1.0, ..Limits::NONE };
        let t = tightest(&some, &Limits::PANDA);
        assert_eq!((t.max_speed, t.max_jerk), (1.0, Limits::PANDA.max_jerk));
        let o = overridden(&Limits::PANDA, &some);
        assert_eq!((o.max_speed, o.max_jerk), (1.0, Limits::PANDA.max_jerk));
        assert_eq!(overridden(&Limits::PANDA, &Limits::NONE), Limits::PANDA);
        assert_eq!(overridden(&Limits::NONE, &Limits::PANDA), Limits::PANDA);
    }
}
