//! What the safety distance costs: seeded straight reaches of 0.3–0.8 m at the Panda's limits past a ball of radius
//! 0.05–0.15 m lying beside the way (its surface 0–5 cm from the straight line, the dynamic volumetric potential),
//! each run with no margin and with a margin of 1 cm. Prints the median cost per output point of each, their ratio,
//! the smallest clearance of the runs with a margin and how many of them braked for it.
//!
//! `cargo run --release -p dmp --example guard_cost [reaches] [seed]` (defaults 100 and 1).

use std::time::Instant;

use dmp::avoidance::{DynamicVolumetric, Method};
use dmp::distance::signed_distance_world;
use dmp::execution::CellMateAvoidance;
use dmp::isopotential::{Shape, Superquadric};
use dmp::{Avoidance, Execution, LimitAction, Limits, Motion, Obstacle, Primitive, Scene, Stepping};

const DT: f64 = 1e-3;

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

/// Seconds per output point, the smallest clearance from `ball`, and whether it braked for the margin.
fn run(p: &Primitive, goal: &[f64], ball: &Obstacle, margin: f64) -> (f64, f64, bool) {
    let motion = Motion { start: vec![0.0; 3], goal: goal.to_vec(), tau: 1.0 };
    let avoid =
        Avoidance::new(Method::DynamicVolumetric(DynamicVolumetric { lambda: 1.0, beta: 2.0, eta: 1.0 }));
    let scene = Scene::with_obstacles(vec![ball.clone()], avoid, 0);
    let mut e =
        Execution::new(p.clone(), motion, scene, CellMateAvoidance::NONE, Stepping::rk4(DT), 0).unwrap();
    e.set_limits(Limits::PANDA, false).unwrap();
    e.set_margin(margin).unwrap();
    e.set_end_time(4.0);
    let (mut points, mut blocked, mut x, mut times) = (0usize, false, Vec::new(), Vec::new());
    let started = Instant::now();
    loop {
        let s = e.advance(10).unwrap();
        points += s.x.len() / 3;
        blocked |= s.limit == LimitAction::Blocked;
        times.push(s.start_time);
        x.extend_from_slice(&s.x);
        if s.outcome.is_final() {
            break;
        }
    }
    let cost = started.elapsed().as_secs_f64() / points as f64;
    let clearance = x
        .chunks(3)
        .enumerate()
        .map(|(k, p)| signed_distance_world(ball, p, k as f64 * DT))
        .fold(f64::INFINITY, f64::min);
    (cost, clearance, blocked)
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let mut args = std::env::args().skip(1);
    let n: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(100);
    let seed: u64 = args.next().and_then(|a| a.parse().ok()).unwrap_or(1);
    let mut rng = Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
    let (mut free, mut guarded, mut clearance, mut braked) = (Vec::new(), Vec::new(), f64::INFINITY, 0);
    for _ in 0..n {
        let length = 0.3 + 0.5 * rng.next();
        let phi = 2.0 * std::f64::consts::PI * rng.next();
        let goal = [length * phi.cos(), length * phi.sin(), 0.1 * (rng.next() - 0.5)];
        let p = Primitive::straight_line(20, 4.0, vec![150.0; 3], None, 1.0, vec![0.0; 3], goal.to_vec())
            .unwrap();
        let radius = 0.05 + 0.1 * rng.next();
        let off = radius + 0.05 * rng.next();
        let along = 0.3 + 0.4 * rng.next();
        let centre = [goal[0] * along - off * phi.sin(), goal[1] * along + off * phi.cos(), goal[2] * along];
        let shape = Shape::Superquadric(Superquadric::ellipsoid(vec![radius; 3]).unwrap());
        let ball = Obstacle::new("ball", shape, centre.to_vec(), None, None).unwrap();
        free.push(run(&p, &goal, &ball, 0.0).0);
        let (cost, c, b) = run(&p, &goal, &ball, 0.01);
        guarded.push(cost);
        clearance = clearance.min(c);
        braked += usize::from(b);
    }
    let (f, g) = (median(&mut free), median(&mut guarded));
    println!("{n} reaches, seed {seed}, Panda limits, a ball beside each");
    println!(
        "cost per output point: no margin {:.0} ns, margin 1 cm {:.0} ns (medians), ratio {:.2}",
        f * 1e9,
        g * 1e9,
        g / f
    );
    println!("margin 1 cm: smallest clearance {:.4} m, {braked} of {n} runs braked for it", clearance);
}
