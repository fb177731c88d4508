//! True shapes of obstacles: what is really there (a box, a ball, a cylinder, a point cloud), as opposed to the
//! inflated superquadric the robot avoids. Surface samples for drawing, signed distance for the clearance.

use dmp::Obstacle;

use super::outline::OUTLINE_SAMPLES_ND;

/// The kind and size of a true shape. Sizes in metres; a 2-D robot uses the first two coordinates of a 3-D size.
#[derive(Debug, Clone, PartialEq)]
pub enum SolidShape {
    /// A box of these half-extents along the axes (2 or 3 of them).
    Box {
        /// Half-extents.
        half: Vec<f64>,
    },
    /// A ball (a disc in 2-D).
    Ball {
        /// Radius.
        radius: f64,
    },
    /// A cylinder standing on the `z` axis (a disc in 2-D).
    CylinderZ {
        /// Radius.
        radius: f64,
        /// Half of its height.
        half_height: f64,
    },
    /// Points, as offsets from the centre (each of the robot's dimension): a perception node's cloud.
    Points(Vec<Vec<f64>>),
    /// A superquadric that is the true shape itself (an obstacle given as one, before any margin); its own centre,
    /// rotation and velocity apply, not the [`Solid`]'s.
    Superquadric(Obstacle),
}

/// A true shape placed in robot space, present during a time window of the run.
#[derive(Debug, Clone, PartialEq)]
pub struct Solid {
    /// The obstacle's id.
    pub id: String,
    /// Kind and size.
    pub shape: SolidShape,
    /// Centre at time 0, one value per dimension of the robot (2 or 3).
    pub center: Vec<f64>,
    /// Constant velocity of the centre (empty: still).
    pub velocity: Vec<f64>,
    /// Present from this time on, seconds.
    pub from: f64,
    /// Present until this time, seconds (infinity: to the end).
    pub until: f64,
}

impl Solid {
    /// A still solid, always present.
    pub fn new(id: impl Into<String>, shape: SolidShape, center: Vec<f64>) -> Self {
        Self {
            id: id.into(),
            shape,
            center,
            velocity: Vec::new(),
            from: f64::NEG_INFINITY,
            until: f64::INFINITY,
        }
    }

    /// Present at `t`.
    pub(crate) fn present_at(&self, t: f64) -> bool {
        t >= self.from && t < self.until
    }

    pub(crate) fn moving(&self) -> bool {
        match &self.shape {
            SolidShape::Superquadric(o) => o.velocity().iter().any(|v| *v != 0.0),
            _ => self.velocity.iter().any(|v| *v != 0.0),
        }
    }

    fn center_at(&self, t: f64) -> Vec<f64> {
        self.center
            .iter()
            .enumerate()
            .map(|(i, c)| c + self.velocity.get(i).copied().unwrap_or(0.0) * t)
            .collect()
    }

    /// Signed distance from `x` to the surface at time `t` (negative inside).
    pub(crate) fn signed_distance(&self, x: &[f64], t: f64) -> f64 {
        let c = self.center_at(t);
        let y: Vec<f64> = x.iter().zip(&c).map(|(a, b)| a - b).collect();
        let d = y.len();
        let norm = |v: &[f64]| v.iter().map(|a| a * a).sum::<f64>().sqrt();
        match &self.shape {
            SolidShape::Ball { radius } => norm(&y) - radius,
            SolidShape::Box { half } => box_sdf(&y, half),
            SolidShape::CylinderZ { radius, half_height } => {
                if d < 3 {
                    norm(&y) - radius
                } else {
                    box_sdf(&[norm(&y[..2]), y[2]], &[*radius, *half_height])
                }
            }
            SolidShape::Points(points) => points
                .iter()
                .map(|p| y.iter().zip(p).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt())
                .fold(f64::INFINITY, f64::min),
            SolidShape::Superquadric(o) => dmp::distance::signed_distance_world(o, x, t),
        }
    }

    /// Surface samples at time `t`, absolute positions; for a point cloud its points.
    pub(crate) fn samples(&self, t: f64) -> Vec<Vec<f64>> {
        let c = self.center_at(t);
        let d = c.len();
        let circle = |r: f64, z: Option<f64>| -> Vec<Vec<f64>> {
            (0..96)
                .map(|k| {
                    let a = std::f64::consts::TAU * k as f64 / 96.0;
                    let mut p = vec![r * a.cos(), r * a.sin()];
                    if let Some(z) = z {
                        p.push(z);
                    }
                    p
                })
                .collect()
        };
        let offsets: Vec<Vec<f64>> = match &self.shape {
            SolidShape::Ball { radius } if d >= 3 => {
                let mut s = Vec::new();
                for (u, v, w) in [(0, 1, 2), (0, 2, 1), (1, 2, 0)] {
                    for p in circle(*radius, None) {
                        let mut q = vec![0.0; 3];
                        q[u] = p[0];
                        q[v] = p[1];
                        q[w] = 0.0;
                        s.push(q);
                    }
                }
                s
            }
            SolidShape::Ball { radius } => circle(*radius, None),
            SolidShape::CylinderZ { radius, half_height } if d >= 3 => {
                let mut s = circle(*radius, Some(-half_height));
                s.extend(circle(*radius, Some(*half_height)));
                s
            }
            SolidShape::CylinderZ { radius, .. } => circle(*radius, None),
            SolidShape::Box { half } => {
                let h: Vec<f64> = (0..d).map(|i| half.get(i).copied().unwrap_or(0.0)).collect();
                (0..1usize << d)
                    .map(|m| (0..d).map(|i| if m >> i & 1 == 1 { h[i] } else { -h[i] }).collect())
                    .collect()
            }
            SolidShape::Points(points) => points.clone(),
            SolidShape::Superquadric(o) => {
                let mut oc = vec![0.0; o.dim()];
                o.center_at(t, &mut oc);
                let n = OUTLINE_SAMPLES_ND;
                return o
                    .boundary_offsets(n)
                    .chunks(o.dim())
                    .map(|p| p.iter().zip(&oc).map(|(a, b)| a + b).collect())
                    .collect();
            }
        };
        offsets.iter().map(|o| o.iter().zip(&c).map(|(a, b)| a + b).collect()).collect()
    }
}

/// Signed distance of `y` to the box of half-extents `half` about the origin.
fn box_sdf(y: &[f64], half: &[f64]) -> f64 {
    let q: Vec<f64> =
        y.iter().enumerate().map(|(i, v)| v.abs() - half.get(i).copied().unwrap_or(0.0)).collect();
    let outside = q.iter().map(|v| v.max(0.0).powi(2)).sum::<f64>().sqrt();
    let inside = q.iter().copied().fold(f64::NEG_INFINITY, f64::max).min(0.0);
    outside + inside
}
