//! What a run was to keep, as the server reports it (`LimitsInForce`): the speed, acceleration and jerk limits,
//! linear and angular, the profile they came from, and the safety distances kept from the obstacles.

/// A quantity of the time strip that a limit may bound.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Bounded {
    Speed,
    Acceleration,
    Jerk,
    AngularSpeed,
    AngularAcceleration,
    AngularJerk,
}

/// The limits a run kept and where they came from, and the safety distance kept from the obstacles: drawn as limit
/// lines on the time strip's panels and as dashed outlines around the obstacles' true shapes. The default is none
/// of them (a run of older data, or without a profile): nothing is drawn.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Safety {
    /// Largest speed, m/s (the Euclidean norm of a robot's position part); 0 or not finite: no limit.
    pub max_speed: f64,
    /// Largest acceleration, m/s²; 0 or not finite: no limit.
    pub max_acceleration: f64,
    /// Largest jerk, m/s³; 0 or not finite: no limit.
    pub max_jerk: f64,
    /// Largest angular speed of a pose run, rad/s; 0 or not finite: no limit.
    pub max_angular_speed: f64,
    /// Largest angular acceleration of a pose run, rad/s²; 0 or not finite: no limit.
    pub max_angular_acceleration: f64,
    /// Largest angular jerk of a pose run, rad/s³; 0 or not finite: no limit.
    pub max_angular_jerk: f64,
    /// Where the limits came from, for a person ("server default", "robot record", ...); named in the legend.
    pub profile: String,
    /// The safety distance kept from every obstacle's true shape, metres; 0: none.
    pub margin: f64,
    /// Obstacles' own safety distances, by id: each obstacle keeps the larger of its own and [`Self::margin`].
    pub obstacle_margins: Vec<(String, f64)>,
}

impl Safety {
    /// The limit on `q`, if there is one.
    pub(crate) fn limit(&self, q: Bounded) -> Option<f64> {
        let v = match q {
            Bounded::Speed => self.max_speed,
            Bounded::Acceleration => self.max_acceleration,
            Bounded::Jerk => self.max_jerk,
            Bounded::AngularSpeed => self.max_angular_speed,
            Bounded::AngularAcceleration => self.max_angular_acceleration,
            Bounded::AngularJerk => self.max_angular_jerk,
        };
        (v.is_finite() && v > 0.0).then_some(v)
    }

    /// Whether any limit applies.
    pub(crate) fn any_limit(&self) -> bool {
        [
            Bounded::Speed,
            Bounded::Acceleration,
            Bounded::Jerk,
            Bounded::AngularSpeed,
            Bounded::AngularAcceleration,
            Bounded::AngularJerk,
        ]
        .into_iter()
        .any(|q| self.limit(q).is_some())
    }

    /// The safety distance kept from the obstacle `id`: the larger of [`Self::margin`] and its own; 0 if none.
    pub(crate) fn margin_of(&self, id: &str) -> f64 {
        let own = self.obstacle_margins.iter().filter(|(o, _)| o == id).map(|(_, m)| *m).fold(0.0, f64::max);
        let m = self.margin.max(own);
        if m.is_finite() && m > 0.0 { m } else { 0.0 }
    }
}
