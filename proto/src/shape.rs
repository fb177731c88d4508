//! Shapes on the wire: superquadric messages, and ROS solid primitives as the smallest superquadrics that contain
//! them. A robot's footprint is a superquadric message too.

use dmp::ranges::{self, check_each};
use dmp::scenario::FootprintSpec;
use dmp::{Shape, Superquadric};

use crate::WireError;
use crate::check::check_finite;
use crate::v1;

/// Exponent of the superquadric that stands for a box (a rounded box; see [`solid_to_shape`]).
pub const BOX_EXPONENT: f64 = 4.0;

/// The engine's shape of a per-axis superquadric message (no exponents: 1 on every axis, an ellipsoid).
/// Semi-axes and exponents are checked against [`dmp::ranges::SEMI_AXIS_M`] and [`dmp::ranges::EXPONENT`].
pub fn superquadric_to_shape(s: &v1::Superquadric) -> Result<Shape, WireError> {
    let n = if s.exponents.is_empty() { vec![1.0; s.semi_axes.len()] } else { s.exponents.clone() };
    let shape = Superquadric::new(s.semi_axes.clone(), n)?;
    check_each("semi_axes", &s.semi_axes, &ranges::SEMI_AXIS_M, " m")?;
    check_each("exponents", &s.exponents, &ranges::EXPONENT, "")?;
    Ok(Shape::Superquadric(shape))
}

/// The message of a scenario's footprint.
pub fn footprint_to_proto(f: &FootprintSpec) -> v1::Superquadric {
    v1::Superquadric { semi_axes: f.semi_axes.clone(), exponents: f.exponents.clone().unwrap_or_default() }
}

/// The smallest superquadric of the documented exponents that contains a ROS solid primitive:
/// a box `[x, y, z]` becomes `sum (y_i / a_i)^8 - 1` (exponent [`BOX_EXPONENT`]) with `a_i = (x_i / 2) 3^(1/8)`,
/// so its corners lie on the surface; a sphere `[r]` is exact; a cylinder `[h, r]` (axis z) becomes exponents
/// `(1, 1, 4)` with `a = r s`, `c = (h / 2) s`, `s` solving `s^-2 + s^-8 = 1`, so its rims lie on the surface.
pub fn solid_to_shape(s: &v1::SolidPrimitive) -> Result<Shape, WireError> {
    use v1::solid_primitive::Type;
    check_finite("dimensions", &s.dimensions)?;
    let want = |n: usize| -> Result<(), WireError> {
        if s.dimensions.len() != n {
            return Err(WireError::new(
                "dimensions",
                format!("must have {n} entries, found {}", s.dimensions.len()),
            ));
        }
        Ok(check_each("dimensions", &s.dimensions, &ranges::SOLID_DIMENSION_M, " m")?)
    };
    let shape = match Type::try_from(s.r#type).unwrap_or(Type::Unspecified) {
        Type::Unspecified => return Err(WireError::new("type", "must be BOX, SPHERE or CYLINDER")),
        Type::Box => {
            want(3)?;
            let k = 3f64.powf(1.0 / (2.0 * BOX_EXPONENT));
            Superquadric::new(s.dimensions.iter().map(|x| 0.5 * x * k).collect(), vec![BOX_EXPONENT; 3])?
        }
        Type::Sphere => {
            want(1)?;
            Superquadric::ellipsoid(vec![s.dimensions[0]; 3])?
        }
        Type::Cylinder => {
            want(2)?;
            let (h, r) = (s.dimensions[0], s.dimensions[1]);
            // s^-2 + s^-8 = 1 by bisection on [1, 2].
            let (mut lo, mut hi) = (1.0f64, 2.0f64);
            for _ in 0..80 {
                let mid = 0.5 * (lo + hi);
                if mid.powi(-2) + mid.powi(-8) > 1.0 { lo = mid } else { hi = mid }
            }
            Superquadric::new(vec![r * hi, r * hi, 0.5 * h * hi], vec![1.0, 1.0, 4.0])?
        }
    };
    Ok(Shape::Superquadric(shape))
}

#[cfg(test)]
mod tests {
    use super::*;
    use dmp::Isopotential;

    #[test]
    fn solids_are_contained_in_their_superquadrics() {
        let b = solid_to_shape(&v1::SolidPrimitive { r#type: 1, dimensions: vec![0.2, 0.4, 0.6] }).unwrap();
        assert!(b.value(&[0.1, 0.2, 0.3]).abs() < 1e-12, "a corner lies on the surface");
        assert!(b.value(&[0.1, 0.0, 0.0]) < 0.0);
        let c = solid_to_shape(&v1::SolidPrimitive { r#type: 3, dimensions: vec![0.5, 0.1] }).unwrap();
        assert!(c.value(&[0.1, 0.0, 0.25]).abs() < 1e-9, "a rim lies on the surface");
        let s = solid_to_shape(&v1::SolidPrimitive { r#type: 2, dimensions: vec![0.3] }).unwrap();
        assert!(s.value(&[0.0, 0.3, 0.0]).abs() < 1e-12);
        assert!(solid_to_shape(&v1::SolidPrimitive { r#type: 0, dimensions: vec![0.3] }).is_err());
        assert!(solid_to_shape(&v1::SolidPrimitive { r#type: 1, dimensions: vec![0.3] }).is_err());
    }

    #[test]
    fn footprints_round_trip_through_the_message() {
        let f = FootprintSpec { semi_axes: vec![0.2, 0.1], exponents: Some(vec![1.0, 2.0]) };
        let shape = superquadric_to_shape(&footprint_to_proto(&f)).unwrap();
        assert!(shape.value(&[0.2, 0.0]).abs() < 1e-12);
        let ellipse = footprint_to_proto(&FootprintSpec { semi_axes: vec![0.2, 0.1], exponents: None });
        assert!(ellipse.exponents.is_empty());
        assert!(superquadric_to_shape(&ellipse).unwrap().value(&[0.0, 0.1]).abs() < 1e-12);
        let bad = v1::Superquadric { semi_axes: vec![0.2, -0.1], exponents: vec![] };
        assert_eq!(superquadric_to_shape(&bad).unwrap_err().field, "semi_axes[1]");
    }
}
