//! The true world of a simulation, measured with parry3d-f64: the obstacles' real shapes (not the superquadrics the
//! server plans with) and the robots' bodies.
//!
//! Everything is 3-D. A 2-D robot (a youBot on the floor) lives in the plane `z = 0`: its obstacles are parry
//! shapes of [`PLANAR_HALF_HEIGHT`] half-height centred on the plane, so a 3-D distance between two such shapes is
//! their distance in the plane.

use parry3d_f64::math::{Pose, Rotation, Vector};
use parry3d_f64::query;
use parry3d_f64::shape::{Ball, Cuboid, Cylinder, Shape};

/// Half-height of the prisms that stand for 2-D shapes.
pub(crate) const PLANAR_HALF_HEIGHT: f64 = 0.5;

/// The kind and size of a true shape: what parry measures (a [`Body`] places it in the world).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum SolidShape {
    /// A ball of this radius.
    Ball {
        /// Radius, metres.
        radius: f64,
    },
    /// A box of these half-extents (x, y, z).
    Cuboid {
        /// Half-extents, metres.
        half: [f64; 3],
    },
    /// A cylinder whose axis is the world `z` axis.
    CylinderZ {
        /// Radius, metres.
        radius: f64,
        /// Half-height, metres.
        half_height: f64,
    },
    /// A point (distance to it is the distance to its position).
    Point,
}

impl SolidShape {
    /// A 2-D rectangle of half-sides `(hx, hy)`, as a prism.
    pub(crate) fn rectangle(hx: f64, hy: f64) -> Self {
        SolidShape::Cuboid { half: [hx, hy, PLANAR_HALF_HEIGHT] }
    }

    /// The parry shape and the rotation (axis-angle) that puts its axis where this solid's is.
    fn parry(&self) -> (Box<dyn Shape>, Vector) {
        match *self {
            SolidShape::Ball { radius } => (Box::new(Ball::new(radius)), Vector::ZERO),
            SolidShape::Point => (Box::new(Ball::new(0.0)), Vector::ZERO),
            SolidShape::Cuboid { half } => {
                (Box::new(Cuboid::new(Vector::new(half[0], half[1], half[2]))), Vector::ZERO)
            }
            // parry's cylinders stand along y; a quarter turn about x takes y to z.
            SolidShape::CylinderZ { radius, half_height } => (
                Box::new(Cylinder::new(half_height, radius)),
                Vector::new(std::f64::consts::FRAC_PI_2, 0.0, 0.0),
            ),
        }
    }
}

/// A solid placed in the world, present during a time window of the run.
pub(crate) struct Body {
    /// Its name (an obstacle's id).
    pub(crate) id: String,
    solid: SolidShape,
    shape: Box<dyn Shape>,
    center: Vector,
    axis_angle: Vector,
    /// Present from this time of the run on (seconds).
    pub(crate) from: f64,
    /// Present until this time of the run (seconds; infinity: to the end).
    pub(crate) until: f64,
}

impl std::fmt::Debug for Body {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Body")
            .field("id", &self.id)
            .field("solid", &self.solid)
            .field("center", &self.center)
            .field("from", &self.from)
            .field("until", &self.until)
            .finish()
    }
}

/// A position of 2 or 3 coordinates as a 3-D point (`z = 0` in 2-D).
pub(crate) fn point3(p: &[f64]) -> Vector {
    Vector::new(p[0], p.get(1).copied().unwrap_or(0.0), p.get(2).copied().unwrap_or(0.0))
}

impl Body {
    /// A solid centred at `center` (2 or 3 coordinates), always present.
    pub(crate) fn new(id: impl Into<String>, solid: SolidShape, center: &[f64]) -> Self {
        let (shape, axis_angle) = solid.parry();
        Self {
            id: id.into(),
            solid,
            shape,
            center: point3(center),
            axis_angle,
            from: 0.0,
            until: f64::INFINITY,
        }
    }

    /// The same, present only in `[from, until)`.
    pub(crate) fn during(mut self, from: f64, until: f64) -> Self {
        self.from = from;
        self.until = until;
        self
    }

    /// The solid.
    pub(crate) fn solid(&self) -> SolidShape {
        self.solid
    }

    /// The centre.
    pub(crate) fn center(&self) -> [f64; 3] {
        [self.center.x, self.center.y, self.center.z]
    }

    /// Whether it exists at time `t`.
    pub(crate) fn present_at(&self, t: f64) -> bool {
        t >= self.from && t < self.until
    }

    fn pose(&self, offset: Vector) -> Pose {
        Pose::new(self.center + offset, self.axis_angle)
    }

    /// Distance between this body translated by `offset` and `other` translated by `other_offset` (0 when they
    /// touch or overlap).
    pub(crate) fn distance(&self, offset: Vector, other: &Body, other_offset: Vector) -> f64 {
        let (p1, p2) = (self.pose(offset), other.pose(other_offset));
        match query::distance(&p1, self.shape.as_ref(), &p2, other.shape.as_ref()) {
            Ok(d) => d.distance,
            // Every pair used here (balls, cuboids, cylinders) is supported; a failure counts as a contact.
            Err(_) => 0.0,
        }
    }
}

