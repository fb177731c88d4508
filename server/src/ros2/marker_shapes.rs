//! What each marker draws, without its header or id (the markers' task adds them): an obstacle's true shape, the
//! isopotential the robots avoid, and a robot's path.
//!
//! | namespace | marker | from |
//! | --- | --- | --- |
//! | [`NS_OBSTACLES`] | a box, sphere or cylinder as itself; a superquadric or a nested one as the ellipsoid of its semi-axes | the obstacle as sent |
//! | [`NS_ISOPOTENTIALS`] | the surface `C = 0` of the engine's shape (inflated by the obstacle's margin): a triangle list in 3-D, a closed line strip in 2-D | the engine's obstacle |
//! | [`NS_PATHS`] | a line strip of the positions sent | [`super::paths`] |
//!
//! The isopotential's surface is sampled with the engine's own parametrisation ([`dmp::Isopotential::surface_point`]
//! of unit directions), so every vertex lies on `C = 0`.

use dmp::Isopotential;
use dmp_proto::v1;
use dmp_ros2::msgs::geometry_msgs::{Point, Vector3};
use dmp_ros2::msgs::std_msgs::ColorRGBA;
use dmp_ros2::msgs::visualization_msgs::Marker;
use dmp_ros2::pose::Rigid;

use super::paths::Path;

/// The obstacles as they were sent.
pub(crate) const NS_OBSTACLES: &str = "obstacles";
/// The isopotentials the robots avoid.
pub(crate) const NS_ISOPOTENTIALS: &str = "isopotentials";
/// The robots' planned paths.
pub(crate) const NS_PATHS: &str = "paths";

/// Rows of directions (from pole to pole) of a 3-D isopotential's mesh.
const LATITUDES: usize = 8;
/// Directions per row of a 3-D isopotential's mesh, and points of a 2-D one's outline.
const LONGITUDES: usize = 16;
/// Width of lines (paths, 2-D outlines), metres.
const LINE_WIDTH_M: f64 = 0.01;

