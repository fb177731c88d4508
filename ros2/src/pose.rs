//! Rigid transforms of the messages' poses: a unit quaternion and a translation, composed and turned into the
//! row-major rotation matrix the server's obstacles carry.
//!
//! # Formula
//! With `q = (x, y, z, w)` a unit quaternion, `R(q)` is the matrix whose columns are the images of the axes:
//! `R = [[1 - 2(y² + z²), 2(xy - zw), 2(xz + yw)], [2(xy + zw), 1 - 2(x² + z²), 2(yz - xw)],
//! [2(xz - yw), 2(yz + xw), 1 - 2(x² + y²)]]`. Composing `a` then `b` (b expressed in a's frame):
//! `t = t_a + R(q_a) t_b`, `q = q_a q_b` (Hamilton product).

use crate::msgs::geometry_msgs::{Point, Pose, Quaternion};

/// A quaternion that is not a rotation.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{field}: {reason}")]
pub struct PoseError {
    /// The field at fault, e.g. `primitive_poses[1].orientation`.
    pub field: String,
    /// Why.
    pub reason: String,
}

/// A rigid transform: a rotation (unit quaternion, `x, y, z, w`) then a translation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rigid {
    /// Translation.
    pub t: [f64; 3],
    /// Unit quaternion `x, y, z, w`.
    pub q: [f64; 4],
}

impl Rigid {
    /// The identity.
    pub const IDENTITY: Self = Self { t: [0.0; 3], q: [0.0, 0.0, 0.0, 1.0] };

    /// A translation and a quaternion, normalised; `field` names the pose in the error of a quaternion that is
    /// zero (within 1e-6 of it) or not finite, or a translation that is not finite.
    pub fn new(t: [f64; 3], q: [f64; 4], field: &str) -> Result<Self, PoseError> {
        let err =
            |what: &str, reason: &str| PoseError { field: format!("{field}.{what}"), reason: reason.into() };
        if !t.iter().all(|v| v.is_finite()) {
            return Err(err("position", "must be finite"));
        }
        let n = q.iter().map(|v| v * v).sum::<f64>().sqrt();
        if !n.is_finite() || n < 1e-6 {
            return Err(err("orientation", "must be a nonzero finite quaternion"));
        }
        Ok(Self { t, q: q.map(|v| v / n) })
    }

    /// The transform of a rotation matrix (row-major rows, columns the frame's axes, assumed orthonormal) and a
    /// translation: the quaternion by Shepperd's method (from the largest of `w`, `x`, `y`, `z`).
    pub fn from_matrix(t: [f64; 3], m: [[f64; 3]; 3]) -> Self {
        let tr = m[0][0] + m[1][1] + m[2][2];
        let q = if tr > 0.0 {
            let s = 2.0 * (1.0 + tr).sqrt();
            [(m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s, 0.25 * s]
        } else if m[0][0] > m[1][1] && m[0][0] > m[2][2] {
            let s = 2.0 * (1.0 + m[0][0] - m[1][1] - m[2][2]).sqrt();
            [0.25 * s, (m[0][1] + m[1][0]) / s, (m[0][2] + m[2][0]) / s, (m[2][1] - m[1][2]) / s]
        } else if m[1][1] > m[2][2] {
            let s = 2.0 * (1.0 + m[1][1] - m[0][0] - m[2][2]).sqrt();
            [(m[0][1] + m[1][0]) / s, 0.25 * s, (m[1][2] + m[2][1]) / s, (m[0][2] - m[2][0]) / s]
        } else {
            let s = 2.0 * (1.0 + m[2][2] - m[0][0] - m[1][1]).sqrt();
            [(m[0][2] + m[2][0]) / s, (m[1][2] + m[2][1]) / s, 0.25 * s, (m[1][0] - m[0][1]) / s]
        };
        Self { t, q }
    }

    /// The transform of a message's pose.
    pub fn from_pose(p: &Pose, field: &str) -> Result<Self, PoseError> {
        let Point { x, y, z } = p.position;
        let Quaternion { x: qx, y: qy, z: qz, w } = p.orientation;
        Self::new([x, y, z], [qx, qy, qz, w], field)
    }

    /// This transform as a message's pose.
    pub fn to_pose(&self) -> Pose {
        let [x, y, z] = self.t;
        let [qx, qy, qz, w] = self.q;
        Pose { position: Point { x, y, z }, orientation: Quaternion { x: qx, y: qy, z: qz, w } }
    }

    /// `self` then `other` (`other` expressed in `self`'s frame).
    pub fn then(&self, other: &Rigid) -> Rigid {
        let r = self.rotate(other.t);
        Rigid { t: [self.t[0] + r[0], self.t[1] + r[1], self.t[2] + r[2]], q: hamilton(self.q, other.q) }
    }

    /// The inverse transform: `self.inverse().then(self)` is the identity.
    pub fn inverse(&self) -> Rigid {
        let [x, y, z, w] = self.q;
        let inv = Rigid { t: [0.0; 3], q: [-x, -y, -z, w] };
        let t = inv.rotate(self.t);
        Rigid { t: [-t[0], -t[1], -t[2]], q: inv.q }
    }

    /// A point of this frame in the outer frame.
    pub fn apply(&self, p: [f64; 3]) -> [f64; 3] {
        let r = self.rotate(p);
        [self.t[0] + r[0], self.t[1] + r[1], self.t[2] + r[2]]
    }

    /// A vector of this frame in the outer frame (rotation only).
    pub fn rotate(&self, v: [f64; 3]) -> [f64; 3] {
        let m = self.matrix();
        [0, 1, 2].map(|i| m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2])
    }

