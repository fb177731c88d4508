//! Conversions between the wire schema and the engine, validating every field on the way (errors name it).

use dmp::avoidance::{DynamicPoint, DynamicVolumetric, StaticPoint, StaticVolumetric, SteeringAngle};
use dmp::{Avoidance, Method, NestedSuperquadric, Shape, Superquadric};
use dmp_proto::v1;

use crate::config::Limits;
use crate::error::ServerError;

/// Default number of boundary samples of the point methods.
pub const DEFAULT_POINT_SAMPLES: usize = 50;

/// Largest dimension of an obstacle (a robot's space is at most `limits.max_dim`, 64 by default).
pub const MAX_OBSTACLE_DIM: usize = 64;

/// Exponent of the superquadric that stands for a box (a rounded box; see [`solid_to_shape`]).
pub const BOX_EXPONENT: f64 = 4.0;

/// Checks a robot id or primitive name: 1 to 128 characters of `[A-Za-z0-9_.-]` (safe in Zenoh keys and paths).
pub fn check_name(field: &str, s: &str) -> Result<(), ServerError> {
    if s.is_empty() || s.len() > 128 {
        return Err(ServerError::invalid(field, "must have 1 to 128 characters"));
    }
    if let Some(c) = s.chars().find(|c| !(c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'))) {
        return Err(ServerError::invalid(
            field,
            format!("has `{c}`: only letters, digits, `_`, `-` and `.` are allowed"),
        ));
    }
    Ok(())
}

fn finite(field: &str, v: &[f64]) -> Result<(), ServerError> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(i) => Err(ServerError::invalid(format!("{field}[{i}]"), "must be a finite number")),
        None => Ok(()),
    }
}

/// The engine's shape of a per-axis superquadric message.
pub fn superquadric_to_shape(s: &v1::Superquadric) -> Result<Shape, ServerError> {
    let n = if s.exponents.is_empty() { vec![1.0; s.semi_axes.len()] } else { s.exponents.clone() };
    Ok(Shape::Superquadric(Superquadric::new(s.semi_axes.clone(), n)?))
}

