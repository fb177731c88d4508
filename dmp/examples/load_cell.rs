//! One cell of the load (`dmpctl load`), offline: ten robots whose paths cross, five fixed obstacles, each robot
//! avoiding the others as moving obstacles, a new goal every `tau`, the load's adaptive step. Prints what stepping them cost per output point
//! (time, evaluations of the field, steps, points the limiter changed, restarts of the grid), what keeping the
//! limits did per segment, and the segments with a contact: as position and as pose robots, without limits and at
//! the Panda profile. The pose robots turn a quarter turn each leg, as `dmpctl load --pose` does.
//!
//! `cargo run --release -p dmp --example load_cell [seconds] [lag] [every]`: `seconds` of run time (default 10);
//! each robot sees its cell-mates as they were `lag` segments before (default 0), every `every` segments (default
//! 1; the server, at 1,000 streams, about 5 and 6). Robot `k` starts `k` [`STAGGER`] after the first.

use std::f64::consts::PI;
use std::time::Instant;

use dmp::avoidance::DynamicVolumetric;
use dmp::execution::{CellMate, CellMateAvoidance, IntegrationCost};
use dmp::orientation::pose::pose_motion;
use dmp::{
    Agent, Avoidance, Execution, Limits, Method, Motion, Obstacle, OrientationChart, Primitive, Scene, Shape,
    Stepping, Superquadric,
};

const ROBOTS: usize = 10;
const TAU: f64 = 2.0;
const DT: f64 = 1e-3;
const SEGMENT: usize = 10;
/// Robot `k` starts `k STAGGER` seconds after the first (the load starts its 1,000 robots over a second).
const STAGGER: f64 = 0.001;

fn ball(r: f64) -> Shape {
    Shape::Superquadric(Superquadric::new(vec![r; 3], vec![1.0; 3]).unwrap())
}

fn point(angle: f64, radius: f64, z: f64) -> Vec<f64> {
    vec![radius * angle.cos(), radius * angle.sin(), z]
}

fn quat_z(a: f64) -> [f64; 4] {
    let (s, c) = (0.5 * a).sin_cos();
    [0.0, 0.0, s, c]
}

fn turned(a: f64) -> [f64; 4] {
    let (s, c) = (0.5 * a).sin_cos();
    let (u, v) = (0.25 * PI).sin_cos();
    [c * u, s * u, s * v, c * v]
}

struct Robot {
    e: Execution,
    goals: [Vec<f64>; 2],
    orientations: [[f64; 4]; 2],
    next_goal: usize,
    x: Vec<f64>,
    v: Vec<f64>,
}

fn cell(pose: bool, limits: Limits) -> Vec<Robot> {
    let obstacles: Vec<Obstacle> = (0..5)
        .map(|k| {
            let c = point(2.0 * PI * k as f64 / 5.0 + PI / 10.0, 0.3, 0.1);
            Obstacle::new(format!("fixed-{k}"), ball(0.06), c, None, None).unwrap()
        })
        .collect();
    let avoid =
        |lambda, eta| Avoidance::new(Method::DynamicVolumetric(DynamicVolumetric { lambda, beta: 2.0, eta }));
    (0..ROBOTS)
        .map(|k| {
            let angle = 2.0 * PI * k as f64 / ROBOTS as f64;
            let start = point(angle, 0.6, 0.0);
            let far = point(angle + PI + 0.4, 0.6, 0.2);
            let dim = if pose { 6 } else { 3 };
            let (mut s, mut g) = (start.clone(), far.clone());
            if pose {
                s.extend([0.0; 3]);
                g.extend([0.0; 3]);
            }
            let mut p = Primitive::straight_line(50, 4.0, vec![25.0; dim], None, TAU, s, g).unwrap();
            let mut motion = Motion::of(&p);
            let orientations = [turned(angle), quat_z(angle)];
            let mut chart = None;
            if pose {
                p.orientation = Some(OrientationChart { reference: [0.0, 0.0, 0.0, 1.0] });
                let m = pose_motion(&p, motion, Some(orientations[1]), Some(orientations[0])).unwrap();
                motion = m.motion;
                chart = Some(m.chart);
            }
            let scene = Scene {
                obstacles: Vec::new(),
                avoidance: avoid(10.0, 0.5),
                agents: vec![Agent { id: format!("r{k}"), dims: vec![0, 1, 2], footprint: Some(ball(0.1)) }],
                robot_avoidance: Avoidance::NONE,
                point_samples: 16,
            };
            let mates = CellMateAvoidance { method: avoid(60.0, 0.2), point_samples: 16 };
            let stepping = Stepping { dt: DT, step_points: 30, tolerance: Some(3e-6) };
            let mut e = Execution::new(p, motion, scene, mates, stepping, 200).unwrap();
            e.set_obstacles(obstacles.iter().map(|o| (o, 0.0))).unwrap();
            if let Some(c) = chart {
                e.set_orientation_chart(c).unwrap();
            }
            e.set_limits(limits, pose).unwrap();
            Robot { e, goals: [far, start.clone()], orientations, next_goal: 1, x: start, v: vec![0.0; 3] }
        })
        .collect()
}

