//! The ranges every value that enters a run must lie in, so that every term of the DMP and of the repulsive field
//! stays finite (IEEE doubles overflow above about `1.8e308`; the bounds below keep every intermediate product under
//! `1e300`). The wire conversions (`dmp_proto`) and the server check each value against them at the edge, and each
//! refusal names the field and the range; the engine's constructors stay lenient so that scenario files and stored
//! primitives written before these ranges still load (the server checks a stored primitive again when it is used).
//!
//! # The argument, in one place
//! Write `q = |y_i| / a_i` for a coordinate `y_i` of the robot in an obstacle's frame (ERRATA.md, "Isopotentials").
//! With semi-axes `a >= 1e-3 m` ([`SEMI_AXIS_M`]) and distances between a robot and an obstacle's centre up to
//! [`REACH_M`] `= 2e5 m`, `q <= 2e8`. With exponents `n <= 8` ([`EXPONENT`]), in up to 64 dimensions:
//! - `C <= 64 q^(2n) < 1e135`;
//! - `|grad C| <= 8 (2n / a) q^(2n - 1) < 1e130`, so `|grad C|^2 < 1e260`;
//! - the Hessian's entries are at most `(2n (2n - 1) / a^2) q^(2n - 2) < 1e125`, so `H u |grad C|` and
//!   `<grad C, u> H grad C / |grad C|` of the dynamic volumetric term stay under `1e255 |u|`;
//! - the nested form is bounded the same way by `q^(2m)` with `m <= 8`.
//!
//! Inside an obstacle the volumetric terms are evaluated at `C >= C_FLOOR = 1e-6` ([`crate::field::C_FLOOR`]), so
//! `C^(-eta) <= 1e60` for `eta <= 10` ([`C_EXPONENT`]) and `1 / C^2 <= 1e12`; the gains are at most `1e9`
//! ([`GAIN`]). Every product of the five terms then stays under `1e300` for relative speeds `|u| < 1e30`.
//!
//! The reach covers every run of accepted values: robots start and aim inside the workspace (the server's
//! `limits.workspace_m`, 1,000 m by default), the forcing term moves them at most the largest weight ([`WEIGHT`],
//! 10 km) beyond the line between them (a critically or over-damped DMP follows its forcing without overshoot; an
//! under-damped one at most doubles it), and a moving obstacle at [`SPEED_MPS`] stays within reach for over an
//! hour. Two things the bounds cannot cover are left to [`crate::Execution`], which drops for that run (and
//! reports) an obstacle whose term is not finite instead of failing: a robot deep inside an obstacle, within about
//! `1e-200 a` of its centre (where `|grad C|` underflows), and a workspace configured far wider than the reach. The
//! point methods only see distances to boundary samples, and are undefined exactly on a sample.

use std::ops::RangeInclusive;

use crate::error::InvalidInput;

/// Largest distance between a robot and an obstacle's centre for which the bounds above are proven, metres.
pub const REACH_M: f64 = 2e5;

/// Semi-axes of a superquadric (an obstacle's, after its margin, or a footprint's), metres. The lower bound keeps
/// `q = |y| / a <= REACH_M / 1e-3`; the upper one keeps the bounding ball (`sum a_i^2`) and the boundary samples
/// well-conditioned.
pub const SEMI_AXIS_M: RangeInclusive<f64> = 1e-3..=1e4;

/// An obstacle's margin (added to every semi-axis), metres: it only enlarges `a`, which shrinks `q`.
pub const MARGIN_M: RangeInclusive<f64> = 0.0..=1e3;

/// Exponents of a superquadric: the per-axis `n_i` and the nested form's `n` and `m`. Below 1 the Hessian is
/// infinite on the axes; above 8 the products of the powers `q^(2n)` leave the range of a double within the reach.
/// The box of a ROS solid has exponent 4; 8 is already sharper than a sensor resolves.
pub const EXPONENT: RangeInclusive<f64> = 1.0..=8.0;

/// The dimensions of a ROS solid primitive (box edges, sphere radius, cylinder height and radius), metres: the
/// superquadric that contains it has semi-axes between `0.56` and `1.12` times these, inside [`SEMI_AXIS_M`].
pub const SOLID_DIMENSION_M: RangeInclusive<f64> = 2e-3..=5e3;

/// How far a rotation may be from orthonormal (the largest entry of `R R^T - I`).
pub const ROTATION_TOLERANCE: f64 = 1e-6;

/// Magnitude of an obstacle's velocity, metres per second: a moving obstacle stays inside the reach for minutes
/// from anywhere in the default workspace, and `tau * o_dot` (with `tau <= 1e4`) stays under `1e6`.
pub const SPEED_MPS: RangeInclusive<f64> = 0.0..=20.0;

/// The canonical decay `alpha`. The basis centres `c_i = exp(-alpha i / N)` are then at least `exp(-100)` apart
/// from zero and, with `N <=` [`N_BASIS`]'s upper bound, at least `alpha / N >= 1e-6` apart relatively: the widths
/// `h_i = 1 / (c_{i+1} - c_i)^2` stay finite and the centres distinct (`alpha = 1e-300` makes them all 1).
pub const ALPHA: RangeInclusive<f64> = 1e-2..=1e2;