impl Body {
    /// Distance between this body carried by a pose, at `position` turned by the unit quaternion `q = [x, y, z,
    /// w]` (the body keeps its own placement in the carrying frame: a held tool's shape in the tool frame), and
    /// `other` where it stands (0 when they touch or overlap).
    pub(crate) fn distance_posed(&self, position: Vector, q: &[f64], other: &Body) -> f64 {
        self.distance_carried((position, Some(q)), other, (Vector::ZERO, None))
    }

    /// Distance between this body and `other`, each carried at a position and, for a pose robot, turned by a
    /// unit quaternion `[x, y, z, w]` (none: not turned).
    pub(crate) fn distance_carried(
        &self,
        (position, q): (Vector, Option<&[f64]>),
        other: &Body,
        (other_position, other_q): (Vector, Option<&[f64]>),
    ) -> f64 {
        let place = |b: &Body, p: Vector, q: Option<&[f64]>| match q {
            Some(q) => {
                let rotation = Rotation::from_xyzw(q[0], q[1], q[2], q[3]).normalize();
                Pose::from_parts(p, rotation) * b.pose(Vector::ZERO)
            }
            None => b.pose(p),
        };
        let (p1, p2) = (place(self, position, q), place(other, other_position, other_q));
        match query::distance(&p1, self.shape.as_ref(), &p2, other.shape.as_ref()) {
            Ok(d) => d.distance,
            Err(_) => 0.0,
        }
    }
}

/// The robot's body relative to its controlled point: a point, a ball (a carried ring), a rectangle (a youBot).
pub(crate) fn robot_body(id: &str, solid: SolidShape) -> Body {
    Body::new(id, solid, &[0.0, 0.0, 0.0])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distances_to_true_shapes() {
        let peg =
            Body::new("peg", SolidShape::CylinderZ { radius: 0.01, half_height: 0.05 }, &[0.5, 0.0, 0.07]);
        let ring = robot_body("ring", SolidShape::Ball { radius: 0.02 });
        // Beside the peg, level with its middle: 0.1 - 0.01 - 0.02.
        let d = ring.distance(point3(&[0.6, 0.0, 0.07]), &peg, Vector::ZERO);
        assert!((d - 0.07).abs() < 1e-9, "{d}");
        // Above its top (z = 0.12): 0.2 - 0.12 - 0.02, which a y-axis cylinder would get wrong.
        let d = ring.distance(point3(&[0.5, 0.0, 0.2]), &peg, Vector::ZERO);
        assert!((d - 0.06).abs() < 1e-9, "{d}");
        let wall = Body::new("wall", SolidShape::rectangle(1.0, 0.05), &[0.0, 1.0]);
        let youbot = robot_body("youbot", SolidShape::rectangle(0.29, 0.19));
        let d = youbot.distance(point3(&[0.3, 0.2]), &wall, Vector::ZERO);
        assert!((d - (0.95 - 0.39)).abs() < 1e-9, "{d}");
        assert_eq!(youbot.distance(point3(&[0.0, 0.8]), &wall, Vector::ZERO), 0.0);
    }

    #[test]
    fn a_carried_body_is_turned_by_its_pose() {
        // (parry measures a turned box or cylinder with GJK, to about 1e-8.)
        // A 0.6 m bar along the tool's x, 0.5 m from a peg's axis along y: across (unturned) it misses the peg by
        // 0.5 - 0.01 - 0.05; turned a quarter about z its tip comes 0.5 - 0.3 - 0.05 from it.
        let peg =
            Body::new("peg", SolidShape::CylinderZ { radius: 0.05, half_height: 0.2 }, &[0.0, 0.5, 0.0]);
        let bar = robot_body("bar", SolidShape::Cuboid { half: [0.3, 0.01, 0.01] });
        let d = bar.distance_posed(Vector::ZERO, &[0.0, 0.0, 0.0, 1.0], &peg);
        assert!((d - 0.44).abs() < 1e-6, "{d}");
        let s = std::f64::consts::FRAC_1_SQRT_2;
        let d = bar.distance_posed(Vector::ZERO, &[0.0, 0.0, s, s], &peg);
        assert!((d - 0.15).abs() < 1e-6, "{d}");
        // A ring's disc (a cylinder along the tool's z) flat: 0.5 - 0.05 - 0.025; turned a quarter about x, on
        // its side, it shows the peg its thickness: 0.5 - 0.05 - 0.004.
        let ring = robot_body("ring", SolidShape::CylinderZ { radius: 0.025, half_height: 0.004 });
        let d = ring.distance_posed(Vector::ZERO, &[0.0, 0.0, 0.0, 1.0], &peg);
        assert!((d - 0.425).abs() < 1e-6, "{d}");
        let d = ring.distance_posed(Vector::ZERO, &[s, 0.0, 0.0, s], &peg);
        assert!((d - 0.446).abs() < 1e-6, "{d}");
    }
}
