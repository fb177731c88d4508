//! What the properties share: the paper's curve and its primitive, obstacles, fields, methods, distances and
//! rollouts.

use std::f64::consts::PI;
use std::sync::LazyLock;

use dmp::avoidance::{DynamicPoint, DynamicVolumetric, StaticPoint, StaticVolumetric, SteeringAngle};
use dmp::{
    Avoidance, Contact, Demonstration, Integrator, LearnConfig, Method, Motion, Obstacle, Perturbation,
    Primitive, RepulsiveField, Rollout, Scene, Shape, State, Superquadric, learn, rollout,
};
use proptest::prelude::*;

/// The paper's demonstration, `x(t) = (t cos(pi t), t sin(pi t))`.
pub(crate) fn paper_curve(t: f64) -> Vec<f64> {
    vec![t * (PI * t).cos(), t * (PI * t).sin()]
}

/// Samples `curve` at `times`.
pub(crate) fn demo_of(times: &[f64], curve: impl Fn(f64) -> Vec<f64>) -> Demonstration {
    Demonstration::new(times.to_vec(), times.iter().map(|&t| curve(t)).collect()).unwrap()
}

/// `0, 1 ms, ..., 1 s`.
pub(crate) fn uniform_times() -> Vec<f64> {
    (0..=1000).map(|k| k as f64 * 1e-3).collect()
}

/// The paper's curve learned with the paper's settings (N = 50, K = 1050, alpha = 4).
pub(crate) static PAPER: LazyLock<Primitive> =
    LazyLock::new(|| learn(&demo_of(&uniform_times(), paper_curve), &LearnConfig::paper()).unwrap());

/// `cases` cases (or `PROPTEST_CASES` when set), without failure files next to the sources.
pub(crate) fn config(cases: u32) -> ProptestConfig {
    let base = ProptestConfig::default();
    let cases = if std::env::var_os("PROPTEST_CASES").is_some() { base.cases } else { cases };
    ProptestConfig { cases, failure_persistence: None, ..base }
}

pub(crate) fn empty_field(dim: usize) -> RepulsiveField {
    RepulsiveField::new(Scene::empty(), dim).unwrap()
}

pub(crate) fn superquadric(axes: &[f64], exponents: &[f64]) -> Shape {
    Shape::Superquadric(Superquadric::new(axes.to_vec(), exponents.to_vec()).unwrap())
}

pub(crate) fn ellipsoid(id: &str, center: &[f64], axes: &[f64]) -> Obstacle {
    Obstacle::new(id, superquadric(axes, &vec![1.0; axes.len()]), center.to_vec(), None, None).unwrap()
}

/// The paper's obstacle: the ellipse of centre (-0.5, 0.7), semi-axes (0.3, 0.2), which the curve crosses.
pub(crate) fn paper_ellipse() -> Obstacle {
    ellipsoid("ellipse", &[-0.5, 0.7], &[0.3, 0.2])
}

pub(crate) fn field(obstacles: Vec<Obstacle>, method: Method, dim: usize) -> RepulsiveField {
    RepulsiveField::new(Scene::with_obstacles(obstacles, Avoidance::new(method), 50), dim).unwrap()
}

pub(crate) fn static_volumetric(a: f64, eta: f64) -> Method {
    Method::StaticVolumetric(StaticVolumetric { a, eta })
}

pub(crate) fn dynamic_volumetric(lambda: f64, beta: f64, eta: f64) -> Method {
    Method::DynamicVolumetric(DynamicVolumetric { lambda, beta, eta })
}

pub(crate) fn dynamic_point(lambda: f64, beta: f64) -> Method {
    Method::DynamicPoint(DynamicPoint { lambda, beta })
}

/// The five methods with the parameters of the paper's first experiment.
pub(crate) fn paper_methods() -> [Method; 5] {
    [
        Method::StaticPoint(StaticPoint { eta: 1.0, p0: 0.1 }),
        dynamic_point(0.2, 2.0),
        Method::SteeringAngle(SteeringAngle { gamma: 20.0, beta: 3.0 }),
        static_volumetric(10.0, 1.0),
        dynamic_volumetric(10.0, 2.0, 0.5),
    ]
}

pub(crate) fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

pub(crate) fn dist(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum::<f64>().sqrt()
}

/// The largest extent of a set of points along one axis.
pub(crate) fn span(points: &[Vec<f64>]) -> f64 {
    (0..points[0].len())
        .map(|i| {
            let (lo, hi) = points
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| (lo.min(p[i]), hi.max(p[i])));
            hi - lo
        })
        .fold(0.0, f64::max)
}

/// Steps `p` from rest at `motion.start` with `Integrator::step` for `t_end / dt` steps; returns the final
/// state.
pub(crate) fn integrate_to(
    p: &Primitive,
    motion: &Motion,
    pert: &mut dyn Perturbation,
    dt: f64,
    t_end: f64,
) -> State {
    let steps = (t_end / dt).round() as usize;
    assert!((steps as f64 * dt - t_end).abs() < 1e-12, "t_end must be a multiple of dt");
    let mut integrator = Integrator::new(p).unwrap();
    let mut state = State::at_rest(&motion.start);
    let mut acc = vec![0.0; p.dim];
    for _ in 0..steps {
        integrator.step(motion, pert, &mut state, dt, &mut acc);
    }
    state
}

pub(crate) fn run(p: &Primitive, motion: &Motion, field: &RepulsiveField, dt: f64, duration: f64) -> Rollout {
    rollout(p, motion, field, dt, (duration / dt).round() as usize).unwrap()
}

pub(crate) fn last_position(r: &Rollout) -> &[f64] {
    r.trajectory.position(r.trajectory.len() - 1)
}

pub(crate) fn obstacle_contacts(r: &Rollout) -> usize {
    r.contacts.iter().filter(|(_, c)| matches!(c, Contact::Obstacle { .. })).count()
}

pub(crate) fn motion(start: Vec<f64>, goal: Vec<f64>, tau: f64) -> Motion {
    Motion { start, goal, tau }
}
