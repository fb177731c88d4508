//! Agreement with brute force: dense sampling and the compass-search reference, in two to four dimensions.

use super::*;

#[test]
fn ellipse_matches_dense_sampling() {
    let (a, b) = (0.4, 0.15);
    let e = sq(&[a, b], &[1.0, 1.0]);
    let n = 200_000;
    let dense: Vec<[f64; 2]> = (0..n)
        .map(|k| {
            let th = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
            [a * th.cos(), b * th.sin()]
        })
        .collect();
    let mut rng = Rng(11);
    for k in 0..60 {
        let y = if k % 2 == 0 {
            let s = rng.uniform(0.0, 1.0);
            [rng.uniform(-a, a) * s, rng.uniform(-b, b) * s]
        } else {
            [rng.uniform(-2.0, 2.0), rng.uniform(-2.0, 2.0)]
        };
        let brute = dense.iter().map(|z| dist2(z, &y)).fold(f64::INFINITY, f64::min).sqrt();
        let got = signed_distance(&e, &y);
        assert_eq!(got < 0.0, e.value(&y) < 0.0);
        // The dense minimum is within ~1e-10 of the truth and never below it.
        assert!(got.abs() <= brute + 1e-12, "at {y:?}: {got} vs brute force {brute}");
        assert!(brute - got.abs() < 1e-9, "at {y:?}: {got} vs brute force {brute}");
    }
}

#[test]
fn two_dimensional_superquadrics_match_brute_force() {
    for (shape, seed) in [
        (sq(&[0.4, 0.15], &[1.0, 1.0]), 1),
        (sq(&[0.3, 0.2], &[2.0, 2.0]), 2),
        (sq(&[0.3, 0.1], &[4.0, 4.0]), 3),
        (sq(&[0.01, 0.02], &[3.0, 3.0]), 4),
        (sq(&[2.0, 0.05], &[1.0, 2.5]), 5),
    ] {
        check_against_reference(&shape, 20_000, 60, seed);
    }
}

#[test]
fn rounded_box_matches_brute_force() {
    check_against_reference(&sq(&[0.3, 0.2, 0.5], &[2.0, 2.0, 2.0]), 100_000, 40, 21);
    check_against_reference(&sq(&[0.05, 0.3, 0.1], &[4.0, 4.0, 4.0]), 100_000, 40, 22);
    check_against_reference(&sq(&[0.05, 0.05, 0.2], &[1.0, 1.0, 2.0]), 100_000, 40, 23);
}

#[test]
fn nested_superquadric_matches_brute_force() {
    let shape = Shape::Nested(NestedSuperquadric::new([0.3, 0.2, 0.5], 2.0, 3.0).unwrap());
    check_against_reference(&shape, 100_000, 40, 31);
    let shape = Shape::Nested(NestedSuperquadric::new([0.02, 0.01, 0.015], 3.0, 1.5).unwrap());
    check_against_reference(&shape, 100_000, 30, 32);
}

#[test]
fn four_dimensional_superquadric_matches_brute_force() {
    check_against_reference(&sq(&[1.0, 0.4, 0.7, 0.2], &[1.5, 3.0, 1.0, 2.0]), 200_000, 20, 41);
}
