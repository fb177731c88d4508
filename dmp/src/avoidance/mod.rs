//! The five repulsive terms `phi(x, v)` of the paper, exactly as in ERRATA.md, and their parameters.
//!
//! Conventions: `r = x - o`; `v` is the DMP's velocity state (`tau dx/dt`); `u = v - tau * o_dot` is the velocity
//! relative to the obstacle (or `v` when relative velocity is off). Every term is in the units of `tau dv/dt`.

pub(crate) mod dynamic_point;
pub(crate) mod dynamic_volumetric;
pub(crate) mod static_point;
pub(crate) mod static_volumetric;
pub(crate) mod steering_angle;

use serde::{Deserialize, Serialize};

use crate::error::InvalidInput;

/// Parameters of the static point potential.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StaticPoint {
    /// Gain `eta`.
    pub eta: f64,
    /// Influence radius `p0`.
    pub p0: f64,
}

/// Parameters of the dynamic point potential.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DynamicPoint {
    /// Gain `lambda`.
    pub lambda: f64,
    /// Angular exponent `beta >= 1`.
    pub beta: f64,
}

/// Parameters of the steering angle.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SteeringAngle {
    /// Gain `gamma`.
    pub gamma: f64,
    /// Angular decay `beta`.
    pub beta: f64,
}

/// Parameters of the static volumetric potential.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StaticVolumetric {
    /// Gain `A`.
    #[serde(rename = "A")]
    pub a: f64,
    /// Decay `eta`.
    pub eta: f64,
}

/// Parameters of the dynamic volumetric potential.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DynamicVolumetric {
    /// Gain `lambda`.
    pub lambda: f64,
    /// Angular exponent `beta >= 1`.
    pub beta: f64,
    /// Exponent `eta` of `C`.
    pub eta: f64,
}

/// The avoidance method and its parameters (the scenario's `avoidance.method` and its fields).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "method", rename_all = "snake_case")]
pub enum Method {
    /// No repulsive term.
    None,
    /// `eq:static_potential_khatib` on boundary samples.
    StaticPoint(StaticPoint),
    /// `eq:dynamic_potential_park` on boundary samples.
    DynamicPoint(DynamicPoint),
    /// `eq:perturb_steering_angle` on boundary samples (2-D and 3-D only).
    SteeringAngle(SteeringAngle),
    /// `eq:static_potential_volume`.
    StaticVolumetric(StaticVolumetric),
    /// `eq:dynamic_potential_volume`.
    DynamicVolumetric(DynamicVolumetric),
}

impl Method {
    /// The method's name as the scenario format spells it.
    pub fn name(&self) -> &'static str {
        match self {
            Method::None => "none",
            Method::StaticPoint(_) => "static_point",
            Method::DynamicPoint(_) => "dynamic_point",
            Method::SteeringAngle(_) => "steering_angle",
            Method::StaticVolumetric(_) => "static_volumetric",
            Method::DynamicVolumetric(_) => "dynamic_volumetric",
        }
    }

    /// True for the three methods that act on boundary samples.
    pub(crate) fn is_point_method(&self) -> bool {
        matches!(self, Method::StaticPoint(_) | Method::DynamicPoint(_) | Method::SteeringAngle(_))
    }

    /// Checks the parameters; `prefix` names the enclosing field (e.g. `avoidance`) and `dim` is the dimension the
    /// method acts in.
    pub fn validate(&self, prefix: &str, dim: usize) -> Result<(), InvalidInput> {
        use crate::ranges::{
            ANGULAR_EXPONENT, C_EXPONENT, GAIN, INFLUENCE_M, STEERING_DECAY, VOLUME_DECAY, check_range,
        };
        let f = |name: &str| format!("{prefix}.{name}");
        match *self {
            Method::None => Ok(()),
            Method::StaticPoint(StaticPoint { eta, p0 }) => {
                check_range(&f("eta"), eta, &GAIN, "")?;
                check_range(&f("p0"), p0, &INFLUENCE_M, " m")
            }
            Method::DynamicPoint(DynamicPoint { lambda, beta }) => {
                check_range(&f("lambda"), lambda, &GAIN, "")?;
                check_range(&f("beta"), beta, &ANGULAR_EXPONENT, "")
            }
            Method::SteeringAngle(SteeringAngle { gamma, beta }) => {
                check_range(&f("gamma"), gamma, &GAIN, "")?;
                check_range(&f("beta"), beta, &STEERING_DECAY, "")?;
                if dim != 2 && dim != 3 {
                    return Err(InvalidInput::new(
                        f("method"),
                        format!(
                            "steering_angle is defined in 2-D and 3-D only, the space here has {dim} dimensions"
                        ),
                    ));
                }
                Ok(())
            }
            Method::StaticVolumetric(StaticVolumetric { a, eta }) => {
                check_range(&f("A"), a, &GAIN, "")?;
                check_range(&f("eta"), eta, &VOLUME_DECAY, "")
            }
            Method::DynamicVolumetric(DynamicVolumetric { lambda, beta, eta }) => {
                check_range(&f("lambda"), lambda, &GAIN, "")?;
                check_range(&f("beta"), beta, &ANGULAR_EXPONENT, "")?;
                check_range(&f("eta"), eta, &C_EXPONENT, "")
            }
        }
    }
}

/// A method together with how it treats moving obstacles.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Avoidance {
    /// The method and its parameters.
    #[serde(flatten)]
    pub method: Method,
    /// Use `v - tau * o_dot` in the dynamic terms (default true); false ignores the obstacles' motion there.
    #[serde(default = "default_true")]
    pub relative_velocity: bool,
}

fn default_true() -> bool {
    true
}

impl Avoidance {
    /// No avoidance.
    pub const NONE: Avoidance = Avoidance { method: Method::None, relative_velocity: true };

    /// The method with relative velocity on.
    pub fn new(method: Method) -> Self {
        Self { method, relative_velocity: true }
    }
}

pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

pub(crate) fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

/// `x^p` for `x >= 0`, exact and fast for the exponents the paper uses (integers and halves).
pub(crate) fn pow(x: f64, p: f64) -> f64 {
    Exponent::new(p).pow(x)
}

/// An exponent classified once, so that raising to it in a hot loop costs no classification: integers are the
/// small powers written out or `powi`, halves that times one square root, the rest `powf`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Exponent {
    Int(i32),
    Half(i32),
    Real(f64),
}

impl Exponent {
    pub(crate) fn new(p: f64) -> Self {
        if p.fract() == 0.0 && p.abs() < 64.0 {
            Exponent::Int(p as i32)
        } else if (2.0 * p).fract() == 0.0 && p.abs() < 64.0 {
            Exponent::Half((p - 0.5) as i32)
        } else {
            Exponent::Real(p)
        }
    }

    #[inline]
    pub(crate) fn pow(self, x: f64) -> f64 {
        match self {
            Exponent::Int(k) => int_pow(x, k),
            Exponent::Half(k) => int_pow(x, k) * x.sqrt(),
            Exponent::Real(p) => x.powf(p),
        }
    }
}

/// `x^k` for any integer `k`, inlined (a runtime `powi` is a call into the compiler's runtime on every evaluation).
#[inline]
fn int_pow(x: f64, k: i32) -> f64 {
    let p = crate::isopotential::ipow(x, k.unsigned_abs());
    if k < 0 { 1.0 / p } else { p }
}

#[cfg(test)]
mod tests;
