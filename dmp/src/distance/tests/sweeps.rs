//! Sweeps run by hand (`--ignored`): settings, the compass-search reference over random shapes, timing.

use super::*;

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

/// Sweep: `STRESS_D=3 STRESS_N=4,6 cargo test -p dmp --release distance::tests::sweeps::stress -- --ignored
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
/// `cargo test -p dmp --release distance::tests::sweeps::compass_sweep -- --ignored --nocapture`.
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

/// Time per call: `cargo test -p dmp --release distance::tests::sweeps::timing -- --ignored --nocapture`.
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