/// A cell-mate as seen: its id, position and velocity.
type Seen = (String, Vec<f64>, Vec<f64>);

/// Runs the cell for `seconds`; each robot sets its cell-mates every `every` segments, as they were `lag` segments
/// before.
fn run(name: &str, pose: bool, limits: Limits, seconds: f64, lag: usize, every: usize) {
    let mut robots = cell(pose, limits);
    let footprint = ball(0.1);
    let segments = (seconds / (SEGMENT as f64 * DT)).round() as usize;
    let mut actions = [0usize; 4];
    let mut collisions = 0;
    let t0 = Instant::now();
    let mut past: Vec<Vec<Seen>> = Vec::new();
    for seg in 0..segments {
        let t = seg as f64 * SEGMENT as f64 * DT;
        past.push(
            robots.iter().enumerate().map(|(k, r)| (format!("r{k}"), r.x.clone(), r.v.clone())).collect(),
        );
        let states = past[past.len().saturating_sub(1 + lag)].clone();
        let age = (past.len() - 1).min(lag) as f64 * SEGMENT as f64 * DT;
        for (k, r) in robots.iter_mut().enumerate() {
            let mates = states.iter().enumerate().filter(|(j, _)| *j != k).map(|(_, (id, x, v))| CellMate {
                id,
                footprint: &footprint,
                position: x,
                velocity: v,
                age,
            });
            if seg % every == 0 {
                r.e.set_cell_mates(mates).unwrap();
            }
            let delay = STAGGER * k as f64;
            r.e.set_holding(t < delay);
            if t >= delay + r.next_goal as f64 * TAU {
                let g = r.next_goal % 2;
                if pose {
                    r.e.set_pose_goal(Some(r.goals[g].clone()), Some(r.orientations[g])).unwrap();
                } else {
                    r.e.set_goal(r.goals[g].clone()).unwrap();
                }
                r.next_goal += 1;
            }
            let s = r.e.advance(SEGMENT).unwrap();
            actions[s.limit as usize] += 1;
            if !s.contacts.is_empty() || !s.cell_mate_contacts.is_empty() {
                collisions += 1;
            }
            let d = r.e.dim();
            r.x.copy_from_slice(&s.x[(SEGMENT - 1) * d..(SEGMENT - 1) * d + 3]);
            r.v.copy_from_slice(&s.xd[(SEGMENT - 1) * d..(SEGMENT - 1) * d + 3]);
        }
    }
    let elapsed = t0.elapsed().as_secs_f64();

    let mut c = IntegrationCost::default();
    for r in &robots {
        let k = r.e.cost();
        c.steps += k.steps;
        c.rejected += k.rejected;
        c.evaluations += k.evaluations;
        c.limited += k.limited;
        c.restarts += k.restarts;
    }
    let points = (segments * SEGMENT * ROBOTS) as f64;
    println!(
        "{name:<28} {:>6.2} us/point  evals/point {:.3}  steps/point {:.3}  rejected {}  limited {:.2}%  \
         restarts/point {:.3}  segments none/slowed/limited/braking {:?}  collision segments {collisions}",
        elapsed / points * 1e6,
        c.evaluations as f64 / points,
        c.steps as f64 / points,
        c.rejected,
        100.0 * c.limited as f64 / points,
        c.restarts as f64 / points,
        actions
    );
}

fn main() {
    let arg = |i: usize, name: &str, default: f64| match std::env::args().nth(i) {
        None => default,
        Some(s) => match s.parse::<f64>() {
            Ok(v) if v.is_finite() && v >= 0.0 => v,
            _ => {
                eprintln!("load_cell: {name} must be a number of at least 0, not `{s}`");
                std::process::exit(2);
            }
        },
    };
    let (seconds, lag, every) =
        (arg(1, "seconds", 10.0), arg(2, "lag", 0.0) as usize, (arg(3, "every", 1.0) as usize).max(1));
    run("position, no limits", false, Limits::NONE, seconds, lag, every);
    run("position, Panda", false, Limits::PANDA, seconds, lag, every);
    run("pose, no limits", true, Limits::NONE, seconds, lag, every);
    run("pose, Panda", true, Limits::PANDA, seconds, lag, every);
}