    /// The rotation matrix `R(q)` (see the module's formula); its columns are this frame's axes.
    pub fn matrix(&self) -> [[f64; 3]; 3] {
        let [x, y, z, w] = self.q;
        [
            [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - z * w), 2.0 * (x * z + y * w)],
            [2.0 * (x * y + z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - x * w)],
            [2.0 * (x * z - y * w), 2.0 * (y * z + x * w), 1.0 - 2.0 * (x * x + y * y)],
        ]
    }

    /// The rotation matrix, row-major (what `dmp.v1.Obstacle.rotation` holds).
    pub fn matrix_row_major(&self) -> Vec<f64> {
        self.matrix().iter().flatten().copied().collect()
    }
}

/// The Hamilton product `a b` of quaternions `x, y, z, w`.
fn hamilton(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    let [ax, ay, az, aw] = a;
    let [bx, by, bz, bw] = b;
    [
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: [f64; 3], b: [f64; 3]) -> bool {
        a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12)
    }

    #[test]
    fn a_quarter_turn_about_z_maps_x_to_y() {
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let r = Rigid::new([1.0, 2.0, 3.0], [0.0, 0.0, h, h], "pose").unwrap();
        assert!(close(r.rotate([1.0, 0.0, 0.0]), [0.0, 1.0, 0.0]));
        assert!(close(r.apply([1.0, 0.0, 0.0]), [1.0, 3.0, 3.0]));
        // Twice is a half turn; composition agrees with applying one after the other.
        let twice = r.then(&r);
        assert!(close(twice.apply([1.0, 0.0, 0.0]), r.apply(r.apply([1.0, 0.0, 0.0]))));
        assert!(close(twice.rotate([1.0, 0.0, 0.0]), [-1.0, 0.0, 0.0]));
        for q in [r.q, twice.q, [0.3, -0.5, 0.1, 0.8]] {
            let a = Rigid::new([0.0; 3], q, "q").unwrap();
            let b = Rigid::from_matrix([0.0; 3], a.matrix());
            let m = (a.matrix(), b.matrix());
            assert!((0..3).all(|i| close(m.0[i], m.1[i])), "{q:?}");
        }
        let back = r.inverse().then(&r);
        assert!(close(back.t, [0.0; 3]) && close(back.rotate([0.3, 0.2, 0.1]), [0.3, 0.2, 0.1]));
    }

    #[test]
    fn quaternions_are_normalised_and_zero_is_refused() {
        let r = Rigid::new([0.0; 3], [0.0, 0.0, 0.0, 2.0], "pose").unwrap();
        assert_eq!(r.q, [0.0, 0.0, 0.0, 1.0]);
        let e = Rigid::new([0.0; 3], [0.0; 4], "primitive_poses[1]").unwrap_err();
        assert_eq!(e.field, "primitive_poses[1].orientation");
        assert!(Rigid::new([f64::NAN, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0], "pose").is_err());
    }
}
