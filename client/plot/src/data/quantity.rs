//! The quantities of the time strip: what each of its panels plots against time (speed, acceleration and jerk,
//! linear and for a pose run angular, the clearance, the orientation), how they are arranged, and their curves.

use super::decimate::decimated;
use super::differences::{angular, linear};
use super::geometry::P2;
use super::input::PlotInput;
use super::run::Run;
use super::safety::Bounded;

/// A panel of the time strip.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Quantity {
    Speed,
    Acceleration,
    Jerk,
    AngularSpeed,
    AngularAcceleration,
    AngularJerk,
    Clearance,
    Orientation,
}

impl Quantity {
    /// The class (and id, after `strip-`) of its panel's group.
    pub(crate) fn class(self) -> &'static str {
        match self {
            Quantity::Speed => "speed",
            Quantity::Acceleration => "acceleration",
            Quantity::Jerk => "jerk",
            Quantity::AngularSpeed => "angular-speed",
            Quantity::AngularAcceleration => "angular-acceleration",
            Quantity::AngularJerk => "angular-jerk",
            Quantity::Clearance => "clearance",
            Quantity::Orientation => "orientation",
        }
    }

    /// Its axis name, with the unit: short enough to stand beside a panel of the strip.
    pub(crate) fn desc(self) -> &'static str {
        match self {
            Quantity::Speed => "speed (m/s)",
            Quantity::Acceleration => "acceleration (m/s²)",
            Quantity::Jerk => "jerk (m/s³)",
            Quantity::AngularSpeed => "ang. speed (rad/s)",
            Quantity::AngularAcceleration => "ang. accel. (rad/s²)",
            Quantity::AngularJerk => "ang. jerk (rad/s³)",
            Quantity::Clearance => "clearance (m)",
            Quantity::Orientation => "turn from start (°)",
        }
    }

    /// Its unit, for a limit's label.
    pub(crate) fn unit(self) -> &'static str {
        let desc = self.desc();
        desc.rsplit_once('(').map_or("", |(_, u)| u.trim_end_matches(')'))
    }

    /// The limit that bounds it, if any may.
    pub(crate) fn bounded(self) -> Option<Bounded> {
        match self {
            Quantity::Speed => Some(Bounded::Speed),
            Quantity::Acceleration => Some(Bounded::Acceleration),
            Quantity::Jerk => Some(Bounded::Jerk),
            Quantity::AngularSpeed => Some(Bounded::AngularSpeed),
            Quantity::AngularAcceleration => Some(Bounded::AngularAcceleration),
            Quantity::AngularJerk => Some(Bounded::AngularJerk),
            Quantity::Clearance | Quantity::Orientation => None,
        }
    }

    /// The panels of `input`'s strip, row by row: one column of the linear quantities and the clearance; for a
    /// pose run, the angular ones (and the orientation) in a second column beside them.
    pub(crate) fn grid(input: &PlotInput<'_>) -> Vec<Vec<Quantity>> {
        use Quantity::*;
        if input.pose.is_some() {
            vec![
                vec![Speed, AngularSpeed],
                vec![Acceleration, AngularAcceleration],
                vec![Jerk, AngularJerk],
                vec![Clearance, Orientation],
            ]
        } else {
            vec![vec![Speed], vec![Acceleration], vec![Jerk], vec![Clearance]]
        }
    }

    /// Its curves per robot, `(adapted, free)`: the speed and acceleration the run reports, the jerk and the angular
    /// quantities as finite differences at the output rate; the clearance has no free curve.
    pub(crate) fn curves(self, input: &PlotInput<'_>, run: &Run<'_>) -> Vec<(Vec<P2>, Vec<P2>)> {
        let angular_of = |order: usize| -> Vec<(Vec<P2>, Vec<P2>)> {
            input
                .pose
                .iter()
                .map(|p| {
                    (
                        angular(&input.adapted.t, p.orientations, order),
                        angular(&input.free.t, p.free_orientations, order),
                    )
                })
                .collect()
        };
        match self {
            Quantity::Orientation => {
                input.pose.iter().map(|p| p.turn_curves(&input.adapted.t, &input.free.t)).collect()
            }
            Quantity::AngularSpeed => angular_of(1),
            Quantity::AngularAcceleration => angular_of(2),
            Quantity::AngularJerk => angular_of(3),
            Quantity::Speed => run
                .groups
                .iter()
                .map(|g| {
                    (
                        run.adapted.norm_against_time(&run.adapted.v, &g.dims),
                        run.free.norm_against_time(&run.free.v, &g.dims),
                    )
                })
                .collect(),
            Quantity::Acceleration => run
                .groups
                .iter()
                .map(|g| {
                    (
                        run.adapted.norm_against_time(&run.adapted.a, &g.dims),
                        run.free.norm_against_time(&run.free.a, &g.dims),
                    )
                })
                .collect(),
            Quantity::Jerk => run
                .groups
                .iter()
                .map(|g| (linear(input.adapted, &g.dims, 3), linear(input.free, &g.dims, 3)))
                .collect(),
            Quantity::Clearance => run
                .clearance
                .iter()
                .map(|s| {
                    let idx = decimated(s.t.len());
                    (idx.iter().map(|&k| (s.t[k], s.v[k])).collect(), Vec::new())
                })
                .collect(),
        }
    }
}
