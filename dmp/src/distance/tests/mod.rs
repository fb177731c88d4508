//! Accuracy of the signed distance against closed forms and brute force.
use super::*;
use crate::directions::unit_directions;
use crate::isopotential::{NestedSuperquadric, Superquadric};

mod brute_force;
mod closed_forms;
mod degenerate_inputs;
mod sweeps;
mod world_frame;

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