/// The number `N` of the basis (`N + 1` functions). The server's `limits.max_basis` may lower it.
pub const N_BASIS: RangeInclusive<usize> = 1..=10_000;

/// The stiffness `K` of each dimension (the `alpha_z beta_z` of other papers); the integration step is checked
/// against it too (`dt sqrt(max K) / tau` at most [`crate::execution::MAX_STIFF_STEP`]).
pub const STIFFNESS: RangeInclusive<f64> = 1e-3..=1e8;

/// The damping `D` of each dimension (critical damping `2 sqrt(K)` is at most `2e4`).
pub const DAMPING: RangeInclusive<f64> = 0.0..=1e5;

/// Forcing weights, metres: the forcing term `f` is `s` times a convex combination of them, so `|f| <= max |w_i|`,
/// and `K f` is a position offset (ERRATA.md, the DMP): a learned primitive's weights are of the order of its
/// motion's span.
pub const WEIGHT: RangeInclusive<f64> = -1e4..=1e4;

/// The avoidance gains: `eta` of the static point potential, `lambda` of the dynamic ones, `gamma` of the steering
/// angle, `A` of the static volumetric potential.
pub const GAIN: RangeInclusive<f64> = 1e-9..=1e9;

/// The influence radius `p0` of the static point potential, metres.
pub const INFLUENCE_M: RangeInclusive<f64> = 1e-4..=1e4;

/// The angular exponent `beta` of the dynamic potentials (`(-cos theta)^(beta - 1) <= 1`; below 1 the gradient is
/// infinite where the term switches on).
pub const ANGULAR_EXPONENT: RangeInclusive<f64> = 1.0..=100.0;

/// The angular decay `beta` of the steering angle (`exp(-beta theta) <= 1`).
pub const STEERING_DECAY: RangeInclusive<f64> = 0.0..=100.0;

/// The decay `eta` of the static volumetric potential: `exp(-eta C) <= 1` and `eta / C <= 1e9` at the floor.
pub const VOLUME_DECAY: RangeInclusive<f64> = 1e-6..=1e3;

/// The exponent `eta` of `C` in the dynamic volumetric potential: `C^(-eta) <= 1e60` at the floor.
pub const C_EXPONENT: RangeInclusive<f64> = 1e-3..=10.0;

/// Boundary samples per obstacle of the point methods.
pub const POINT_SAMPLES: RangeInclusive<usize> = 1..=10_000;

/// Checks that `value` is finite and in `range`; the error names `field`, the range and `unit` (e.g. `" m"`).
pub fn check_range(
    field: &str,
    value: f64,
    range: &RangeInclusive<f64>,
    unit: &str,
) -> Result<(), InvalidInput> {
    if value.is_finite() && range.contains(&value) {
        Ok(())
    } else {
        Err(InvalidInput::new(
            field,
            format!(
                "must be between {} and {}{unit}, found {}",
                fmt(*range.start()),
                fmt(*range.end()),
                fmt(value)
            ),
        ))
    }
}

/// Checks every entry of `values` with [`check_range`], naming `field[i]`.
pub fn check_each(
    field: &str,
    values: &[f64],
    range: &RangeInclusive<f64>,
    unit: &str,
) -> Result<(), InvalidInput> {
    for (i, v) in values.iter().enumerate() {
        check_range(&format!("{field}[{i}]"), *v, range, unit)?;
    }
    Ok(())
}

/// Checks a count against `range`.
pub fn check_count(field: &str, value: usize, range: &RangeInclusive<usize>) -> Result<(), InvalidInput> {
    if range.contains(&value) {
        Ok(())
    } else {
        Err(InvalidInput::new(
            field,
            format!("must be between {} and {}, found {value}", range.start(), range.end()),
        ))
    }
}

/// A bound as people write it: `1000`, `0.001`, `1e-9`.
fn fmt(v: f64) -> String {
    if v == 0.0 || !v.is_finite() || (1e-3..=1e4).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refusals_name_the_field_and_the_range() {
        assert!(check_range("a", 1.0, &SEMI_AXIS_M, " m").is_ok());
        let e = check_range("semi_axes[1]", 1e-300, &SEMI_AXIS_M, " m").unwrap_err();
        assert_eq!(e.to_string(), "semi_axes[1]: must be between 0.001 and 10000 m, found 1e-300");
        let e = check_range("exponents[0]", 1e6, &EXPONENT, "").unwrap_err();
        assert_eq!(e.to_string(), "exponents[0]: must be between 1 and 8, found 1e6");
        assert!(check_range("x", f64::NAN, &GAIN, "").unwrap_err().rule.contains("1e-9 and 1e9"));
        assert_eq!(check_each("w", &[0.0, 1e13], &WEIGHT, "").unwrap_err().field, "w[1]");
        assert!(check_count("n", 0, &N_BASIS).unwrap_err().rule.contains("between 1 and 10000"));
    }
}