/// The true shape of `o`; none for a shape RViz cannot draw (not 2-D or 3-D, a solid with bad dimensions).
pub fn true_shape(o: &v1::Obstacle) -> Option<Marker> {
    let (r#type, scale) = shape_marker(o)?;
    let pose =
        pose_of(&o.center, (o.rotation.len() == o.center.len().pow(2)).then_some(o.rotation.as_slice()))?;
    Some(Marker {
        ns: NS_OBSTACLES.into(),
        r#type,
        action: Marker::ADD,
        pose: pose.to_pose(),
        scale,
        color: ColorRGBA { r: 0.8, g: 0.2, b: 0.2, a: 0.6 },
        text: o.id.clone(),
        ..Default::default()
    })
}

/// The isopotential of the engine's obstacle `o` (its surface in its own frame, placed by the marker's pose); none
/// unless 2-D or 3-D.
pub fn isopotential(o: &dmp::Obstacle) -> Option<Marker> {
    let pose = pose_of(o.center(), o.rotation())?;
    let shape = o.shape();
    let surface = |w: [f64; 3]| -> Point {
        let mut out = [0.0; 3];
        shape.surface_point(&w[..shape.dim()], &mut out[..shape.dim()]);
        Point { x: out[0], y: out[1], z: out[2] }
    };
    let ring = |k: usize| {
        let phi = 2.0 * std::f64::consts::PI * (k % LONGITUDES) as f64 / LONGITUDES as f64;
        (phi.cos(), phi.sin())
    };
    let (r#type, points, scale) = if shape.dim() == 2 {
        let points = (0..=LONGITUDES).map(ring).map(|(c, s)| surface([c, s, 0.0])).collect();
        (Marker::LINE_STRIP, points, Vector3 { x: LINE_WIDTH_M, y: 0.0, z: 0.0 })
    } else {
        let grid: Vec<Vec<Point>> = (0..=LATITUDES)
            .map(|i| {
                let theta = std::f64::consts::PI * i as f64 / LATITUDES as f64;
                (0..=LONGITUDES)
                    .map(ring)
                    .map(|(c, s)| surface([theta.sin() * c, theta.sin() * s, theta.cos()]))
                    .collect()
            })
            .collect();
        let mut points = Vec::with_capacity(LATITUDES * LONGITUDES * 6);
        for i in 0..LATITUDES {
            for k in 0..LONGITUDES {
                let (a, b, c, d) = (&grid[i][k], &grid[i][k + 1], &grid[i + 1][k], &grid[i + 1][k + 1]);
                points.extend([a, c, b, b, c, d].map(Point::clone));
            }
        }
        (Marker::TRIANGLE_LIST, points, Vector3 { x: 1.0, y: 1.0, z: 1.0 })
    };
    Some(Marker {
        ns: NS_ISOPOTENTIALS.into(),
        r#type,
        action: Marker::ADD,
        pose: pose.to_pose(),
        scale,
        color: ColorRGBA { r: 1.0, g: 0.6, b: 0.1, a: 0.25 },
        points,
        text: o.id().to_owned(),
        ..Default::default()
    })
}

/// The path of `robot`; none with fewer than 2 points (a line strip needs 2).
pub fn path(robot: &str, p: &Path) -> Option<Marker> {
    (p.points.len() >= 2).then(|| Marker {
        ns: NS_PATHS.into(),
        r#type: Marker::LINE_STRIP,
        action: Marker::ADD,
        pose: Rigid::IDENTITY.to_pose(),
        scale: Vector3 { x: LINE_WIDTH_M, y: 0.0, z: 0.0 },
        color: ColorRGBA { r: 0.1, g: 0.7, b: 0.2, a: 1.0 },
        points: p.points.iter().map(|&[x, y, z]| Point { x, y, z }).collect(),
        text: robot.to_owned(),
        ..Default::default()
    })
}

/// The pose of a 2-D or 3-D centre and rotation (row-major `d x d`, none for the identity).
fn pose_of(center: &[f64], rotation: Option<&[f64]>) -> Option<Rigid> {
    let d = center.len();
    if !(d == 2 || d == 3) {
        return None;
    }
    let t = [center[0], center[1], center.get(2).copied().unwrap_or(0.0)];
    let mut m = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    if let Some(r) = rotation.filter(|r| r.len() == d * d) {
        for (i, row) in m.iter_mut().enumerate().take(d) {
            row[..d].copy_from_slice(&r[i * d..(i + 1) * d]);
        }
    }
    Some(Rigid::from_matrix(t, m))
}

fn shape_marker(o: &v1::Obstacle) -> Option<(i32, Vector3)> {
    use v1::obstacle::Shape;
    let v = |x: f64, y: f64, z: f64| Vector3 { x, y, z };
    let axes = |a: &[f64]| match a {
        [x, y] => Some(v(2.0 * x, 2.0 * y, 0.01)),
        [x, y, z] => Some(v(2.0 * x, 2.0 * y, 2.0 * z)),
        _ => None,
    };
    match o.shape.as_ref()? {
        Shape::Solid(s) => {
            match (v1::solid_primitive::Type::try_from(s.r#type).ok()?, s.dimensions.as_slice()) {
                (v1::solid_primitive::Type::Box, [x, y, z]) => Some((Marker::CUBE, v(*x, *y, *z))),
                (v1::solid_primitive::Type::Sphere, [r]) => {
                    Some((Marker::SPHERE, v(2.0 * r, 2.0 * r, 2.0 * r)))
                }
                (v1::solid_primitive::Type::Cylinder, [h, r]) => {
                    Some((Marker::CYLINDER, v(2.0 * r, 2.0 * r, *h)))
                }
                _ => None,
            }
        }
        Shape::Superquadric(s) => Some((Marker::SPHERE, axes(&s.semi_axes)?)),
        Shape::Nested(n) => Some((Marker::SPHERE, axes(&n.semi_axes)?)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn boxed(margin: f64) -> v1::Obstacle {
        v1::Obstacle {
            id: "b".into(),
            shape: Some(v1::obstacle::Shape::Solid(v1::SolidPrimitive {
                r#type: 1,
                dimensions: vec![0.2, 0.1, 0.3],
            })),
            center: vec![1.0, 2.0, 3.0],
            rotation: vec![0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0],
            margin,
            ..Default::default()
        }
    }

    #[test]
    fn a_box_is_a_cube_turned_as_sent() {
        let cube = true_shape(&boxed(0.0)).unwrap();
        assert_eq!((cube.r#type, cube.scale.x, cube.pose.position.z), (Marker::CUBE, 0.2, 3.0));
        let q = &cube.pose.orientation;
        let h = std::f64::consts::FRAC_1_SQRT_2;
        assert!((q.z - h).abs() < 1e-12 && (q.w - h).abs() < 1e-12, "a quarter turn about z: {q:?}");
        assert_eq!((cube.ns.as_str(), cube.text.as_str()), (NS_OBSTACLES, "b"));
    }

    #[test]
    fn the_isopotential_is_the_inflated_surface_the_engine_avoids() {
        let proto = boxed(0.05);
        let engine = dmp_proto::obstacle::obstacle_to_engine(&proto).unwrap();
        let m = isopotential(&engine).unwrap();
        assert_eq!((m.r#type, m.ns.as_str()), (Marker::TRIANGLE_LIST, NS_ISOPOTENTIALS));
        assert_eq!(m.points.len(), LATITUDES * LONGITUDES * 6);
        assert_eq!(m.pose, true_shape(&proto).unwrap().pose);
        // Every vertex on C = 0 of the engine's (inflated) shape, so outside the true box.
        for p in &m.points {
            let y = [p.x, p.y, p.z];
            assert!(engine.shape().value(&y).abs() < 1e-9, "{y:?}");
            assert!(y[0].abs() > 0.1 || y[1].abs() > 0.05 || y[2].abs() > 0.15, "{y:?} inside the box");
        }
        let flat = v1::Obstacle {
            id: "e".into(),
            shape: Some(v1::obstacle::Shape::Superquadric(v1::Superquadric {
                semi_axes: vec![0.1, 0.2],
                exponents: vec![],
            })),
            center: vec![0.5, 0.5],
            ..Default::default()
        };
        let outline = isopotential(&dmp_proto::obstacle::obstacle_to_engine(&flat).unwrap()).unwrap();
        assert_eq!((outline.r#type, outline.points.len()), (Marker::LINE_STRIP, LONGITUDES + 1));
        assert_eq!(outline.points.first(), outline.points.last());
        assert_eq!(true_shape(&flat).unwrap().scale, Vector3 { x: 0.2, y: 0.4, z: 0.01 });
    }

    #[test]
    fn a_path_needs_two_points() {
        let mut p = Path { times: vec![0.0], points: vec![[1.0, 2.0, 0.0]] };
        assert!(path("r", &p).is_none());
        p.times.push(0.1);
        p.points.push([1.5, 2.0, 0.0]);
        let m = path("r", &p).unwrap();
        assert_eq!((m.r#type, m.points.len(), m.ns.as_str()), (Marker::LINE_STRIP, 2, NS_PATHS));
    }
}