/// The smallest superquadric of the documented exponents that contains a ROS solid primitive:
/// a box `[x, y, z]` becomes `sum (y_i / a_i)^8 - 1` (exponent [`BOX_EXPONENT`]) with `a_i = (x_i / 2) 3^(1/8)`,
/// so its corners lie on the surface; a sphere `[r]` is exact; a cylinder `[h, r]` (axis z) becomes exponents
/// `(1, 1, 4)` with `a = r s`, `c = (h / 2) s`, `s` solving `s^-2 + s^-8 = 1`, so its rims lie on the surface.
pub fn solid_to_shape(s: &v1::SolidPrimitive) -> Result<Shape, ServerError> {
    use v1::solid_primitive::Type;
    finite("dimensions", &s.dimensions)?;
    let want = |n: usize| -> Result<(), ServerError> {
        if s.dimensions.len() != n {
            return Err(ServerError::invalid(
                "dimensions",
                format!("must have {n} entries, found {}", s.dimensions.len()),
            ));
        }
        if let Some(i) = s.dimensions.iter().position(|d| *d <= 0.0) {
            return Err(ServerError::invalid(format!("dimensions[{i}]"), "must be greater than zero"));
        }
        Ok(())
    };
    let shape = match Type::try_from(s.r#type).unwrap_or(Type::Unspecified) {
        Type::Unspecified => return Err(ServerError::invalid("type", "must be BOX, SPHERE or CYLINDER")),
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

/// The engine's obstacle of a message: its centre is the one at the time of the update.
pub fn obstacle_to_engine(o: &v1::Obstacle) -> Result<dmp::Obstacle, ServerError> {
    use v1::obstacle::Shape as S;
    let shape = match &o.shape {
        None => return Err(ServerError::invalid("shape", "is required (superquadric, nested or solid)")),
        Some(S::Superquadric(s)) => superquadric_to_shape(s).map_err(|e| e.within("superquadric"))?,
        Some(S::Nested(n)) => {
            let a: [f64; 3] = n.semi_axes.as_slice().try_into().map_err(|_| {
                ServerError::invalid(
                    "nested.semi_axes",
                    format!("must have 3 entries, found {}", n.semi_axes.len()),
                )
            })?;
            Shape::Nested(
                NestedSuperquadric::new(a, n.n, n.m).map_err(|e| ServerError::from(e).within("nested"))?,
            )
        }
        Some(S::Solid(s)) => solid_to_shape(s).map_err(|e| e.within("solid"))?,
    };
    if !(o.margin.is_finite() && o.margin >= 0.0) {
        return Err(ServerError::invalid("margin", "must be a finite number >= 0"));
    }
    if !(o.ttl_s.is_finite() && o.ttl_s >= 0.0) {
        return Err(ServerError::invalid("ttl_s", "must be a finite number >= 0"));
    }
    let shape = if o.margin > 0.0 { shape.inflated(o.margin)? } else { shape };
    let d = dmp::Isopotential::dim(&shape);
    if d > MAX_OBSTACLE_DIM {
        return Err(ServerError::invalid(
            "shape",
            format!("has {d} dimensions, more than {MAX_OBSTACLE_DIM}"),
        ));
    }
    let rotation = if o.rotation.is_empty() {
        None
    } else {
        if o.rotation.len() != d * d {
            return Err(ServerError::invalid(
                "rotation",
                format!("must have {} entries (d x d, row-major)", d * d),
            ));
        }
        Some(o.rotation.chunks(d).map(<[f64]>::to_vec).collect())
    };
    let velocity = (!o.velocity.is_empty()).then(|| o.velocity.clone());
    Ok(dmp::Obstacle::new(o.id.clone(), shape, o.center.clone(), rotation, velocity)?)
}

/// Parses a Zenoh JSON payload (the scenario format's obstacle, plus `margin` and `ttl_s`) into the obstacle
/// message; `id_from_key` names it when the JSON has no `id`.
pub fn obstacle_from_json(bytes: &[u8], id_from_key: &str) -> Result<v1::Obstacle, ServerError> {
    let mut value: serde_json::Value =
        serde_json::from_slice(bytes).map_err(|e| ServerError::invalid("payload", e.to_string()))?;
    if let serde_json::Value::Object(obj) = &mut value {
        obj.entry("id").or_insert_with(|| id_from_key.into());
    }
    Ok(dmp_proto::obstacle_json::JsonObstacle::parse(&value, "")?.to_proto())
}

/// The message of a primitive.
pub use dmp_proto::primitive::primitive_to_proto;

/// The engine's primitive of a message, validated and within the limits.
pub fn primitive_from_proto(p: &v1::Primitive, limits: &Limits) -> Result<dmp::Primitive, ServerError> {
    if p.dim as usize > limits.max_dim {
        return Err(ServerError::invalid("dim", format!("must be at most {}", limits.max_dim)));
    }
    if p.n_basis as usize > limits.max_basis {
        return Err(ServerError::invalid("n_basis", format!("must be at most {}", limits.max_basis)));
    }
    Ok(dmp_proto::primitive::primitive_from_proto(p)?)
}

/// The engine's demonstration of a message, within the limits.
pub fn demonstration_from_proto(
    d: &v1::Demonstration,
    limits: &Limits,
) -> Result<dmp::Demonstration, ServerError> {
    let dim = d.dim as usize;
    if dim == 0 || dim > limits.max_dim {
        return Err(ServerError::invalid(
            "demonstration.dim",
            format!("must be between 1 and {}", limits.max_dim),
        ));
    }
    if d.t.len() > limits.max_samples {
        return Err(ServerError::ResourceExhausted(format!(
            "demonstration.t: {} samples, more than the limit of {}",
            d.t.len(),
            limits.max_samples
        )));
    }
    if d.positions.len() != d.t.len() * dim {
        return Err(ServerError::invalid(
            "demonstration.positions",
            format!("must have t.len() x dim = {} entries, found {}", d.t.len() * dim, d.positions.len()),
        ));
    }
    let rows = d.positions.chunks(dim).map(<[f64]>::to_vec).collect();
    Ok(dmp::Demonstration::new(d.t.clone(), rows)?)
}

/// The learning configuration of a message, with the documented defaults.
pub fn learn_config_from_proto(
    p: Option<&v1::LearnParameters>,
    limits: &Limits,
) -> Result<dmp::LearnConfig, ServerError> {
    let mut c = dmp::LearnConfig::paper();
    if let Some(p) = p {
        if p.n_basis as usize > limits.max_basis {
            return Err(ServerError::invalid(
                "parameters.n_basis",
                format!("must be at most {}", limits.max_basis),
            ));
        }
        if p.n_basis > 0 {
            c.n_basis = p.n_basis as usize;
        }
        if !p.k.is_empty() {
            c.k = p.k.clone();
        }
        if !p.d.is_empty() {
            c.d = Some(p.d.clone());
        }
        if p.alpha != 0.0 {
            c.alpha = p.alpha;
        }
    }
    Ok(c)
}

/// The engine's avoidance of a message; an unset method takes `default`. Returns the boundary sample count too.
pub fn avoidance_from_proto(
    a: Option<&v1::Avoidance>,
    default: Avoidance,
) -> Result<(Avoidance, usize), ServerError> {
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
    if samples > 10_000 {
        return Err(ServerError::invalid("point_samples", "must be at most 10000"));
    }
    let relative_velocity =
        if a.method.is_none() { default.relative_velocity } else { !a.ignore_obstacle_velocity };
    Ok((Avoidance { method, relative_velocity }, samples))
}

/// Checks a vector of `dim` finite entries.
pub fn vector(field: &str, v: &[f64], dim: usize) -> Result<(), ServerError> {
    if v.len() != dim {
        return Err(ServerError::invalid(field, format!("must have {dim} entries, found {}", v.len())));
    }
    finite(field, v)
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
    fn json_obstacles_follow_the_scenario_format() {
        let o = obstacle_from_json(
            br#"{"center": [0.1, 0.2], "semi_axes": [0.3, 0.2], "exponents": [1, 2], "ttl_s": 2.5}"#,
            "box1",
        )
        .unwrap();
        assert_eq!(o.id, "box1");
        assert_eq!(o.ttl_s, 2.5);
        obstacle_to_engine(&o).unwrap();
        let e = obstacle_from_json(br#"{"center": [0.1], "semi_axes": [0.3], "bogus": 1}"#, "x").unwrap_err();
        assert!(e.to_string().contains("bogus"), "{e}");
        let o = obstacle_from_json(br#"{"center": [0.1, 0.2], "semi_axes": [-0.3, 0.2]}"#, "x").unwrap();
        let e = obstacle_to_engine(&o).unwrap_err();
        assert!(e.to_string().contains("semi_axes[0]"), "{e}");
    }

    #[test]
    fn names_are_checked() {
        assert!(check_name("robot_id", "panda-1.left_arm").is_ok());
        assert!(check_name("robot_id", "").is_err());
        assert!(check_name("robot_id", "a/b").is_err());
        assert!(check_name("robot_id", &"x".repeat(129)).is_err());
    }
}
