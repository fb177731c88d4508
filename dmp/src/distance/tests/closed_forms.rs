//! Shapes whose distances are known in closed form: circles, spheres, an ellipse's axes, boxes on their
//! axes, surface points, the centre, one dimension.

use super::*;

#[test]
fn circle_and_sphere_are_closed_form() {
    let mut rng = Rng(7);
    let shapes = [
        (sq(&[0.3, 0.3], &[1.0, 1.0]), 0.3),
        (sq(&[0.01, 0.01], &[1.0, 1.0]), 0.01),
        (sq(&[1.5, 1.5, 1.5], &[1.0, 1.0, 1.0]), 1.5),
        (Shape::Nested(NestedSuperquadric::new([0.2, 0.2, 0.2], 1.0, 1.0).unwrap()), 0.2),
    ];
    for (shape, r) in &shapes {
        let d = shape.dim();
        for k in 0..40 {
            let radius = if k % 2 == 0 { rng.uniform(0.0, *r) } else { rng.uniform(*r, 3.0) };
            let y: Vec<f64> = rng.direction(d).iter().map(|x| x * radius).collect();
            let want = norm(&y) - r;
            let got = signed_distance(shape, &y);
            assert!((got - want).abs() < 1e-12, "{shape:?} at {y:?}: {got} vs {want}");
        }
    }
}

#[test]
fn ellipse_axes_are_known() {
    let (a, b) = (0.5, 0.2);
    let e = sq(&[a, b], &[1.0, 1.0]);
    let check = |y: [f64; 2], want: f64| {
        let got = signed_distance(&e, &y);
        assert!((got - want).abs() < 1e-10, "at {y:?}: {got} vs {want}");
    };
    // Outside on the axes: the nearest vertex.
    for x in [0.5001, 0.7, 2.0, 3.5] {
        check([x, 0.0], x - a);
        check([-x, 0.0], x - a);
    }
    for y in [0.2001, 0.5, 3.0] {
        check([0.0, y], y - b);
        check([0.0, -y], y - b);
    }
    // Inside on the major axis: b sqrt(1 - x^2 / (a^2 - b^2)) while |x| <= (a^2 - b^2) / a, then a - |x|.
    let knee = (a * a - b * b) / a;
    for x in [0.0, 0.1, 0.3, 0.41, knee, 0.43, 0.49, 0.4999] {
        let want = if x <= knee { b * (1.0 - x * x / (a * a - b * b)).sqrt() } else { a - x };
        check([x, 0.0], -want);
        check([-x, 0.0], -want);
    }
    // Inside on the minor axis: the co-vertex.
    for y in [0.0, 0.05, 0.19, 0.1999] {
        check([0.0, y], -(b - y));
        check([0.0, -y], -(b - y));
    }
}

#[test]
fn boxes_on_their_axes() {
    let shape = sq(&[0.3, 0.2, 0.5], &[4.0, 4.0, 4.0]);
    for (i, a) in [0.3, 0.2, 0.5].iter().enumerate() {
        for x in [a + 1e-4, a + 0.3, 2.5] {
            let mut y = vec![0.0; 3];
            y[i] = -x;
            assert!((signed_distance(&shape, &y) - (x - a)).abs() < 1e-12);
        }
    }
    // Inside on the short axis, the nearest face is straight ahead.
    assert!((signed_distance(&shape, &[0.0, 0.15, 0.0]) + 0.05).abs() < 1e-12);
}

#[test]
fn surface_points_are_at_distance_zero() {
    let shapes = [
        sq(&[0.3, 0.2], &[1.0, 1.0]),
        sq(&[0.3, 0.2], &[4.0, 2.0]),
        sq(&[0.3, 0.2, 0.5], &[2.0, 2.0, 2.0]),
        sq(&[0.01, 0.3, 0.2], &[1.0, 3.5, 1.2]),
        Shape::Nested(NestedSuperquadric::new([0.3, 0.2, 0.5], 2.0, 3.0).unwrap()),
        sq(&[1.0, 0.4, 0.7, 0.2], &[1.5, 3.0, 1.0, 2.0]),
    ];
    let mut rng = Rng(3);
    for shape in &shapes {
        let d = shape.dim();
        let mut z = vec![0.0; d];
        for _ in 0..30 {
            shape.surface_point(&rng.direction(d), &mut z);
            let got = signed_distance(shape, &z);
            assert!(got.abs() < 1e-12, "{shape:?} at {z:?}: {got}");
        }
    }
}

#[test]
fn the_centre_is_at_minus_the_smallest_semi_axis() {
    // Every shape contains the ball of radius a_min, which touches the surface at +- a_min e_min.
    let shapes = [
        sq(&[0.3, 0.2], &[1.0, 1.0]),
        sq(&[0.3, 0.3], &[1.0, 1.0]),
        sq(&[0.3, 0.2, 0.5], &[4.0, 4.0, 4.0]),
        sq(&[0.5, 0.5, 0.5], &[2.0, 2.0, 2.0]),
        Shape::Nested(NestedSuperquadric::new([0.3, 0.2, 0.5], 2.0, 3.0).unwrap()),
        sq(&[1.0, 0.4, 0.7, 0.2], &[1.5, 3.0, 1.0, 2.0]),
        sq(&[0.7], &[2.0]),
    ];
    for shape in &shapes {
        let y = vec![0.0; shape.dim()];
        let a_min = shape.semi_axes().iter().fold(f64::INFINITY, |m, a| m.min(*a));
        let got = signed_distance(shape, &y);
        assert!(got.is_finite() && got < 0.0);
        assert!((got + a_min).abs() < 1e-12, "{shape:?}: {got}");
    }
}

#[test]
fn one_dimensional_is_closed_form() {
    let s = sq(&[0.4], &[3.0]);
    for (y, want) in [(0.0, -0.4), (0.1, -0.3), (-0.3, -0.1), (0.4, 0.0), (-1.4, 1.0), (2.0, 1.6)] {
        assert!((signed_distance(&s, &[y]) - want).abs() < 1e-15);
    }
}
