//! Accuracy of the signed distance against closed forms and brute force.
use super::*;
use crate::directions::unit_directions;
use crate::isopotential::{NestedSuperquadric, Superquadric};

/// A small deterministic generator (xorshift64*), uniform in `[lo, hi)`.
struct Rng(u64);

impl Rng {
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let bits = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11;
        lo + (hi - lo) * (bits as f64 / (1u64 << 53) as f64)
    }

    fn direction(&mut self, d: usize) -> Vec<f64> {
        loop {
            let v: Vec<f64> = (0..d).map(|_| self.uniform(-1.0, 1.0)).collect();
            let n = norm(&v);
            if n > 1e-3 && n <= 1.0 {
                return v.iter().map(|x| x / n).collect();
            }
        }
    }
}

fn sq(a: &[f64], n: &[f64]) -> Shape {
    Shape::Superquadric(Superquadric::new(a.to_vec(), n.to_vec()).unwrap())
}

/// The radial projection by plain bisection on `C(s v) = 0` (independent of the code under test).
fn radial_bisection(shape: &Shape, v: &[f64]) -> Vec<f64> {
    let at = |s: f64| v.iter().map(|x| s * x).collect::<Vec<f64>>();
    let (mut lo, mut hi) = (0.0, 1.0);
    while shape.value(&at(hi)) < 0.0 {
        hi *= 2.0;
    }
    for _ in 0..80 {
        let mid = 0.5 * (lo + hi);
        if shape.value(&at(mid)) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    at(0.5 * (lo + hi))
}

/// Brute force: the nearest of `samples`, then a derivative-free compass search over radial directions from
/// the best few distinct samples. An upper bound of the true unsigned distance.
fn reference(shape: &Shape, samples: &[Vec<f64>], y: &[f64]) -> f64 {
    let d = y.len();
    let length = shape.semi_axes().iter().fold(0.0_f64, |m, a| m.max(*a));
    let mut order: Vec<(f64, usize)> = samples.iter().enumerate().map(|(i, s)| (dist2(s, y), i)).collect();
    order.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut starts: Vec<&Vec<f64>> = Vec::new();
    for &(_, i) in &order {
        if starts.len() == 3 {
            break;
        }
        if starts.iter().all(|s| dist2(s, &samples[i]).sqrt() > 0.05 * length) {
            starts.push(&samples[i]);
        }
    }
    let mut best = order[0].0;
    for start in starts {
        let mut v = start.clone();
        let mut f = dist2(&radial_bisection(shape, &v), y);
        let mut h = 0.02 * length;
        let mut iterations = 0;
        while h > 1e-12 * length && iterations < 5000 {
            iterations += 1;
            let mut improved = false;
            for i in 0..d {
                for s in [1.0, -1.0] {
                    let mut trial = v.clone();
                    trial[i] += s * h;
                    let ft = dist2(&radial_bisection(shape, &trial), y);
                    if ft < f {
                        (v, f, improved) = (trial, ft, true);
                    }
                }
            }
            if improved {
                h *= 1.5;
            } else {
                h *= 0.5;
            }
        }
        best = best.min(f);
    }
    best.sqrt()
}

/// `n` surface points from the shape's own parametrization.
fn dense_samples(shape: &Shape, n: usize) -> Vec<Vec<f64>> {
    let d = shape.dim();
    unit_directions(d, n)
        .iter()
        .map(|w| {
            let mut z = vec![0.0; d];
            shape.surface_point(w, &mut z);
            z
        })
        .collect()
}

/// Test points: inside (shrunk surface points, including near the centre), near the surface on both sides,
/// near corners (diagonal directions), and outside up to a few metres.
fn test_points(shape: &Shape, count: usize, seed: u64) -> Vec<Vec<f64>> {
    let d = shape.dim();
    let mut rng = Rng(seed);
    let mut points = Vec::new();
    for k in 0..count {
        let w = if k % 4 == 0 {
            // Near a corner: all components of similar size.
            let v: Vec<f64> = (0..d)
                .map(|_| rng.uniform(0.8, 1.0) * if rng.uniform(0.0, 1.0) < 0.5 { -1.0 } else { 1.0 })
                .collect();
            let n = norm(&v);
            v.iter().map(|x| x / n).collect()
        } else {
            rng.direction(d)
        };
        let mut z = vec![0.0; d];
        shape.surface_point(&w, &mut z);
        let s = match k % 6 {
            0 => rng.uniform(0.0, 0.3),
            1 => rng.uniform(0.3, 0.99),
            2 => rng.uniform(0.99, 1.01),
            3 => rng.uniform(1.01, 2.0),
            _ => rng.uniform(2.0, 3.0 / norm(&z)),
        };
        points.push(z.iter().map(|x| s * x).collect());
    }
    points
}

/// Points built axis by axis: on a medial plane, just inside or outside a face, or anywhere within the box:
/// near edges, corners and medial planes, where several local minima compete.
fn adversarial_points(shape: &Shape, count: usize, seed: u64) -> Vec<Vec<f64>> {
    let mut rng = Rng(seed);
    let a = shape.semi_axes().to_vec();
    let a_min = a.iter().fold(f64::INFINITY, |m, v| m.min(*v));
    (0..count)
        .map(|_| {
            a.iter()
                .map(|&ai| {
                    let sign = if rng.uniform(0.0, 1.0) < 0.5 { -1.0 } else { 1.0 };
                    let small = a_min * 10f64.powf(rng.uniform(-4.0, 0.0));
                    match (rng.uniform(0.0, 5.0)) as usize {
                        0 => 0.0,
                        1 => sign * (ai - small).max(0.0),
                        2 => sign * (ai + small),
                        _ => rng.uniform(-ai, ai),
                    }
                })
                .collect()
        })
        .collect()
}

/// Compares against the brute-force reference at test and adversarial points; also checks that the nearest
/// point lies on the surface and that the sign is right.
fn check_against_reference(shape: &Shape, samples: usize, count: usize, seed: u64) {
    let dense = dense_samples(shape, samples);
    let mut points = test_points(shape, count, seed);
    points.extend(adversarial_points(shape, count, seed + 1));
    for y in points {
        let (sd, z) = nearest_surface_point(shape, &y);
        assert!(sd.is_finite(), "{y:?}");
        assert!(shape.value(&z).abs() < 1e-12, "nearest point off the surface: {z:?}");
        assert!((dist2(&z, &y).sqrt() - sd.abs()).abs() < 1e-14);
        let c = shape.value(&y);
        if c.abs() > 1e-12 {
            assert_eq!(sd < 0.0, c < 0.0, "sign at {y:?}");
        }
        let reference = reference(shape, &dense, &y);
        let diff = sd.abs() - reference;
        assert!(diff.abs() < 1e-7, "{shape:?} at {y:?}: distance {sd}, reference {reference}");
    }
}

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
fn one_dimensional_is_closed_form() {
    let s = sq(&[0.4], &[3.0]);
    for (y, want) in [(0.0, -0.4), (0.1, -0.3), (-0.3, -0.1), (0.4, 0.0), (-1.4, 1.0), (2.0, 1.6)] {
        assert!((signed_distance(&s, &[y]) - want).abs() < 1e-15);
    }
}

#[test]
fn non_finite_inputs() {
    let s = sq(&[0.3, 0.2], &[1.0, 1.0]);
    assert!(signed_distance(&s, &[f64::NAN, 0.0]).is_nan());
    assert_eq!(signed_distance(&s, &[f64::INFINITY, 0.0]), f64::INFINITY);
}

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

fn random_shape(rng: &mut Rng, d: usize) -> Shape {
    let axis = |rng: &mut Rng| 10f64.powf(rng.uniform(-2.0, 0.3));
    let exponent = |rng: &mut Rng| match (rng.uniform(0.0, 6.0)) as usize {
        0 => 1.0,
        1 => 2.0,
        2 => 3.0,
        3 => 4.0,
        _ => rng.uniform(1.0, 5.0),
    };
    if d == 3 && rng.uniform(0.0, 1.0) < 0.3 {
        let a = [axis(rng), axis(rng), axis(rng)];
        return Shape::Nested(NestedSuperquadric::new(a, exponent(rng), exponent(rng)).unwrap());
    }
    let a: Vec<f64> = (0..d).map(|_| axis(rng)).collect();
    let same = rng.uniform(0.0, 1.0) < 0.5;
    let e0 = exponent(rng);
    let n: Vec<f64> = (0..d).map(|_| if same { e0 } else { exponent(rng) }).collect();
    sq(&a, &n)
}

fn env_list(name: &str, default: &str) -> Vec<usize> {
    std::env::var(name).unwrap_or_else(|_| default.into()).split(',').map(|x| x.parse().unwrap()).collect()
}

/// Sweep: `STRESS_D=3 STRESS_N=4,6 cargo test -p dmp --release distance::tests::stress -- --ignored
/// --nocapture`; compares each setting with the best of all settings and a fine one.
#[test]
#[ignore]
fn stress() {
    let d = env_list("STRESS_D", "3")[0];
    let shapes = env_list("STRESS_SHAPES", "200")[0];
    let per_shape = env_list("STRESS_POINTS", "50")[0];
    let local = env_list("STRESS_N", &grid_intervals(d).to_string());
    let configs: Vec<Config> = local
        .iter()
        .map(|&n| Config { intervals: n, per_grid: GRID_CANDIDATES, levels: MAX_LEVELS })
        .collect();
    let fine = Config { intervals: 4 * grid_intervals(d), per_grid: 40, levels: 12 };
    let mut rng = Rng(12345);
    let mut worst = vec![(0.0_f64, String::new()); configs.len()];
    let mut bad = vec![0usize; configs.len()];
    let mut total = 0;
    let mut times = vec![0.0; configs.len()];
    for k in 0..shapes {
        let shape = random_shape(&mut rng, d);
        let mut points = test_points(&shape, per_shape, 1000 + k as u64);
        points.extend(adversarial_points(&shape, per_shape, 5000 + k as u64));
        for y in points {
            let fine_result = nearest_with(&shape, &y, fine).0;
            let results: Vec<f64> = configs
                .iter()
                .enumerate()
                .map(|(j, c)| {
                    let start = std::time::Instant::now();
                    let r = nearest_with(&shape, &y, *c).0;
                    times[j] += start.elapsed().as_secs_f64();
                    r
                })
                .collect();
            let reference = results.iter().fold(fine_result.abs(), |m, r| m.min(r.abs()));
            if fine_result.abs() - reference > 1e-9 {
                println!("fine missed by {:e}: {shape:?} y={y:?}", fine_result.abs() - reference);
            }
            total += 1;
            for (j, &got) in results.iter().enumerate() {
                let diff = got.abs() - reference;
                if diff.abs() > 1e-9 {
                    bad[j] += 1;
                }
                if diff.abs() > worst[j].0 {
                    worst[j] = (diff.abs(), format!("{shape:?} y={y:?} got={got} best={reference}"));
                }
            }
        }
    }
    for (j, c) in configs.iter().enumerate() {
        println!(
            "N={}: {:.1} us/call, {} of {total} differ by > 1e-9; worst {:e}: {}",
            c.intervals,
            times[j] / total as f64 * 1e6,
            bad[j],
            worst[j].0,
            worst[j].1
        );
    }
}

/// Against the independent compass-search reference over random shapes:
/// `cargo test -p dmp --release distance::tests::compass_sweep -- --ignored --nocapture`.
#[test]
#[ignore]
fn compass_sweep() {
    let mut rng = Rng(777);
    for d in [2, 3, 4] {
        let (mut worse, mut better, mut count) = (0.0_f64, 0.0_f64, 0);
        for k in 0..25 {
            let shape = random_shape(&mut rng, d);
            let dense = dense_samples(&shape, if d == 2 { 20_000 } else { 100_000 });
            let mut points = test_points(&shape, 20, 100 + k);
            points.extend(adversarial_points(&shape, 20, 200 + k));
            for y in points {
                let got = signed_distance(&shape, &y).abs();
                let reference = reference(&shape, &dense, &y);
                worse = worse.max(got - reference);
                better = better.max(reference - got);
                count += 1;
                if got - reference > 1e-9 {
                    println!("worse by {:e}: {shape:?} y={y:?}", got - reference);
                }
            }
        }
        println!(
            "d={d}: {count} points, ours above reference by at most {worse:e}, below by at most {better:e}"
        );
    }
}

/// Time per call: `cargo test -p dmp --release distance::tests::timing -- --ignored --nocapture`.
#[test]
#[ignore]
fn timing() {
    let shapes = [
        ("ellipse", sq(&[0.3, 0.2], &[1.0, 1.0])),
        ("box n=4 2-D", sq(&[0.3, 0.1], &[4.0, 4.0])),
        ("ellipsoid", sq(&[0.3, 0.2, 0.5], &[1.0, 1.0, 1.0])),
        ("box n=2", sq(&[0.3, 0.2, 0.5], &[2.0, 2.0, 2.0])),
        ("mixed (1,1,2)", sq(&[0.05, 0.05, 0.2], &[1.0, 1.0, 2.0])),
        ("nested (2,3)", Shape::Nested(NestedSuperquadric::new([0.3, 0.2, 0.5], 2.0, 3.0).unwrap())),
        ("4-D", sq(&[1.0, 0.4, 0.7, 0.2], &[1.5, 3.0, 1.0, 2.0])),
    ];
    for (name, shape) in &shapes {
        let points = test_points(shape, 3000, 5);
        let (outside, inside): (Vec<_>, Vec<_>) = points.iter().partition(|y| shape.value(y) > 0.0);
        let mut line = format!("{name:>14}:");
        for (label, set) in
            [("all", points.iter().collect::<Vec<_>>()), ("outside", outside), ("inside", inside)]
        {
            let start = std::time::Instant::now();
            let mut acc = 0.0;
            for y in &set {
                acc += signed_distance(shape, y);
            }
            let per_call = start.elapsed().as_secs_f64() / set.len() as f64;
            line += &format!("  {label} {:7.1} us ({} points, sum {acc:.3})", per_call * 1e6, set.len());
        }
        println!("{line}");
    }
}
