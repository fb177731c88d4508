//! The held tool: its shape in the tool frame, its control points and their inertia.

use nalgebra::{Matrix3, SymmetricEigen, Vector3};

use super::sampling::ControlPoints;
use crate::error::{InvalidInput, Result, ensure_finite};
use crate::isopotential::{Isopotential, Shape};

/// Eigenvalues of the inertia below this fraction of the largest are taken as zero (the axis of a tool sampled on
/// its axis, about which no term can turn it).
const INERTIA_RANK_TOLERANCE: f64 = 1e-9;

/// A tool or held object attached to the end effector: a superquadric in the tool frame (the frame of the pose
/// `q`, origin at the controlled point `p`), and the points the repulsive terms act on.
///
/// The shape is centred at `offset` with its axes along the tool frame's; a bar held at its middle has offset 0.
#[derive(Debug, Clone, PartialEq)]
pub struct Tool {
    shape: Shape,
    offset: Vector3<f64>,
    sampling: ControlPoints,
    points: Vec<Vector3<f64>>,
    inertia: Matrix3<f64>,
    inertia_inv: Matrix3<f64>,
}

impl Tool {
    /// A tool of `shape` (3-D) centred at `offset` in the tool frame, sampled by `sampling`. Errors name
    /// `tool.shape`, `tool.offset[i]`, `tool.control_points.count`.
    pub fn new(shape: Shape, offset: [f64; 3], sampling: ControlPoints) -> Result<Self> {
        if shape.dim() != 3 {
            return Err(InvalidInput::new(
                "tool.shape.semi_axes",
                format!("a tool is a 3-D shape: must have 3 entries, found {}", shape.dim()),
            )
            .into());
        }
        for (i, o) in offset.iter().enumerate() {
            ensure_finite(|| format!("tool.offset[{i}]"), *o)?;
        }
        sampling.validate("tool.control_points")?;
        let offset = Vector3::from(offset);
        let points: Vec<Vector3<f64>> = sampling.sample(&shape).into_iter().map(|r| r + offset).collect();
        let inertia = inertia(&points);
        let inertia_inv = pseudo_inverse(&inertia);
        Ok(Self { shape, offset, sampling, points, inertia, inertia_inv })
    }

    /// The shape, in its own frame (centre at the origin).
    pub fn shape(&self) -> &Shape {
        &self.shape
    }

    /// The shape's centre in the tool frame.
    pub fn offset(&self) -> Vector3<f64> {
        self.offset
    }

    /// How it is sampled.
    pub fn sampling(&self) -> ControlPoints {
        self.sampling
    }

    /// The control points `r_i`, tool frame.
    pub fn control_points(&self) -> &[Vector3<f64>] {
        &self.points
    }

    /// The inertia `I` of the control points about the tool origin, tool frame (see [`inertia`]).
    #[cfg(test)]
    pub(crate) fn inertia(&self) -> &Matrix3<f64> {
        &self.inertia
    }

    /// Its (pseudo-)inverse, tool frame.
    pub(crate) fn inertia_inverse(&self) -> &Matrix3<f64> {
        &self.inertia_inv
    }
}

/// The inertia of a unit mass spread evenly over `points`, about the origin.
///
/// # Formula
/// `I = (1 / N) sum_i (|r_i|² 1 - r_i r_iᵀ)`: symmetric, positive semi-definite; `I ω` is the angular momentum of
/// the points turning at `ω`. In m² (per unit mass).
///
/// ```
/// use dmp::tool::inertia;
/// use nalgebra::Vector3;
/// // The two tips of a 0.6 m bar along x: nothing about x, 0.09 m² about y and z.
/// let i = inertia(&[Vector3::new(-0.3, 0.0, 0.0), Vector3::new(0.3, 0.0, 0.0)]);
/// assert!(i[(0, 0)].abs() < 1e-15 && (i[(1, 1)] - 0.09).abs() < 1e-15 && (i[(2, 2)] - 0.09).abs() < 1e-15);
/// ```
pub fn inertia(points: &[Vector3<f64>]) -> Matrix3<f64> {
    let mut m = Matrix3::zeros();
    for r in points {
        m += Matrix3::identity() * r.norm_squared() - r * r.transpose();
    }
    m / points.len().max(1) as f64
}

/// The Moore–Penrose inverse of a symmetric positive semi-definite matrix: eigenvalues below
/// [`INERTIA_RANK_TOLERANCE`] times the largest are dropped (their directions get no angular acceleration).
fn pseudo_inverse(m: &Matrix3<f64>) -> Matrix3<f64> {
    let e = SymmetricEigen::new(*m);
    let largest = e.eigenvalues.iter().copied().fold(0.0, f64::max);
    let mut out = Matrix3::zeros();
    for k in 0..3 {
        let l = e.eigenvalues[k];
        if largest > 0.0 && l > INERTIA_RANK_TOLERANCE * largest {
            let u = e.eigenvectors.column(k);
            out += u * u.transpose() / l;
        }
    }
    out
}
