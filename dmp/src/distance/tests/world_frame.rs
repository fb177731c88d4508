//! The distance in the world frame: the obstacle's pose and velocity move and rotate the point.

use super::*;

#[test]
fn world_frame_moves_and_rotates_the_point() {
    let shape = sq(&[0.3, 0.1, 0.2], &[2.0, 1.0, 3.0]);
    let (c, s) = (0.6_f64.cos(), 0.6_f64.sin());
    let rows = vec![vec![c, -s, 0.0], vec![s, c, 0.0], vec![0.0, 0.0, 1.0]];
    let o = Obstacle::new(
        "o",
        shape.clone(),
        vec![0.2, -0.1, 0.4],
        Some(rows.clone()),
        Some(vec![0.1, 0.0, -0.2]),
    )
    .unwrap();
    let t = 1.5;
    let centre = [0.2 + 0.1 * t, -0.1, 0.4 - 0.2 * t];
    for y in [[0.0, 0.0, 0.0], [0.5, 0.2, -0.1], [0.1, 0.05, 0.1], [-2.0, 1.0, 0.5]] {
        // x = c(t) + R y.
        let x: Vec<f64> =
            (0..3).map(|i| centre[i] + (0..3).map(|k| rows[i][k] * y[k]).sum::<f64>()).collect();
        let got = signed_distance_world(&o, &x, t);
        let want = signed_distance(&shape, &y);
        assert!((got - want).abs() < 1e-12, "{got} vs {want}");
    }
}
