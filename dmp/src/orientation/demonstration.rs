//! One demonstration of an orientation: sample times and unit quaternions, checked and made sign-consistent.

use nalgebra::UnitQuaternion;

use super::quaternion::from_xyzw;
use crate::error::Result;
use crate::learn::check_samples;

/// An orientation demonstration: at least 3 strictly increasing, finite sample times (any start, not necessarily
/// uniform) and one unit quaternion per sample.
///
/// The quaternions are made sign-consistent on construction: `q` and `-q` are the same orientation, and a recorder
/// may flip between them (many do, to keep `w >= 0`), so each sample whose 4-dot product with the one before is
/// negative is negated. The first sample keeps its sign, and the goal is the last sample in the sign its
/// neighbours give it: the demonstration's rotation from start to goal is the one the demonstrator made.
#[derive(Debug, Clone, PartialEq)]
pub struct OrientationDemonstration {
    t: Vec<f64>,
    q: Vec<UnitQuaternion<f64>>,
}

impl OrientationDemonstration {
    /// Checks and wraps the samples; `q[i]` is `[x, y, z, w]`, finite and of norm 1 within
    /// [`super::quaternion::UNIT_TOLERANCE`] (it is renormalised). The errors name `demonstration.t[i]` or
    /// `demonstration.q[i]`.
    ///
    /// ```
    /// use dmp::OrientationDemonstration;
    /// let (c, s) = (0.25f64.cos(), 0.25f64.sin());
    /// let q = vec![[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, -s, -c], [0.0, 0.0, (2.0 * 0.25f64).sin(), (0.5f64).cos()]];
    /// let demo = OrientationDemonstration::new(vec![0.0, 0.5, 1.0], q).unwrap();
    /// assert!(demo.quaternions()[1].w > 0.0); // the flipped sample was negated back
    /// assert!(OrientationDemonstration::new(vec![0.0, 1.0], vec![[0.0, 0.0, 0.0, 1.0]; 2]).is_err());
    /// ```
    pub fn new(t: Vec<f64>, q: Vec<[f64; 4]>) -> Result<Self> {
        check_samples(&t, q.len(), "demonstration.q", "quaternion")?;
        let mut out: Vec<UnitQuaternion<f64>> = Vec::with_capacity(q.len());
        for (i, raw) in q.into_iter().enumerate() {
            let mut qi = from_xyzw(&format!("demonstration.q[{i}]"), raw)?;
            if let Some(prev) = out.last()
                && qi.coords.dot(&prev.coords) < 0.0
            {
                qi = UnitQuaternion::new_unchecked(-qi.into_inner());
            }
            out.push(qi);
        }
        Ok(Self { t, q: out })
    }

    /// Sample times.
    pub fn times(&self) -> &[f64] {
        &self.t
    }

    /// The quaternions, sign-consistent.
    pub fn quaternions(&self) -> &[UnitQuaternion<f64>] {
        &self.q
    }

    /// The first orientation.
    pub fn start(&self) -> UnitQuaternion<f64> {
        self.q[0]
    }

    /// The last orientation, in the sign the demonstration reaches it with.
    pub fn goal(&self) -> UnitQuaternion<f64> {
        self.q[self.q.len() - 1]
    }

    /// Duration, last time minus first.
    pub fn duration(&self) -> f64 {
        self.t[self.t.len() - 1] - self.t[0]
    }
}
