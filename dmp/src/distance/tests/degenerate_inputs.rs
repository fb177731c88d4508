//! Degenerate and non-finite points: finite, exact where defined.

use super::*;

#[test]
fn degenerate_points_stay_finite_and_exact() {
    let shapes = [
        Shape::Nested(NestedSuperquadric::new([0.3, 0.2, 0.5], 3.0, 1.5).unwrap()),
        Shape::Nested(NestedSuperquadric::new([0.3, 0.3, 0.5], 1.0, 4.0).unwrap()),
        sq(&[0.3, 0.2, 0.5], &[10.0, 10.0, 10.0]),
        sq(&[0.01, 0.2, 0.05], &[1.0, 7.5, 2.0]),
    ];
    let points: [[f64; 3]; 9] = [
        [0.0, 0.0, 1e-300],
        [1e-200, -1e-210, 0.0],
        [0.0, 0.0, 0.7],
        [0.0, 0.0, -0.3],
        [1e-120, 0.0, 0.45],
        [0.0, 1e-160, 2.0],
        [0.05, 0.02, 0.0],
        [3.0, -2.0, 1.0],
        [1e6, 0.0, 0.0],
    ];
    for shape in &shapes {
        let dense = dense_samples(shape, 20_000);
        for y in &points {
            let (sd, z) = nearest_surface_point(shape, y);
            assert!(sd.is_finite() && z.iter().all(|v| v.is_finite()), "{shape:?} at {y:?}: {sd}");
            assert!(shape.value(&z).abs() < 1e-12);
            if norm(y) < 10.0 {
                let reference = reference(shape, &dense, y);
                assert!((sd.abs() - reference).abs() < 1e-7, "{shape:?} at {y:?}: {sd} vs {reference}");
            }
        }
    }
}

#[test]
fn non_finite_inputs() {
    let s = sq(&[0.3, 0.2], &[1.0, 1.0]);
    assert!(signed_distance(&s, &[f64::NAN, 0.0]).is_nan());
    assert_eq!(signed_distance(&s, &[f64::INFINITY, 0.0]), f64::INFINITY);
}
