//! One RK4 step (`Integrator::step`) of a 3-D primitive with N = 50, for each of the five avoidance methods
//! with 0, 1 and 10 obstacles (50 boundary samples per obstacle for the point methods).
//!
//! `cargo bench -p dmp --bench step`: one group per method, the parameter is the number of obstacles.

use std::f64::consts::PI;
use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use dmp::avoidance::{DynamicPoint, DynamicVolumetric, StaticPoint, StaticVolumetric, SteeringAngle};
use dmp::{
    Avoidance, Demonstration, Integrator, LearnConfig, Method, Motion, Obstacle, Primitive, RepulsiveField,
    Scene, Shape, State, Superquadric, learn,
};

const DT: f64 = 1e-3;

/// The paper's spiral lifted along z, sampled every millisecond for one second, learned with N = 50.
fn primitive() -> Primitive {
    let t: Vec<f64> = (0..=1000).map(|k| k as f64 * 1e-3).collect();
    let x = t
        .iter()
        .map(|&u| vec![u * (PI * u).cos(), u * (PI * u).sin(), 0.4 * (PI * u).sin().powi(2) + 0.2 * u])
        .collect();
    let p = learn(&Demonstration::new(t, x).unwrap(), &LearnConfig::paper()).unwrap();
    assert_eq!((p.dim, p.n_basis), (3, 50));
    p
}

/// Number of consecutive states the bench cycles through.
const WINDOW: usize = 20;

/// `WINDOW` consecutive states of the free motion, 10 ms either side of its middle: the robot is moving, so
/// the dynamic terms have something to act on. Stepping from them in order is what a run does: each state's
/// phase is the one the previous step ended at, so the forcing term's cache hits as it does in a run.
fn mid_states(p: &Primitive) -> Vec<State> {
    let motion = Motion::of(p);
    let mut integrator = Integrator::new(p).unwrap();
    let mut field = RepulsiveField::new(Scene::empty(), 3).unwrap();
    let mut state = State::at_rest(&motion.start);
    let mut acc = [0.0; 3];
    let mut out = Vec::new();
    for k in 0..500 + WINDOW / 2 {
        if k >= 500 - WINDOW / 2 {
            out.push(state.clone());
        }
        integrator.step(&motion, &mut field, &mut state, DT, &mut acc);
    }
    out
}

/// `n` obstacles centred 0.18 away from `state.x`: the first straight ahead, the others spread over a sphere
/// (so some lie ahead and some behind), of three shapes (ellipsoid, rounded box, rounded cylinder), every
/// other one turned about z and every third one moving.
fn obstacles(state: &State, n: usize) -> Vec<Obstacle> {
    let speed = state.xd.iter().map(|v| v * v).sum::<f64>().sqrt();
    let ahead: Vec<f64> = state.xd.iter().map(|v| v / speed).collect();
    let golden = PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|k| {
            let dir = if k == 0 {
                ahead.clone()
            } else {
                let z = 1.0 - (2.0 * k as f64 + 1.0) / n as f64;
                let r = (1.0 - z * z).sqrt();
                vec![r * (golden * k as f64).cos(), r * (golden * k as f64).sin(), z]
            };
            let center = state.x.iter().zip(&dir).map(|(x, d)| x + 0.18 * d).collect();
            let exponents = [[1.0, 1.0, 1.0], [2.0, 2.0, 2.0], [1.0, 1.0, 2.0]][k % 3].to_vec();
            let shape = Shape::Superquadric(Superquadric::new(vec![0.1, 0.08, 0.12], exponents).unwrap());
            let a = 0.4 * k as f64;
            let rotation = (k % 2 == 1).then(|| {
                vec![vec![a.cos(), -a.sin(), 0.0], vec![a.sin(), a.cos(), 0.0], vec![0.0, 0.0, 1.0]]
            });
            let velocity = (k % 3 == 2).then(|| vec![0.1, -0.05, 0.0]);
            Obstacle::new(format!("o{k}"), shape, center, rotation, velocity).unwrap()
        })
        .collect()
}

/// The five methods with the parameters of the paper's first experiment.
fn methods() -> [Method; 5] {
    [
        Method::StaticPoint(StaticPoint { eta: 1.0, p0: 0.1 }),
        Method::DynamicPoint(DynamicPoint { lambda: 0.2, beta: 2.0 }),
        Method::SteeringAngle(SteeringAngle { gamma: 20.0, beta: 3.0 }),
        Method::StaticVolumetric(StaticVolumetric { a: 10.0, eta: 1.0 }),
        Method::DynamicVolumetric(DynamicVolumetric { lambda: 10.0, beta: 2.0, eta: 0.5 }),
    ]
}

fn step(c: &mut Criterion) {
    let p = primitive();
    let motion = Motion::of(&p);
    let states = mid_states(&p);
    let mid = &states[WINDOW / 2];
    for method in methods() {
        let mut group = c.benchmark_group(method.name());
        group.warm_up_time(Duration::from_millis(300)).measurement_time(Duration::from_secs(1));
        for n in [0, 1, 10] {
            let scene = Scene::with_obstacles(obstacles(mid, n), Avoidance::new(method), 50);
            let mut field = RepulsiveField::new(scene, 3).unwrap();
            let mut integrator = Integrator::new(&p).unwrap();
            let mut state = mid.clone();
            let mut acc = [0.0; 3];
            if n > 0 {
                // The obstacles must act on this state, or the bench would time an early exit.
                let mut free = [0.0; 3];
                let mut empty = RepulsiveField::new(Scene::empty(), 3).unwrap();
                integrator
                    .acceleration(&motion, &mut empty, state.t, state.s, &state.x, &state.xd, &mut free);
                integrator.acceleration(&motion, &mut field, state.t, state.s, &state.x, &state.xd, &mut acc);
                assert!(free != acc, "{}: {n} obstacles do not act", method.name());
            }
            let mut next = 0;
            group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
                b.iter(|| {
                    // Step from the next state of the window (copying it in allocates nothing).
                    let from = &states[next];
                    next = (next + 1) % WINDOW;
                    state.t = from.t;
                    state.s = from.s;
                    state.x.copy_from_slice(&from.x);
                    state.xd.copy_from_slice(&from.xd);
                    integrator.step(&motion, &mut field, black_box(&mut state), black_box(DT), &mut acc);
                    black_box(&state);
                })
            });
        }
        group.finish();
    }
}

criterion_group!(benches, step);
criterion_main!(benches);
