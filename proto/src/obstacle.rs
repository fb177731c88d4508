//! An obstacle message as the engine's obstacle. The JSON form of an obstacle is [`crate::obstacle_json`].

use dmp::ranges::{self, check_each, check_range};
use dmp::{NestedSuperquadric, Shape};

use crate::WireError;
use crate::check::check_finite;
use crate::shape::{solid_to_shape, superquadric_to_shape};
use crate::v1;

/// Largest dimension of an obstacle (a robot's space is at most the server's `limits.max_dim`, 64 by default).
pub const MAX_OBSTACLE_DIM: usize = 64;

/// The engine's obstacle of a message, inflated by its margin: its centre is the one at the time of the update.
/// Every number is checked against its range in [`dmp::ranges`] (the centre against the workspace is the server's).
pub fn obstacle_to_engine(o: &v1::Obstacle) -> Result<dmp::Obstacle, WireError> {
    use v1::obstacle::Shape as S;
    let shape = match &o.shape {
        None => return Err(WireError::new("shape", "is required (superquadric, nested or solid)")),
        Some(S::Superquadric(s)) => superquadric_to_shape(s).map_err(|e| e.within("superquadric"))?,
        Some(S::Nested(n)) => {
            let a: [f64; 3] = n.semi_axes.as_slice().try_into().map_err(|_| {
                WireError::new(
                    "nested.semi_axes",
                    format!("must have 3 entries, found {}", n.semi_axes.len()),
                )
            })?;
            let shape =
                NestedSuperquadric::new(a, n.n, n.m).map_err(|e| WireError::from(e).within("nested"))?;
            check_each("nested.semi_axes", &a, &ranges::SEMI_AXIS_M, " m")?;
            check_range("nested.n", n.n, &ranges::EXPONENT, "")?;
            check_range("nested.m", n.m, &ranges::EXPONENT, "")?;
            Shape::Nested(shape)
        }
        Some(S::Solid(s)) => solid_to_shape(s).map_err(|e| e.within("solid"))?,
    };
    check_range("margin", o.margin, &ranges::MARGIN_M, " m")?;
    if !(o.ttl_s.is_finite() && o.ttl_s >= 0.0) {
        return Err(WireError::new("ttl_s", "must be a finite number >= 0"));
    }
    let shape = if o.margin > 0.0 { shape.inflated(o.margin)? } else { shape };
    let d = dmp::Isopotential::dim(&shape);
    if d > MAX_OBSTACLE_DIM {
        return Err(WireError::new("shape", format!("has {d} dimensions, more than {MAX_OBSTACLE_DIM}")));
    }
    let rotation = if o.rotation.is_empty() {
        None
    } else {
        if o.rotation.len() != d * d {
            return Err(WireError::new(
                "rotation",
                format!("must have {} entries (d x d, row-major)", d * d),
            ));
        }
        Some(o.rotation.chunks(d).map(<[f64]>::to_vec).collect())
    };
    check_finite("velocity", &o.velocity)?;
    let speed = o.velocity.iter().map(|v| v * v).sum::<f64>().sqrt();
    check_range("velocity", speed, &ranges::SPEED_MPS, " m/s (its magnitude)")?;
    let velocity = (!o.velocity.is_empty()).then(|| o.velocity.clone());
    Ok(dmp::Obstacle::new(o.id.clone(), shape, o.center.clone(), rotation, velocity)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ball(radius: f64) -> v1::Obstacle {
        v1::Obstacle {
            id: "b".into(),
            shape: Some(v1::obstacle::Shape::Solid(v1::SolidPrimitive {
                r#type: 2,
                dimensions: vec![radius],
            })),
            center: vec![0.0; 3],
            ..Default::default()
        }
    }

    #[test]
    fn bad_obstacles_name_the_field() {
        obstacle_to_engine(&ball(0.1)).unwrap();
        assert_eq!(obstacle_to_engine(&ball(-0.1)).unwrap_err().field, "solid.dimensions[0]");
        let e = obstacle_to_engine(&v1::Obstacle { margin: f64::INFINITY, ..ball(0.1) }).unwrap_err();
        assert_eq!(e.field, "margin");
        let e = obstacle_to_engine(&v1::Obstacle { rotation: vec![1.0; 4], ..ball(0.1) }).unwrap_err();
        assert_eq!(e.field, "rotation");
        let e = obstacle_to_engine(&v1::Obstacle { shape: None, ..ball(0.1) }).unwrap_err();
        assert_eq!(e.field, "shape");
    }
}
