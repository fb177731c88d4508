//! A ROS shape as the server's obstacle shape, with the offset of that shape's centre in the ROS shape's frame.
//! Boxes, spheres and cylinders are `dmp.v1.SolidPrimitive`s, which `dmp_proto::shape::solid_to_shape` makes the
//! smallest superquadrics around them (the server's one conversion); the others are new here.

use dmp_proto::v1;
use dmp_proto::v1::obstacle::Shape;
use dmp_ros2::msgs::geometry_msgs::Point;
use dmp_ros2::msgs::shape_msgs::{Mesh, SolidPrimitive};

use crate::error::ServerError;

/// A shape and where its centre is in the frame of the ROS shape it stands for.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Placed {
    /// The server's shape.
    pub shape: Shape,
    /// Its centre in the ROS shape's frame (not zero for a cone, a mesh, a prism).
    pub offset: [f64; 3],
}

/// The server's shape of a solid primitive (fields named from `field`, e.g. `primitives[1]`).
///
/// # Formula
/// A cone of height `h` and base radius `r` (base at `z = -h/2`, tip at `z = h/2`) is inside the ellipsoid (the
/// superquadric of exponents 1) of centre `z = -h/4` and semi-axes `(3r / (2 sqrt 2), 3r / (2 sqrt 2), 3h / 4)`,
/// which touches its tip and its base's rim. Of the ellipsoids through the tip and the rim, centred on the axis
/// at `z = -h/2 + t` (`c = h - t`, `a² = r² / (1 - t² / c²)`), the volume `∝ a² c ∝ (h - t)³ / (h - 2t)` is least at
/// `t = h / 4`. A prism is the box around its polygon and height.
pub(crate) fn solid(p: &SolidPrimitive, field: &str) -> Result<Placed, ServerError> {
    let dims = &p.dimensions;
    let want = |n: usize| -> Result<(), ServerError> {
        if dims.len() != n {
            return Err(ServerError::invalid(
                format!("{field}.dimensions"),
                format!("must have {n} entries, found {}", dims.len()),
            ));
        }
        if let Some(i) = dims.iter().position(|d| !(d.is_finite() && *d > 0.0)) {
            return Err(ServerError::invalid(format!("{field}.dimensions[{i}]"), "must be finite and > 0"));
        }
        Ok(())
    };
    let solid = |ty: v1::solid_primitive::Type, d: Vec<f64>| {
        Shape::Solid(v1::SolidPrimitive { r#type: ty as i32, dimensions: d })
    };
    use v1::solid_primitive::Type;
    let placed = match p.r#type {
        SolidPrimitive::BOX => {
            want(3)?;
            Placed { shape: solid(Type::Box, dims.clone()), offset: [0.0; 3] }
        }
        SolidPrimitive::SPHERE => {
            want(1)?;
            Placed { shape: solid(Type::Sphere, dims.clone()), offset: [0.0; 3] }
        }
        SolidPrimitive::CYLINDER => {
            want(2)?;
            Placed { shape: solid(Type::Cylinder, dims.clone()), offset: [0.0; 3] }
        }
        SolidPrimitive::CONE => {
            want(2)?;
            let (h, r) = (dims[0], dims[1]);
            let a = 3.0 * r / (2.0 * std::f64::consts::SQRT_2);
            let shape =
                Shape::Superquadric(v1::Superquadric { semi_axes: vec![a, a, 0.75 * h], exponents: vec![] });
            Placed { shape, offset: [0.0, 0.0, -0.25 * h] }
        }
        SolidPrimitive::PRISM => {
            want(1)?;
            let h = dims[0];
            let points: Vec<[f64; 3]> = p
                .polygon
                .points
                .iter()
                .flat_map(|q| [-0.5, 0.5].map(|s| [f64::from(q.x), f64::from(q.y), s * h]))
                .collect();
            bounding_box(&points, &format!("{field}.polygon.points"))?
        }
        other => {
            return Err(ServerError::invalid(
                format!("{field}.type"),
                format!("is {other}: must be BOX (1), SPHERE (2), CYLINDER (3), CONE (4) or PRISM (5)"),
            ));
        }
    };
    Ok(placed)
}

/// The server's shape of a mesh: the box superquadric around the box that holds its vertices (in the mesh's
/// frame), so the whole mesh is inside. Fields named from `field`, e.g. `meshes[0]`.
pub(crate) fn mesh(m: &Mesh, field: &str) -> Result<Placed, ServerError> {
    let points: Vec<[f64; 3]> = m.vertices.iter().map(|Point { x, y, z }| [*x, *y, *z]).collect();
    bounding_box(&points, &format!("{field}.vertices"))
}

/// The box solid around `points`, centred on their bounding box; a flat side is given the smallest thickness the
/// server takes.
fn bounding_box(points: &[[f64; 3]], field: &str) -> Result<Placed, ServerError> {
    if points.is_empty() {
        return Err(ServerError::invalid(field, "must not be empty"));
    }
    if let Some(i) = points.iter().position(|p| !p.iter().all(|v| v.is_finite())) {
        return Err(ServerError::invalid(format!("{field}[{i}]"), "must be finite"));
    }
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in points {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let min = *dmp::ranges::SOLID_DIMENSION_M.start();
    let dims = [0, 1, 2].map(|k| (hi[k] - lo[k]).max(min));
    let offset = [0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k]));
    let shape = Shape::Solid(v1::SolidPrimitive {
        r#type: v1::solid_primitive::Type::Box as i32,
        dimensions: dims.to_vec(),
    });
    Ok(Placed { shape, offset })
}

