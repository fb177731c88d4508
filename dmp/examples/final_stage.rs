//! The final stage against the time-optimal motion: seeded straight reaches of 0.05–0.8 m in random directions (a
//! 1 s minimum-jerk demonstration of each, learned), replayed at `tau` 0.05–2 s at the Panda's Cartesian limits. For each, the time until the output stays within 1 mm of the
//! goal is compared with the larger of the time-optimal motion's (Ruckig over the distance, one axis, from rest to
//! rest, at the robot's speed, acceleration and jerk) and the unlimited replay's own. Also the overshoot past the
//! goal, the largest distance from the straight line, and the cost per output point of the limited run against the
//! unlimited one.
//!
//! `cargo run --release -p dmp --example final_stage [reaches] [seed]` (defaults 200 and 1).

use std::time::Instant;

use dmp::execution::CellMateAvoidance;
use dmp::{Demonstration, Execution, LearnConfig, Limits, Motion, Primitive, Scene, Stepping, learn};
use rsruckig::prelude::{IgnoreErrorHandler, InputParameter, Ruckig, Trajectory};

const DT: f64 = 1e-3;

/// A 1 s minimum-jerk reach from the origin to `goal`, learned with the paper's settings.
fn reach(goal: &[f64]) -> Primitive {
    let t: Vec<f64> = (0..=1000).map(|k| k as f64 * 1e-3).collect();
    let x = t
        .iter()
        .map(|&t| {
            let c = t * t * t * (10.0 - 15.0 * t + 6.0 * t * t);
            goal.iter().map(|g| g * c).collect()
        })
        .collect();
    learn(&Demonstration::new(t, x).unwrap(), &LearnConfig::paper()).unwrap()
}

/// A small deterministic generator (xorshift64*), uniform in [0, 1).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Time until the path stays within `tol` of `goal`, the overshoot past the goal along the reach, the largest
/// distance from the straight line, and the seconds spent computing a point, for a run of `p` to `goal` at `tau`
/// with `limits`.
fn run(p: &Primitive, goal: &[f64], tau: f64, limits: Limits, tol: f64) -> (f64, f64, f64, f64) {
    let motion = Motion { start: vec![0.0; 3], goal: goal.to_vec(), tau };
    let mut e =
        Execution::new(p.clone(), motion, Scene::empty(), CellMateAvoidance::NONE, Stepping::rk4(DT), 0)
            .unwrap();
    e.set_limits(limits, false).unwrap();
    let d = goal.iter().map(|g| g * g).sum::<f64>().sqrt();
    let u: Vec<f64> = goal.iter().map(|g| g / d).collect();
    let (mut within, mut overshoot, mut deviation, mut t) = (None::<f64>, 0.0f64, 0.0f64, 0.0);
    let started = Instant::now();
    let mut x = Vec::new();
    while t < 3.0 * tau.max(0.5) + 3.0 {
        let s = e.advance(10).unwrap();
        x.extend_from_slice(&s.x);
        t = e.time();
        if s.outcome.is_final() {
            break;
        }
    }
    let spent = started.elapsed().as_secs_f64();
    for (k, q) in x.chunks(3).enumerate() {
        let off = q.iter().zip(goal).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt();
        if off > tol {
            within = None;
        } else if within.is_none() {
            within = Some(k as f64 * DT);
        }
        let along: f64 = q.iter().zip(&u).map(|(a, b)| a * b).sum();
        overshoot = overshoot.max(along - d);
        let across = (q.iter().map(|a| a * a).sum::<f64>() - along * along).max(0.0).sqrt();
        deviation = deviation.max(across);
    }
    (within.unwrap_or(f64::INFINITY), overshoot, deviation, spent / (x.len() / 3).max(1) as f64)
}

/// The time-optimal motion over `d` from rest to rest at `(v, a, j)`: the time it stays within `tol` of its end.
fn optimum(d: f64, l: &Limits, tol: f64) -> f64 {
    let mut otg = Ruckig::<1, IgnoreErrorHandler>::new(None, DT);
    let mut input = InputParameter::<1>::new(None);
    input.target_position[0] = d;
    input.max_velocity[0] = l.max_speed;
    input.max_acceleration[0] = l.max_acceleration;
    input.max_jerk[0] = l.max_jerk;
    let mut traj = Trajectory::<1>::new(None);
    otg.calculate(&input, &mut traj).unwrap();
    let (mut lo, mut hi) = (0.0, traj.get_duration());
    let mut p = rsruckig::prelude::DataArrayOrVec::<f64, 1>::new(None, 0.0);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        traj.at_time(mid, &mut Some(&mut p), &mut None, &mut None, &mut None, &mut None);
        if d - p[0] > tol { lo = mid } else { hi = mid }
    }
    hi
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let mut args = std::env::args().skip(1);
    let n: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(200);
    let seed: u64 = args.next().and_then(|a| a.parse().ok()).unwrap_or(1);
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15 ^ seed);
    let l = Limits::PANDA;
    let tol = 1e-3;
    let (mut ratios, mut overshoots, mut cost_limited, mut cost_free) = (vec![], vec![], vec![], vec![]);
    let (mut deviations, mut deviations_free) = (vec![], vec![]);
    let mut worst = (0.0, 0.0, 0.0);
    for _ in 0..n {
        let d = 0.05 + 0.75 * rng.next();
        let tau = 0.05 + 1.95 * rng.next();
        // A random direction on the sphere.
        let z = 2.0 * rng.next() - 1.0;
        let phi = 2.0 * std::f64::consts::PI * rng.next();
        let r = (1.0 - z * z).sqrt();
        let goal = [d * r * phi.cos(), d * r * phi.sin(), d * z];
        let p = reach(&goal);
        let (t_lim, over, dev, c_lim) = run(&p, &goal, tau, l, tol);
        let (t_free, _, dev_free, c_free) = run(&p, &goal, tau, Limits::NONE, tol);
        deviations.push(dev);
        deviations_free.push(dev_free);
        let t_opt = optimum(d, &l, tol);
        let ratio = t_lim / t_opt.max(t_free);
        if ratio > worst.0 {
            worst = (ratio, d, tau);
        }
        ratios.push(ratio);
        overshoots.push(over / d);
        cost_limited.push(c_lim);
        cost_free.push(c_free);
    }
    let worst_overshoot = overshoots.iter().copied().fold(0.0, f64::max);
    println!("{n} straight reaches at the Panda profile (seed {seed})");
    println!(
        "time to within 1 mm / max(time-optimal, unlimited replay): median {:.3}, worst {:.3} (d {:.3} m, tau {:.3} s)",
        median(&mut ratios.clone()),
        worst.0,
        worst.1,
        worst.2
    );
    println!("overshoot past the goal: worst {:.4} % of the reach", 100.0 * worst_overshoot);
    let worst_of = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
    println!(
        "distance from the straight line: worst {:.2} mm limited, {:.2} mm unlimited",
        1e3 * worst_of(&deviations),
        1e3 * worst_of(&deviations_free)
    );
    println!(
        "cost per output point: limited {:.0} ns, unlimited {:.0} ns (medians)",
        1e9 * median(&mut cost_limited),
        1e9 * median(&mut cost_free)
    );
}
