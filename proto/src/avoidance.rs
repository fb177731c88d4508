//! The avoidance of a motion, both ways between its message and the engine's [`Avoidance`].

use dmp::avoidance::{DynamicPoint, DynamicVolumetric, StaticPoint, StaticVolumetric, SteeringAngle};
use dmp::{Avoidance, Method};

use crate::WireError;
use crate::v1;

/// Default number of boundary samples of the point methods (a message's `point_samples = 0`).
pub const DEFAULT_POINT_SAMPLES: usize = 50;

/// Largest number of boundary samples of the point methods ([`dmp::ranges::POINT_SAMPLES`]).
pub const MAX_POINT_SAMPLES: usize = *dmp::ranges::POINT_SAMPLES.end();

/// The engine's avoidance of a message; an unset message or method takes `default`. Returns the boundary sample
/// count of the point methods too.
pub fn avoidance_from_proto(
    a: Option<&v1::Avoidance>,
    default: Avoidance,
) -> Result<(Avoidance, usize), WireError> {
    use v1::avoidance::Method as M;
    let Some(a) = a else { return Ok((default, DEFAULT_POINT_SAMPLES)) };
    let method = match &a.method {
        None => default.method,
        Some(M::None(_)) => Method::None,
        Some(M::StaticPoint(p)) => Method::StaticPoint(StaticPoint { eta: p.eta, p0: p.p0 }),
        Some(M::DynamicPoint(p)) => Method::DynamicPoint(DynamicPoint { lambda: p.lambda, beta: p.beta }),
        Some(M::SteeringAngle(p)) => Method::SteeringAngle(SteeringAngle { gamma: p.gamma, beta: p.beta }),
        Some(M::StaticVolumetric(p)) => Method::StaticVolumetric(StaticVolumetric { a: p.a, eta: p.eta }),
        Some(M::DynamicVolumetric(p)) => {
            Method::DynamicVolumetric(DynamicVolumetric { lambda: p.lambda, beta: p.beta, eta: p.eta })
        }
    };
    let samples = if a.point_samples == 0 { DEFAULT_POINT_SAMPLES } else { a.point_samples as usize };
    if samples > MAX_POINT_SAMPLES {
        return Err(WireError::new(
            "point_samples",
            format!("must be between 1 and {MAX_POINT_SAMPLES} (0: the default, {DEFAULT_POINT_SAMPLES})"),
        ));
    }
    let relative_velocity =
        if a.method.is_none() { default.relative_velocity } else { !a.ignore_obstacle_velocity };
    Ok((Avoidance { method, relative_velocity }, samples))
}

/// The message of the engine's avoidance; `point_samples` is the boundary sample count of the point methods
/// (0: the server's default, [`DEFAULT_POINT_SAMPLES`]).
pub fn avoidance_to_proto(a: &Avoidance, point_samples: usize) -> v1::Avoidance {
    use v1::avoidance as pa;
    let method = match a.method {
        Method::None => pa::Method::None(pa::None {}),
        Method::StaticPoint(p) => pa::Method::StaticPoint(pa::StaticPoint { eta: p.eta, p0: p.p0 }),
        Method::DynamicPoint(p) => {
            pa::Method::DynamicPoint(pa::DynamicPoint { lambda: p.lambda, beta: p.beta })
        }
        Method::SteeringAngle(p) => {
            pa::Method::SteeringAngle(pa::SteeringAngle { gamma: p.gamma, beta: p.beta })
        }
        Method::StaticVolumetric(p) => {
            pa::Method::StaticVolumetric(pa::StaticVolumetric { a: p.a, eta: p.eta })
        }
        Method::DynamicVolumetric(p) => pa::Method::DynamicVolumetric(pa::DynamicVolumetric {
            lambda: p.lambda,
            beta: p.beta,
            eta: p.eta,
        }),
    };
    v1::Avoidance {
        method: Some(method),
        ignore_obstacle_velocity: !a.relative_velocity,
        point_samples: point_samples as u32,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn avoidance_maps_every_method() {
        let a: Avoidance = serde_json::from_value(
            json!({"method": "dynamic_volumetric", "lambda": 10, "beta": 2, "eta": 0.5}),
        )
        .unwrap();
        let m = avoidance_to_proto(&a, 50);
        assert_eq!(
            m.method,
            Some(v1::avoidance::Method::DynamicVolumetric(v1::avoidance::DynamicVolumetric {
                lambda: 10.0,
                beta: 2.0,
                eta: 0.5
            }))
        );
        assert!(!m.ignore_obstacle_velocity);
        let none = avoidance_to_proto(&Avoidance::NONE, 50);
        assert_eq!(none.method, Some(v1::avoidance::Method::None(v1::avoidance::None {})));
    }

    #[test]
    fn every_method_round_trips_through_the_message() {
        let methods = [
            Method::None,
            Method::StaticPoint(StaticPoint { eta: 1.0, p0: 0.5 }),
            Method::DynamicPoint(DynamicPoint { lambda: 2.0, beta: 3.0 }),
            Method::SteeringAngle(SteeringAngle { gamma: 4.0, beta: 5.0 }),
            Method::StaticVolumetric(StaticVolumetric { a: 6.0, eta: 0.7 }),
            Method::DynamicVolumetric(DynamicVolumetric { lambda: 8.0, beta: 9.0, eta: 0.1 }),
        ];
        for method in methods {
            for relative_velocity in [true, false] {
                let a = Avoidance { method, relative_velocity };
                let back = avoidance_from_proto(Some(&avoidance_to_proto(&a, 7)), Avoidance::NONE).unwrap();
                assert_eq!(back, (a, 7));
            }
        }
    }

    #[test]
    fn unset_fields_take_the_defaults() {
        let default = Avoidance {
            method: Method::StaticVolumetric(StaticVolumetric { a: 1.0, eta: 1.0 }),
            relative_velocity: false,
        };
        assert_eq!(avoidance_from_proto(None, default).unwrap(), (default, DEFAULT_POINT_SAMPLES));
        let unset = v1::Avoidance { method: None, ignore_obstacle_velocity: false, point_samples: 0 };
        assert_eq!(avoidance_from_proto(Some(&unset), default).unwrap(), (default, DEFAULT_POINT_SAMPLES));
        let many = v1::Avoidance { point_samples: 10_001, ..unset };
        assert_eq!(avoidance_from_proto(Some(&many), default).unwrap_err().field, "point_samples");
    }
}