#[cfg(test)]
mod tests {
    use super::*;
    use dmp::Isopotential;
    use dmp_ros2::msgs::geometry_msgs::{Point32, Polygon};

    fn engine(p: &Placed) -> dmp::Shape {
        let o = v1::Obstacle {
            id: "o".into(),
            shape: Some(p.shape.clone()),
            center: vec![0.0; 3],
            ..Default::default()
        };
        match dmp_proto::obstacle::obstacle_to_engine(&o) {
            Ok(e) => e.shape().clone(),
            Err(e) => panic!("{e}"),
        }
    }

    #[test]
    fn the_cone_is_inside_its_ellipsoid_touching_tip_and_rim() {
        let (h, r) = (0.4, 0.1);
        let cone =
            SolidPrimitive { r#type: SolidPrimitive::CONE, dimensions: vec![h, r], ..Default::default() };
        let p = solid(&cone, "primitives[0]").unwrap();
        let s = engine(&p);
        let at = |x: f64, z: f64| s.value(&[x - p.offset[0], -p.offset[1], z - p.offset[2]]);
        assert!(at(0.0, h / 2.0).abs() < 1e-12, "the tip is on the surface");
        assert!(at(r, -h / 2.0).abs() < 1e-12, "the base's rim is on the surface");
        for i in 0..=20 {
            // The cone's side, from the rim to the tip, is inside.
            let f = f64::from(i) / 20.0;
            assert!(at(r * (1.0 - f), -h / 2.0 + f * h) <= 1e-12);
        }
    }

    #[test]
    fn meshes_and_prisms_are_inside_their_boxes() {
        let m = Mesh {
            vertices: vec![Point { x: 0.0, y: 0.0, z: 0.0 }, Point { x: 0.2, y: 0.4, z: 0.1 }],
            triangles: vec![],
        };
        let p = mesh(&m, "meshes[0]").unwrap();
        assert_eq!(p.offset, [0.1, 0.2, 0.05]);
        assert!(engine(&p).value(&[0.1, 0.2, 0.05]).abs() < 1e-12, "a corner is on the surface");
        let pts = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)].map(|(x, y)| Point32 { x, y, z: 0.0 });
        let prism = SolidPrimitive {
            r#type: SolidPrimitive::PRISM,
            dimensions: vec![0.2],
            polygon: Polygon { points: pts.to_vec() },
        };
        assert_eq!(solid(&prism, "p").unwrap().offset, [0.5, 0.5, 0.0]);
    }

    #[test]
    fn bad_solids_name_the_field() {
        let bad =
            SolidPrimitive { r#type: SolidPrimitive::BOX, dimensions: vec![0.1, 0.2], ..Default::default() };
        assert!(
            solid(&bad, "primitives[2]").unwrap_err().to_string().starts_with("primitives[2].dimensions")
        );
        let neg =
            SolidPrimitive { r#type: SolidPrimitive::SPHERE, dimensions: vec![-1.0], ..Default::default() };
        assert!(solid(&neg, "p").unwrap_err().to_string().starts_with("p.dimensions[0]"));
        let unknown = SolidPrimitive { r#type: 9, dimensions: vec![1.0], ..Default::default() };
        assert!(solid(&unknown, "p").unwrap_err().to_string().starts_with("p.type"));
        assert!(
            mesh(&Mesh::default(), "meshes[0]").unwrap_err().to_string().starts_with("meshes[0].vertices")
        );
    }
}
