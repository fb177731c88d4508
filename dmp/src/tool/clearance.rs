//! How far a held tool is from an obstacle: the smallest signed distance of samples of the tool's surface, posed,
//! to the obstacle's surface (negative inside). A measurement for reports and plots, not a term of the field: the
//! true clearance may be smaller than the sampled one by up to the samples' spacing.

use nalgebra::{UnitQuaternion, Vector3};

use super::{ControlPoints, Tool};
use crate::distance::signed_distance_world;
use crate::obstacle::Obstacle;

/// `count` samples of the tool's surface in the tool frame (its offset included), in the nearly uniform directions of
/// [`ControlPoints::Surface`].
pub fn surface_samples(tool: &Tool, count: usize) -> Vec<Vector3<f64>> {
    let offset = tool.offset();
    ControlPoints::Surface { count }.sample(tool.shape()).into_iter().map(|r| r + offset).collect()
}

/// The smallest signed distance, at time `t`, of the tool-frame `samples` with the tool frame at `position` turned
/// by `q`, to `obstacle` (3-D).
pub fn sampled_clearance(
    samples: &[Vector3<f64>],
    position: &Vector3<f64>,
    q: &UnitQuaternion<f64>,
    obstacle: &Obstacle,
    t: f64,
) -> f64 {
    samples
        .iter()
        .map(|s| {
            let w = position + q * s;
            signed_distance_world(obstacle, w.as_slice(), t)
        })
        .fold(f64::INFINITY, f64::min)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::isopotential::{Shape, Superquadric};

    #[test]
    fn a_ball_tool_beside_a_ball_obstacle_is_the_gap_between_them() {
        let ball = |r: f64| Shape::Superquadric(Superquadric::new(vec![r; 3], vec![1.0; 3]).unwrap());
        let tool = Tool::new(ball(0.1), [0.0; 3], ControlPoints::default()).unwrap();
        let obstacle = Obstacle::new("o", ball(0.2), vec![1.0, 0.0, 0.0], None, None).unwrap();
        let samples = surface_samples(&tool, 2000);
        let q = UnitQuaternion::from_scaled_axis(Vector3::new(0.3, -0.2, 1.0));
        let d = sampled_clearance(&samples, &Vector3::zeros(), &q, &obstacle, 0.0);
        // 1 - 0.1 - 0.2, less what the samples miss of the nearest point (a few mm at 2,000 samples).
        assert!((0.7 - 1e-9..0.705).contains(&d), "{d}");
        // Moved into the obstacle: negative.
        let inside = sampled_clearance(&samples, &Vector3::new(0.85, 0.0, 0.0), &q, &obstacle, 0.0);
        assert!(inside < 0.0, "{inside}");
    }
}
