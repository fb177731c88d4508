//! What a pose robot costs against a position robot, per output point, as the server steps them: one whole
//! 1 s run ([`dmp::Execution`], 1,000 points of 1 ms, handed out in 10-point segments as a stream does) of the
//! same 3-D path, once as a position primitive and once as a pose primitive (the same positions and an
//! orientation turning 90° about a tilted axis: dimension 6, its orientations, angular velocities and
//! accelerations filled at every point), with 0 and 10 obstacles (dynamic volumetric, acting on the position).
//!
//! `cargo bench -p dmp --bench pose`: one group per stepping (RK4 at every point, the server's default; RK4 every
//! 10 points with exact dense output in between), the parameter is the robot and the number of obstacles. The
//! throughput is in points: criterion prints the time per point.

use std::f64::consts::PI;
use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use dmp::avoidance::DynamicVolumetric;
use dmp::execution::CellMateAvoidance;
use dmp::orientation::pose::{learn_pose, pose_motion};
use dmp::{
    Avoidance, Demonstration, Execution, LearnConfig, Method, Motion, Obstacle, OrientationDemonstration,
    Primitive, Scene, Shape, Stepping, Superquadric, learn,
};
use nalgebra::{UnitQuaternion, Vector3};

const DT: f64 = 1e-3;
/// Points per segment, as the load's robots ask.
const SEGMENT: usize = 10;

/// The paper's spiral lifted along z, sampled every millisecond for one second.
fn demonstration() -> Demonstration {
    let t: Vec<f64> = (0..=1000).map(|k| k as f64 * 1e-3).collect();
    let x = t
        .iter()
        .map(|&u| vec![u * (PI * u).cos(), u * (PI * u).sin(), 0.4 * (PI * u).sin().powi(2) + 0.2 * u])
        .collect();
    Demonstration::new(t, x).unwrap()
}

/// The position primitive and the pose primitive of the same path.
fn primitives() -> (Primitive, Primitive) {
    let positions = demonstration();
    let position = learn(&positions, &LearnConfig::paper()).unwrap();
    let axis = Vector3::new(1.0, 1.0, 1.0).normalize();
    let orientations = positions
        .times()
        .iter()
        .map(|&u| {
            let q = UnitQuaternion::from_scaled_axis(axis * (0.5 * PI * u));
            [q.i, q.j, q.k, q.w]
        })
        .collect();
    let orientations = OrientationDemonstration::new(positions.times().to_vec(), orientations).unwrap();
    let pose = learn_pose(&positions, &orientations, &LearnConfig::paper()).unwrap();
    assert_eq!((position.dim, pose.dim), (3, 6));
    (position, pose)
}

/// `n` obstacles around the middle of the path, of three shapes, every third one moving.
fn obstacles(n: usize) -> Vec<Obstacle> {
    (0..n)
        .map(|k| {
            let a = 2.0 * PI * k as f64 / n.max(1) as f64;
            let center = vec![-0.1 + 0.3 * a.cos(), 0.5 + 0.3 * a.sin(), 0.5];
            let exponents = [[1.0, 1.0, 1.0], [2.0, 2.0, 2.0], [1.0, 1.0, 2.0]][k % 3].to_vec();
            let shape = Shape::Superquadric(Superquadric::new(vec![0.08, 0.06, 0.1], exponents).unwrap());
            let velocity = (k % 3 == 2).then(|| vec![0.1, -0.05, 0.0]);
            Obstacle::new(format!("o{k}"), shape, center, None, velocity).unwrap()
        })
        .collect()
}

/// A fresh execution of `p` (a pose primitive replays its demonstration's orientations).
fn execution(p: &Primitive, n_obstacles: usize, stepping: Stepping) -> Execution {
    let method = Method::DynamicVolumetric(DynamicVolumetric { lambda: 10.0, beta: 2.0, eta: 0.5 });
    let scene = Scene::with_obstacles(obstacles(n_obstacles), Avoidance::new(method), 50);
    let mut motion = Motion::of(p);
    let mut chart = None;
    if p.orientation.is_some() {
        motion.start.truncate(p.position_dim());
        motion.goal.truncate(p.position_dim());
        let m = pose_motion(p, motion, None, None).unwrap();
        motion = m.motion;
        chart = Some(m.chart);
    }
    let mut e = Execution::new(p.clone(), motion, scene, CellMateAvoidance::NONE, stepping, 64).unwrap();
    if let Some(c) = chart {
        e.set_orientation_chart(c).unwrap();
    }
    e
}

/// Runs `e` to its end in segments; returns the points handed out.
fn run(mut e: Execution) -> usize {
    let mut points = 0;
    while points < 1000 {
        let s = e.advance(SEGMENT).unwrap();
        points += s.x.len() / e.dim();
        black_box(&s);
    }
    points
}

fn pose_against_position(c: &mut Criterion) {
    let (position, pose) = primitives();
    for (name, stepping) in [
        ("rk4-every-point", Stepping::rk4(DT)),
        ("rk4-every-10-points", Stepping { dt: DT, step_points: 10, tolerance: None }),
    ] {
        let mut group = c.benchmark_group(format!("pose/{name}"));
        group.warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(3));
        group.throughput(Throughput::Elements(1000));
        for n in [0, 10] {
            for (robot, p) in [("position", &position), ("pose", &pose)] {
                // The pose run hands out orientations: the bench times what a stream sends.
                let mut first = execution(p, n, stepping);
                let s = first.advance(SEGMENT).unwrap();
                assert_eq!(s.orientation.q.is_empty(), p.orientation.is_none());
                group.bench_with_input(BenchmarkId::new(robot, n), &n, |b, &n| {
                    b.iter_batched(|| execution(p, n, stepping), run, criterion::BatchSize::SmallInput)
                });
            }
        }
        group.finish();
    }
}

criterion_group!(benches, pose_against_position);
criterion_main!(benches);
