//! Properties of the `dmp` engine, through its public API only: RK4 order, replay of a demonstration, time
//! scaling, spatial generalisation, save and load, changing the motion mid-run, guard rails (never NaN,
//! contacts and stalls reported) and several robots on one phase.
//!
//! Measured numbers are printed with `eprintln!` (`cargo test -p dmp --test properties -- --nocapture`).

use std::f64::consts::PI;
use std::sync::LazyLock;

use dmp::avoidance::{DynamicPoint, DynamicVolumetric, StaticPoint, StaticVolumetric, SteeringAngle};
use dmp::{
    Agent, Avoidance, Contact, Demonstration, Integrator, LearnConfig, Method, Motion, Obstacle,
    Perturbation, Primitive, RepulsiveField, Rollout, Scene, Shape, State, Superquadric, learn, rollout,
};
use proptest::prelude::*;

// -----------------------------------------------------------------------------------------------------------
// Fixtures
// -----------------------------------------------------------------------------------------------------------

/// The paper's demonstration, `x(t) = (t cos(pi t), t sin(pi t))`.
fn paper_curve(t: f64) -> Vec<f64> {
    vec![t * (PI * t).cos(), t * (PI * t).sin()]
}

/// Samples `curve` at `times`.
fn demo_of(times: &[f64], curve: impl Fn(f64) -> Vec<f64>) -> Demonstration {
    Demonstration::new(times.to_vec(), times.iter().map(|&t| curve(t)).collect()).unwrap()
}

/// `0, 1 ms, ..., 1 s`.
fn uniform_times() -> Vec<f64> {
    (0..=1000).map(|k| k as f64 * 1e-3).collect()
}

/// The paper's curve learned with the paper's settings (N = 50, K = 1050, alpha = 4).
static PAPER: LazyLock<Primitive> =
    LazyLock::new(|| learn(&demo_of(&uniform_times(), paper_curve), &LearnConfig::paper()).unwrap());

/// `cases` cases (or `PROPTEST_CASES` when set), without failure files next to the sources.
fn config(cases: u32) -> ProptestConfig {
    let base = ProptestConfig::default();
    let cases = if std::env::var_os("PROPTEST_CASES").is_some() { base.cases } else { cases };
    ProptestConfig { cases, failure_persistence: None, ..base }
}

fn empty_field(dim: usize) -> RepulsiveField {
    RepulsiveField::new(Scene::empty(), dim).unwrap()
}

fn superquadric(axes: &[f64], exponents: &[f64]) -> Shape {
    Shape::Superquadric(Superquadric::new(axes.to_vec(), exponents.to_vec()).unwrap())
}

fn ellipsoid(id: &str, center: &[f64], axes: &[f64]) -> Obstacle {
    Obstacle::new(id, superquadric(axes, &vec![1.0; axes.len()]), center.to_vec(), None, None).unwrap()
}

/// The paper's obstacle: the ellipse of centre (-0.5, 0.7), semi-axes (0.3, 0.2), which the curve crosses.
fn paper_ellipse() -> Obstacle {
    ellipsoid("ellipse", &[-0.5, 0.7], &[0.3, 0.2])
}

fn field(obstacles: Vec<Obstacle>, method: Method, dim: usize) -> RepulsiveField {
    RepulsiveField::new(Scene::with_obstacles(obstacles, Avoidance::new(method), 50), dim).unwrap()
}

fn static_volumetric(a: f64, eta: f64) -> Method {
    Method::StaticVolumetric(StaticVolumetric { a, eta })
}

fn dynamic_volumetric(lambda: f64, beta: f64, eta: f64) -> Method {
    Method::DynamicVolumetric(DynamicVolumetric { lambda, beta, eta })
}

fn dynamic_point(lambda: f64, beta: f64) -> Method {
    Method::DynamicPoint(DynamicPoint { lambda, beta })
}

/// The five methods with the parameters of the paper's first experiment.
fn paper_methods() -> [Method; 5] {
    [
        Method::StaticPoint(StaticPoint { eta: 1.0, p0: 0.1 }),
        dynamic_point(0.2, 2.0),
        Method::SteeringAngle(SteeringAngle { gamma: 20.0, beta: 3.0 }),
        static_volumetric(10.0, 1.0),
        dynamic_volumetric(10.0, 2.0, 0.5),
    ]
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

fn dist(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum::<f64>().sqrt()
}

/// The largest extent of a set of points along one axis.
fn span(points: &[Vec<f64>]) -> f64 {
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
fn integrate_to(p: &Primitive, motion: &Motion, pert: &mut dyn Perturbation, dt: f64, t_end: f64) -> State {
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

fn run(p: &Primitive, motion: &Motion, field: &mut RepulsiveField, dt: f64, duration: f64) -> Rollout {
    rollout(p, motion, field, dt, (duration / dt).round() as usize).unwrap()
}

fn last_position(r: &Rollout) -> &[f64] {
    r.trajectory.position(r.trajectory.len() - 1)
}

fn obstacle_contacts(r: &Rollout) -> usize {
    r.contacts.iter().filter(|(_, c)| matches!(c, Contact::Obstacle { .. })).count()
}

// -----------------------------------------------------------------------------------------------------------
// RK4 convergence
// -----------------------------------------------------------------------------------------------------------

/// Errors at `t_end` in position and velocity for `dt` and `dt / 2`, against a reference at `dt / 32`;
/// returns the two ratios `e(dt) / e(dt / 2)`.
fn convergence_ratios(
    label: &str,
    make_field: impl Fn() -> RepulsiveField,
    dt: f64,
    t_end: f64,
) -> (f64, f64) {
    let p = &*PAPER;
    let motion = Motion::of(p);
    let reference = integrate_to(p, &motion, &mut make_field(), dt / 32.0, t_end);
    let err = |h: f64| {
        let s = integrate_to(p, &motion, &mut make_field(), h, t_end);
        (dist(&s.x, &reference.x), dist(&s.xd, &reference.xd))
    };
    let (ex1, ev1) = err(dt);
    let (ex2, ev2) = err(dt / 2.0);
    let (rx, rv) = (ex1 / ex2, ev1 / ev2);
    eprintln!(
        "rk4 {label}: dt {:.0} ms vs {:.0} ms: |x err| {ex1:.3e} -> {ex2:.3e} (ratio {rx:.2}), \
         |xd err| {ev1:.3e} -> {ev2:.3e} (ratio {rv:.2})",
        dt * 1e3,
        dt * 5e2
    );
    (rx, rv)
}

/// `e(4 ms) / e(2 ms)` and `e(2 ms) / e(1 ms)` at `t = 1` must both be about 16.
fn assert_fourth_order(label: &str, make_field: impl Fn() -> RepulsiveField + Copy) {
    for dt in [4e-3, 2e-3] {
        let (rx, rv) = convergence_ratios(label, make_field, dt, 1.0);
        assert!((12.0..=20.0).contains(&rx), "{label}, dt {dt}: position error ratio {rx}");
        assert!((12.0..=20.0).contains(&rv), "{label}, dt {dt}: velocity error ratio {rv}");
    }
}

/// Whether the field pushes at each step of the paper's rollout at 1 ms (evaluated at the state after the
/// step).
fn activity(make_field: impl Fn() -> RepulsiveField) -> Vec<bool> {
    let p = &*PAPER;
    let motion = Motion::of(p);
    let (mut integrator, mut field) = (Integrator::new(p).unwrap(), make_field());
    let mut state = State::at_rest(&motion.start);
    let (mut acc, mut phi) = (vec![0.0; 2], vec![0.0; 2]);
    (0..1000)
        .map(|_| {
            integrator.step(&motion, &mut field, &mut state, 1e-3, &mut acc);
            let v: Vec<f64> = state.xd.iter().map(|xd| motion.tau * xd).collect();
            phi.fill(0.0);
            field.add(state.t, &state.x, &v, motion.tau, &mut phi);
            norm(&phi) > 0.0
        })
        .collect()
}

/// The obstacle must really change the motion, or a convergence test with it would only repeat the free one.
fn assert_acts(make_field: impl Fn() -> RepulsiveField) {
    let p = &*PAPER;
    let free = run(p, &Motion::of(p), &mut empty_field(2), 1e-3, 1.0).trajectory;
    let pushed = run(p, &Motion::of(p), &mut make_field(), 1e-3, 1.0).trajectory;
    let moved = (0..free.len()).map(|k| dist(free.position(k), pushed.position(k))).fold(0.0, f64::max);
    assert!(moved > 1e-2, "the obstacle moves the path by only {moved}");
}

#[test]
fn rk4_error_falls_sixteenfold_when_dt_halves_without_obstacles() {
    assert_fourth_order("no obstacle", || empty_field(2));
}

#[test]
fn rk4_error_falls_sixteenfold_when_dt_halves_with_a_static_volumetric_obstacle() {
    // The paper's ellipse, which the demonstration crosses: the static potential acts everywhere, all the
    // time.
    let make = || field(vec![paper_ellipse()], static_volumetric(10.0, 1.0), 2);
    assert_acts(make);
    assert!(activity(make).iter().all(|&on| on));
    assert_fourth_order("static volumetric", make);
}

#[test]
fn rk4_error_falls_sixteenfold_when_dt_halves_with_a_dynamic_volumetric_obstacle() {
    // A disc beside the goal, which the robot heads for during the second half of the motion. The dynamic
    // term has a switch (cos theta = 0) where, for beta = 2, it is continuous but its derivative jumps, so
    // RK4 loses an order on the step that crosses it; here it switches on once, far from the disc where that
    // kink is weak, then stays on.
    let make =
        || field(vec![ellipsoid("disc", &[-1.0, -0.35], &[0.2, 0.2])], dynamic_volumetric(10.0, 2.0, 0.5), 2);
    assert_acts(make);
    let on = activity(make);
    let first = on.iter().position(|&a| a).expect("the dynamic term never acts");
    assert!(on[first..].iter().all(|&a| a), "the dynamic term switches off again");
    eprintln!("dynamic volumetric term on from t = {} s", (first + 1) as f64 * 1e-3);
    assert_fourth_order("dynamic volumetric", make);
}

#[test]
fn a_step_from_the_previous_steps_last_acceleration_is_bit_identical() {
    // First same as last: the acceleration at the state a step ends in, evaluated under the same field, is the
    // next step's first stage; passing it in skips one field evaluation and changes nothing.
    let motion = Motion::of(&PAPER);
    let mut f =
        field(vec![ellipsoid("disc", &[-0.6, -0.1], &[0.2, 0.15])], dynamic_volumetric(10.0, 2.0, 0.5), 2);
    let dt = 0.01;
    let (mut plain, mut fsal) = (Integrator::new(&PAPER).unwrap(), Integrator::new(&PAPER).unwrap());
    let (mut a, mut b) = (State::at_rest(&motion.start), State::at_rest(&motion.start));
    let (mut acc_a, mut acc_b) = (vec![0.0; 2], vec![0.0; 2]);
    let mut known = false;
    for _ in 0..100 {
        plain.step(&motion, &mut f, &mut a, dt, &mut acc_a);
        fsal.step_from(&motion, &mut f, &mut b, dt, &mut acc_b, known);
        assert_eq!((a.x.clone(), a.xd.clone(), acc_a.clone()), (b.x.clone(), b.xd.clone(), acc_b.clone()));
        // The acceleration at the end of the step, as a dense-output knot computes it.
        fsal.acceleration(&motion, &mut f, b.t, b.s, &b.x, &b.xd, &mut acc_b);
        known = true;
    }
}

#[test]
fn rk4_error_falls_sixteenfold_when_dt_halves_with_a_moving_obstacle() {
    // The paper's ellipse drifting across the path: the field depends on time, so each RK4 stage must see the
    // obstacle where it is at that stage's time.
    let moving = || {
        let e = paper_ellipse();
        Obstacle::new("drifting", e.shape().clone(), vec![-0.3, 0.9], None, Some(vec![-0.3, -0.2])).unwrap()
    };
    let make = || field(vec![moving()], static_volumetric(10.0, 1.0), 2);
    assert_acts(make);
    assert_fourth_order("moving static volumetric", make);
}

// -----------------------------------------------------------------------------------------------------------
// Replaying a demonstration
// -----------------------------------------------------------------------------------------------------------

/// Learns `curve` sampled every millisecond over `[t0, t0 + duration]`, rolls it out at 1 ms with no
/// obstacle, and checks the replay: the largest deviation after the first 10 % of the time is within 1e-2 of
/// the span, and the end point is within 1e-3 of the span of the goal. Returns the relative deviation.
fn assert_replays(label: &str, t0: f64, duration: f64, curve: impl Fn(f64) -> Vec<f64>) -> f64 {
    let n = (duration / 1e-3).round() as usize;
    let times: Vec<f64> = (0..=n).map(|k| t0 + k as f64 * 1e-3).collect();
    let demo = demo_of(&times, &curve);
    let p = learn(&demo, &LearnConfig::paper()).unwrap();
    assert!((p.tau - duration).abs() < 1e-9);
    let dim = demo.dim();
    let r = rollout(&p, &Motion::of(&p), &mut empty_field(dim), 1e-3, n).unwrap();
    assert!(r.trajectory.is_finite());
    let span = span(demo.positions());
    let dev = (0..=n)
        .filter(|&k| k as f64 >= 0.1 * n as f64)
        .map(|k| dist(r.trajectory.position(k), &demo.positions()[k]))
        .fold(0.0, f64::max);
    let goal = &demo.positions()[n];
    let end = dist(last_position(&r), goal);
    eprintln!(
        "replay {label}: span {span:.3}, max deviation after 10 % {dev:.3e} ({:.2e} of the span), \
         end {end:.2e} from the goal",
        dev / span
    );
    assert!(dev <= 1e-2 * span, "{label}: deviation {dev} for a span of {span}");
    assert!(end <= 1e-3 * span, "{label}: ends {end} from the goal");
    dev / span
}

#[test]
fn a_learned_primitive_replays_the_papers_curve() {
    assert_replays("paper 2-D", 0.0, 1.0, paper_curve);
}

#[test]
fn a_learned_primitive_replays_a_3d_demonstration_of_two_seconds() {
    // The paper's spiral, lifted along z, played over two seconds (so tau = 2).
    assert_replays("3-D, 2 s", 0.0, 2.0, |t| {
        let u = t / 2.0;
        vec![u * (PI * u).cos(), u * (PI * u).sin(), 0.4 * (PI * u).sin().powi(2) + 0.2 * u]
    });
}

#[test]
fn a_learned_primitive_replays_a_1d_demonstration_that_does_not_start_at_zero() {
    assert_replays("1-D, t in [5, 6.5]", 5.0, 1.5, |t| {
        let u = (t - 5.0) / 1.5;
        vec![0.5 * (1.0 - (PI * u).cos()) + 0.2 * (3.0 * PI * u).sin()]
    });
}

/// Positions of a no-obstacle rollout, row-major.
fn free_rollout(p: &Primitive, dt: f64, steps: usize) -> Vec<f64> {
    rollout(p, &Motion::of(p), &mut empty_field(p.dim), dt, steps).unwrap().trajectory.x
}

proptest! {
    #![proptest_config(config(12))]

    /// Random increasing sample times (each of `n` intervals jittered by up to 45 % of its nominal length)
    /// learn the same motion as the uniform 1 ms sampling.
    #[test]
    fn a_non_uniformly_sampled_demonstration_learns_the_same_curve(
        n in 400usize..1500,
        jitter in prop::collection::vec(-0.45f64..0.45, 1500),
    ) {
        a_non_uniformly_sampled_demonstration_learns_the_same_curve_case(n, jitter)?;
    }
}

fn a_non_uniformly_sampled_demonstration_learns_the_same_curve_case(
    n: usize,
    jitter: Vec<f64>,
) -> Result<(), TestCaseError> {
    let mut times: Vec<f64> =
        (0..=n).map(|k| (k as f64 + if k == 0 || k == n { 0.0 } else { jitter[k] }) / n as f64).collect();
    times[n] = 1.0;
    let p = learn(&demo_of(&times, paper_curve), &LearnConfig::paper()).unwrap();
    prop_assert!((p.tau - 1.0).abs() < 1e-12);
    let (a, b) = (free_rollout(&PAPER, 1e-3, 1000), free_rollout(&p, 1e-3, 1000));
    let dev = a.chunks(2).zip(b.chunks(2)).map(|(a, b)| dist(a, b)).fold(0.0, f64::max);
    let span = span(demo_of(&uniform_times(), paper_curve).positions());
    eprintln!(
        "non-uniform sampling, {n} intervals: max difference from the uniform one {:.2e} of the span",
        dev / span
    );
    prop_assert!(dev <= 5e-4 * span, "difference {} for a span of {}", dev, span);
    Ok(())
}

// -----------------------------------------------------------------------------------------------------------
// Time scaling and spatial generalisation
// -----------------------------------------------------------------------------------------------------------

fn motion(start: Vec<f64>, goal: Vec<f64>, tau: f64) -> Motion {
    Motion { start, goal, tau }
}

proptest! {
    #![proptest_config(config(10))]

    /// With no obstacle, `x_{2 tau}(2 t) = x_tau(t)`: with the same `dt` for both the two differ by the
    /// integration error only, and with `dt` doubled for the slow one RK4 makes the very same steps (to
    /// rounding).
    #[test]
    fn doubling_tau_plays_the_same_path_twice_as_slowly(
        tau in 0.5f64..1.5,
        shift in prop::array::uniform2(-1.0f64..1.0),
    ) {
        doubling_tau_plays_the_same_path_twice_as_slowly_case(tau, shift)?;
    }
}

fn doubling_tau_plays_the_same_path_twice_as_slowly_case(
    tau: f64,
    shift: [f64; 2],
) -> Result<(), TestCaseError> {
    let p = &*PAPER;
    let start: Vec<f64> = p.start.iter().zip(shift).map(|(s, d)| s + d).collect();
    let fast_motion = motion(start.clone(), p.goal.clone(), tau);
    let slow_motion = motion(start, p.goal.clone(), 2.0 * tau);
    let dt = 5e-4;
    let n = (1.5 * tau / dt).round() as usize;
    let fast = rollout(p, &fast_motion, &mut empty_field(2), dt, n).unwrap().trajectory;
    let slow = rollout(p, &slow_motion, &mut empty_field(2), dt, 2 * n).unwrap().trajectory;
    let slow_2dt = rollout(p, &slow_motion, &mut empty_field(2), 2.0 * dt, n).unwrap().trajectory;
    let span = (0..=n).map(|k| dist(fast.position(k), fast.position(0))).fold(0.0, f64::max);
    let (mut same_dt, mut double_dt, mut velocity) = (0.0f64, 0.0f64, 0.0f64);
    for k in 0..=n {
        same_dt = same_dt.max(dist(fast.position(k), slow.position(2 * k)));
        double_dt = double_dt.max(dist(fast.position(k), slow_2dt.position(k)));
        // dx/dt halves.
        let half: Vec<f64> = fast.velocity(k).iter().map(|v| 0.5 * v).collect();
        velocity = velocity.max(dist(&half, slow.velocity(2 * k)));
    }
    eprintln!(
        "time scaling, tau {tau:.3}: same dt {:.2e}, doubled dt {:.2e} of the span",
        same_dt / span,
        double_dt / span
    );
    prop_assert!(span > 0.5);
    prop_assert!(same_dt <= 1e-6 * span, "same dt: {}", same_dt);
    prop_assert!(velocity <= 1e-5 * span, "velocity: {}", velocity);
    prop_assert!(double_dt <= 1e-12 * span, "doubled dt: {}", double_dt);
    Ok(())
}

proptest! {
    #![proptest_config(config(10))]

    /// A new start and goal: the rollout starts at rest at the new start and converges to the new goal.
    #[test]
    fn new_start_and_goal_are_reached(
        start in prop::array::uniform2(-2.0f64..2.0),
        goal in prop::array::uniform2(-2.0f64..2.0),
        tau in 0.5f64..2.0,
    ) {
        new_start_and_goal_are_reached_case(start, goal, tau)?;
    }
}

fn new_start_and_goal_are_reached_case(
    start: [f64; 2],
    goal: [f64; 2],
    tau: f64,
) -> Result<(), TestCaseError> {
    let p = &*PAPER;
    let m = motion(start.to_vec(), goal.to_vec(), tau);
    let r = run(p, &m, &mut empty_field(2), 1e-3, (3.0 * tau * 1e3).round() * 1e-3);
    let t = &r.trajectory;
    prop_assert!(t.is_finite());
    prop_assert_eq!(t.position(0), &start[..]);
    prop_assert_eq!(t.velocity(0), &[0.0, 0.0][..]);
    let scale = 1.0 + dist(&start, &goal);
    let end = dist(last_position(&r), &goal);
    // At t = tau / 2 it is still on its way: the forcing term shapes the path, it does not jump to the goal.
    let mid = dist(t.position(t.len() / 6), &goal);
    prop_assert!(end <= 1e-3 * scale, "ends {} from the goal", end);
    prop_assert!(norm(t.velocity(t.len() - 1)) <= 1e-2 * scale / tau);
    prop_assert!(mid > 10.0 * end);
    Ok(())
}

// -----------------------------------------------------------------------------------------------------------
// Save and load
// -----------------------------------------------------------------------------------------------------------

fn assert_same_bits(a: &[f64], b: &[f64]) {
    assert_eq!(a.len(), b.len());
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        assert_eq!(x.to_bits(), y.to_bits(), "entry {i}: {x} vs {y}");
    }
}

fn save_and_load(p: &Primitive) -> Primitive {
    let json = serde_json::to_string(p).unwrap();
    let q: Primitive = serde_json::from_str(&json).unwrap();
    q.validate().unwrap();
    q
}

#[test]
fn a_saved_and_loaded_primitive_replays_bit_for_bit() {
    let p = PAPER.clone();
    let q = save_and_load(&p);
    assert_eq!(p, q);
    for w in [&p.weights, &q.weights] {
        assert!(w.iter().flatten().any(|w| w.fract() != 0.0), "weights with nothing to lose");
    }
    let m = Motion::of(&p);
    let make = || field(vec![paper_ellipse()], dynamic_volumetric(10.0, 2.0, 0.5), 2);
    let a = run(&p, &m, &mut make(), 1e-3, 1.0);
    let b = run(&q, &Motion::of(&q), &mut make(), 1e-3, 1.0);
    assert_same_bits(&a.trajectory.x, &b.trajectory.x);
    assert_same_bits(&a.trajectory.xd, &b.trajectory.xd);
    assert_same_bits(&a.trajectory.xdd, &b.trajectory.xdd);
}

#[test]
fn a_loaded_primitive_that_breaks_a_rule_is_refused() {
    let json = serde_json::to_value(&*PAPER).unwrap();
    let broken = |path: &str, value: serde_json::Value| {
        let mut j = json.clone();
        *j.pointer_mut(path).unwrap() = value;
        serde_json::from_value::<Primitive>(j).unwrap()
    };
    assert!(broken("/format_version", 2.into()).validate().is_err());
    assert!(broken("/tau", (-1.0).into()).validate().is_err());
    assert!(broken("/weights/1", serde_json::json!([1.0, 2.0])).validate().is_err());
    assert!(broken("/k", serde_json::json!([1050.0])).validate().is_err());
    assert!(broken("/dim", 3.into()).validate().is_err());
    let mut extra = json.clone();
    extra["comment"] = "hello".into();
    assert!(serde_json::from_value::<Primitive>(extra).is_err());
}

/// Any finite double: normal, subnormal or zero, of either sign.
fn any_finite() -> impl Strategy<Value = f64> {
    prop::num::f64::POSITIVE
        | prop::num::f64::NEGATIVE
        | prop::num::f64::NORMAL
        | prop::num::f64::SUBNORMAL
        | prop::num::f64::ZERO
}

proptest! {
    #![proptest_config(config(64))]

    /// Any finite weights and gains survive a JSON round trip exactly.
    #[test]
    fn every_finite_number_survives_a_json_round_trip(
        weights in prop::collection::vec(any_finite(), 3 * 11),
        k in prop::array::uniform3(1e-3f64..1e6),
        tau in 1e-3f64..1e3,
    ) {
        every_finite_number_survives_a_json_round_trip_case(weights, k, tau)?;
    }
}

fn every_finite_number_survives_a_json_round_trip_case(
    weights: Vec<f64>,
    k: [f64; 3],
    tau: f64,
) -> Result<(), TestCaseError> {
    let mut p =
        Primitive::straight_line(10, 4.0, k.to_vec(), None, tau, vec![0.1, -0.2, 0.3], vec![1.0, 2.0, 3.0])
            .unwrap();
    p.weights = weights.chunks(11).map(|c| c.to_vec()).collect();
    let q = save_and_load(&p);
    for (a, b) in p.weights.iter().flatten().zip(q.weights.iter().flatten()) {
        prop_assert_eq!(a.to_bits(), b.to_bits());
    }
    prop_assert_eq!(p, q);
    Ok(())
}

// -----------------------------------------------------------------------------------------------------------
// Changing the motion between two steps
// -----------------------------------------------------------------------------------------------------------

proptest! {
    #![proptest_config(config(16))]

    /// From step `k0` on, a new start, goal and tau. The state carries `dx/dt`, so the acceleration right
    /// after the switch must be the paper's with the new motion and `v = tau' dx/dt`; the steps stay small,
    /// the phase keeps decaying from where it was, and the robot converges to the new goal.
    #[test]
    fn changing_goal_start_and_tau_mid_run_is_smooth(
        k0 in 50usize..800,
        goal_shift in prop::array::uniform2(-1.0f64..1.0),
        start_shift in prop::array::uniform2(-1.0f64..1.0),
        tau_factor in 0.5f64..2.0,
    ) {
        changing_goal_start_and_tau_mid_run_is_smooth_case(k0, goal_shift, start_shift, tau_factor)?;
    }
}

fn changing_goal_start_and_tau_mid_run_is_smooth_case(
    k0: usize,
    goal_shift: [f64; 2],
    start_shift: [f64; 2],
    tau_factor: f64,
) -> Result<(), TestCaseError> {
    let p = &*PAPER;
    let (dt, d) = (1e-3, 2);
    let a = Motion::of(p);
    let b = motion(
        a.start.iter().zip(start_shift).map(|(s, x)| s + x).collect(),
        a.goal.iter().zip(goal_shift).map(|(g, x)| g + x).collect(),
        a.tau * tau_factor,
    );
    let mut integrator = Integrator::new(p).unwrap();
    let mut field = empty_field(d);
    let mut state = State::at_rest(&a.start);
    let mut acc = vec![0.0; d];
    let steps = k0 + (4.0 * b.tau / dt) as usize;
    let (mut xs, mut xds, mut accs) = (vec![state.x.clone()], vec![state.xd.clone()], Vec::new());
    for k in 0..steps {
        let m = if k < k0 { &a } else { &b };
        if k == k0 {
            // The paper's acceleration under both motions at the switch state: the forcing term K f(s) is
            // the same, so the one under `b` follows from the one under `a`.
            let (mut acc_a, mut acc_b) = (vec![0.0; d], vec![0.0; d]);
            integrator.acceleration(&a, &mut field, state.t, state.s, &state.x, &state.xd, &mut acc_a);
            integrator.acceleration(&b, &mut field, state.t, state.s, &state.x, &state.xd, &mut acc_b);
            for i in 0..d {
                let (kk, dd, x, xd, s) = (p.k[i], p.d[i], state.x[i], state.xd[i], state.s);
                let kf = a.tau * a.tau * acc_a[i] - kk * (a.goal[i] - x)
                    + dd * a.tau * xd
                    + kk * (a.goal[i] - a.start[i]) * s;
                let want = (kk * (b.goal[i] - x) - dd * b.tau * xd - kk * (b.goal[i] - b.start[i]) * s + kf)
                    / (b.tau * b.tau);
                prop_assert!(
                    (acc_b[i] - want).abs() <= 1e-9 * (1.0 + want.abs()),
                    "acc {} vs {}",
                    acc_b[i],
                    want
                );
            }
            let s_before = state.s;
            let mut probe = state.clone();
            integrator.step(&b, &mut field, &mut probe, dt, &mut acc);
            let s_want = s_before * (-p.alpha * dt / b.tau).exp();
            prop_assert!((probe.s - s_want).abs() <= 1e-14 * s_want, "phase {} vs {}", probe.s, s_want);
        }
        integrator.step(m, &mut field, &mut state, dt, &mut acc);
        prop_assert!(state.x.iter().chain(&state.xd).all(|v| v.is_finite()));
        accs.push(acc.clone());
        xs.push(state.x.clone());
        xds.push(state.xd.clone());
    }
    let acc_max = accs.iter().map(|a| norm(a)).fold(0.0, f64::max);
    let speed_max = xds.iter().map(|v| norm(v)).fold(0.0, f64::max);
    for k in k0.saturating_sub(5)..(k0 + 50).min(steps) {
        let dx = dist(&xs[k + 1], &xs[k]);
        let dxd = dist(&xds[k + 1], &xds[k]);
        let local_acc = norm(&accs[k]).max(norm(&accs[(k + 1).min(steps - 1)]));
        prop_assert!(dx <= dt * speed_max * 1.01, "step {}: |dx| {} > dt max|xd|", k, dx);
        prop_assert!(
            dxd <= dt * local_acc * 1.1 + 1e-12,
            "step {}: |dxd| {} vs dt |acc| {}",
            k,
            dxd,
            dt * local_acc
        );
        prop_assert!(dxd <= dt * acc_max, "step {}: |dxd| {} > dt max|acc|", k, dxd);
    }
    let end = dist(&state.x, &b.goal);
    prop_assert!(end <= 1e-3 * (1.0 + dist(&b.start, &b.goal)), "ends {} from the new goal", end);
    Ok(())
}

// -----------------------------------------------------------------------------------------------------------
// Guard rails: never NaN or infinity, contacts and stalls reported
// -----------------------------------------------------------------------------------------------------------

/// All five methods, and the two dynamic ones with beta = 1 (where they jump at the switch).
fn all_methods() -> Vec<Method> {
    let mut m = paper_methods().to_vec();
    m.push(dynamic_point(0.2, 1.0));
    m.push(dynamic_volumetric(10.0, 1.0, 0.5));
    m
}

#[test]
fn a_start_inside_an_obstacle_gives_a_finite_trajectory_and_a_contact() {
    let p = &*PAPER;
    let shape = superquadric(&[0.2, 0.15], &[1.0, 1.0]);
    let obstacles = [
        // Off-centre around the start, still.
        Obstacle::new("still", shape.clone(), vec![0.05, -0.03], None, None).unwrap(),
        // Centred exactly on the start, where grad C = 0.
        Obstacle::new("centred", shape.clone(), vec![0.0, 0.0], None, None).unwrap(),
        // Around the start and moving along with the robot's first direction of motion.
        Obstacle::new("moving", shape, vec![0.1, 0.0], None, Some(vec![0.5, 0.2])).unwrap(),
    ];
    for method in all_methods() {
        for o in &obstacles {
            let mut f = field(vec![o.clone()], method, 2);
            let r = run(p, &Motion::of(p), &mut f, 1e-3, 1.0);
            let label = format!("{} in {}", method.name(), o.id());
            assert!(r.trajectory.is_finite(), "{label}: not finite");
            let (row, contact) = r.contacts.first().copied().unwrap_or_else(|| panic!("{label}: no contact"));
            assert_eq!(row, 0, "{label}");
            match contact {
                Contact::Obstacle { agent: 0, obstacle: 0, c } => assert!(c <= 0.0, "{label}: C = {c}"),
                other => panic!("{label}: {other:?}"),
            }
            assert!(r.contacts.iter().all(|(_, c)| matches!(c, Contact::Obstacle { .. })));
        }
    }
}

#[test]
fn a_robot_at_rest_feels_no_dynamic_term_and_stays_finite() {
    // start = goal and no forcing term: only a repulsive term could move the robot.
    let p = Primitive::straight_line(50, 4.0, vec![1050.0; 2], None, 1.0, vec![0.0, 0.0], vec![0.0, 0.0])
        .unwrap();
    let near = ellipsoid("near", &[0.25, 0.0], &[0.2, 0.2]);
    for method in [
        dynamic_point(0.2, 2.0),
        dynamic_point(0.2, 1.0),
        paper_methods()[2],
        dynamic_volumetric(10.0, 2.0, 0.5),
    ] {
        let r = run(&p, &Motion::of(&p), &mut field(vec![near.clone()], method, 2), 1e-3, 0.5);
        assert!(r.trajectory.is_finite(), "{}", method.name());
        assert!(r.trajectory.x.iter().all(|&x| x == 0.0), "{}: a robot at rest moved", method.name());
    }
    // The static terms do push it, so the test above could see a motion.
    let r =
        run(&p, &Motion::of(&p), &mut field(vec![near.clone()], static_volumetric(10.0, 1.0), 2), 1e-3, 0.5);
    assert!(last_position(&r)[0] < -1e-3);
    // An obstacle coming at a robot at rest: the relative velocity is not zero, the dynamic terms push it
    // away.
    let coming = Obstacle::new(
        "coming",
        superquadric(&[0.2, 0.2], &[1.0, 1.0]),
        vec![0.8, 0.0],
        None,
        Some(vec![-1.0, 0.0]),
    )
    .unwrap();
    for method in
        [dynamic_point(0.2, 2.0), dynamic_volumetric(10.0, 2.0, 0.5), dynamic_volumetric(10.0, 1.0, 0.5)]
    {
        let r = run(&p, &Motion::of(&p), &mut field(vec![coming.clone()], method, 2), 1e-3, 1.0);
        assert!(r.trajectory.is_finite(), "{}", method.name());
        let pushed = (0..r.trajectory.len()).map(|k| r.trajectory.position(k)[0]).fold(0.0, f64::min);
        assert!(pushed < -1e-2, "{}: pushed only to {pushed}", method.name());
    }
    // The steering angle rotates the robot's own velocity: at rest it does nothing, and the obstacle runs it
    // over.
    let r = run(&p, &Motion::of(&p), &mut field(vec![coming], paper_methods()[2], 2), 1e-3, 1.0);
    assert!(r.trajectory.is_finite());
    assert!(obstacle_contacts(&r) > 0);
}

#[test]
fn a_robot_stuck_in_front_of_a_large_disc_is_reported_as_stalled() {
    // Aimed straight through the centre of a disc: by symmetry the static potential only pushes back along
    // the line, and the robot stops where it balances the attraction to the goal.
    let p = Primitive::straight_line(50, 4.0, vec![1050.0; 2], None, 1.0, vec![0.0, 0.0], vec![2.0, 0.0])
        .unwrap();
    let disc = ellipsoid("disc", &[1.0, 0.0], &[0.5, 0.5]);
    let r = run(&p, &Motion::of(&p), &mut field(vec![disc], static_volumetric(10.0, 1.0), 2), 1e-3, 3.0);
    assert!(r.trajectory.is_finite());
    assert!(r.contacts.is_empty(), "{:?}", r.contacts.first());
    let end = last_position(&r);
    assert!(end[0] < 0.5 && end[1] == 0.0, "ends at {end:?}");
    let &(robot, stall) = r.stalls.first().expect("no stall reported");
    eprintln!(
        "stall: robot {robot} stopped at t = {:.3} s, {:.3} from its goal, at x = {:.3}",
        stall.since, stall.distance, end[0]
    );
    assert_eq!(robot, 0);
    assert!(stall.distance > 1.0 && stall.since < stall.detected_at && stall.detected_at < 3.0);
    // Without the disc it arrives and nothing is reported.
    let free = run(&p, &Motion::of(&p), &mut empty_field(2), 1e-3, 3.0);
    assert!(free.stalls.is_empty());
    assert!(dist(last_position(&free), &p.goal) < 1e-3);
}

#[test]
fn the_dynamic_terms_are_finite_exactly_at_their_switch_and_jump_there_only_for_beta_1() {
    // A disc of radius 0.2 at the origin (one boundary sample for the point method, at (0.2, 0)). The robot
    // is at `x` with velocity (1, -e): for e = 0 it moves exactly perpendicular to grad C (cos theta = 0, the
    // switch), for e > 0 slightly toward the obstacle.
    let disc = ellipsoid("disc", &[0.0, 0.0], &[0.2, 0.2]);
    let phi = |method: Method, x: [f64; 2], e: f64| {
        let scene = Scene::with_obstacles(vec![disc.clone()], Avoidance::new(method), 1);
        let mut f = RepulsiveField::new(scene, 2).unwrap();
        let mut out = [0.0; 2];
        f.add(0.0, &x, &[1.0, -e], 1.0, &mut out);
        assert!(out.iter().all(|v| v.is_finite()), "{} at e = {e}: {out:?}", method.name());
        norm(&out)
    };
    for (method, x) in [
        (dynamic_volumetric(10.0, 1.0, 0.5), [0.0, 0.5]),
        (dynamic_volumetric(10.0, 2.0, 0.5), [0.0, 0.5]),
        (dynamic_point(0.2, 1.0), [0.2, 0.5]),
        (dynamic_point(0.2, 2.0), [0.2, 0.5]),
    ] {
        let (at, past) = (phi(method, x, 0.0), phi(method, x, 1e-9));
        let beta = match method {
            Method::DynamicVolumetric(p) => p.beta,
            Method::DynamicPoint(p) => p.beta,
            _ => unreachable!(),
        };
        eprintln!("{} beta {beta}: |phi| at the switch {at:.3e}, just past it {past:.3e}", method.name());
        assert_eq!(at, 0.0);
        if beta == 1.0 {
            assert!(past > 1e-2, "{}: no jump for beta = 1 ({past})", method.name());
        } else {
            assert!(past < 1e-6, "{}: jump for beta = 2 ({past})", method.name());
        }
    }
    // Rollouts through the paper's scene cross the switch: finite, and with beta = 1 still no collision.
    let p = &*PAPER;
    for method in [dynamic_point(0.2, 1.0), dynamic_volumetric(10.0, 1.0, 0.5)] {
        let r = run(p, &Motion::of(p), &mut field(vec![paper_ellipse()], method, 2), 1e-3, 1.0);
        assert!(r.trajectory.is_finite(), "{}", method.name());
        assert!(r.contacts.is_empty(), "{}: {:?}", method.name(), r.contacts.first());
    }
}

/// Points where the terms have a singular or degenerate form: the centre, a boundary sample, the surface,
/// inside.
fn special_point() -> impl Strategy<Value = [f64; 2]> {
    prop_oneof![
        Just([-0.5, 0.7]),
        Just([-0.2, 0.7]),
        Just([-0.5, 0.5]),
        Just([-0.5, 0.6]),
        Just([-0.5 + 0.3 * (2.0 * PI / 50.0).cos(), 0.7 + 0.2 * (2.0 * PI / 50.0).sin()]),
        prop::array::uniform2(-1.5f64..0.5),
    ]
}

fn special_velocity() -> impl Strategy<Value = [f64; 2]> {
    prop_oneof![
        Just([0.0, 0.0]),
        Just([1.0, 0.0]),
        Just([0.0, -1.0]),
        Just([1e-300, 0.0]),
        prop::array::uniform2(-5.0f64..5.0)
    ]
}

proptest! {
    #![proptest_config(config(256))]

    /// Every method, still or moving obstacle, at any point (inside included) and any velocity (zero
    /// included): the term is finite.
    #[test]
    fn every_term_is_finite_everywhere(
        x in special_point(),
        v in special_velocity(),
        velocity in prop_oneof![Just([0.0, 0.0]), prop::array::uniform2(-1.0f64..1.0)],
        t in 0.0f64..1.0,
        tau in 0.5f64..2.0,
    ) {
        every_term_is_finite_everywhere_case(x, v, velocity, t, tau)?;
    }
}

fn every_term_is_finite_everywhere_case(
    x: [f64; 2],
    v: [f64; 2],
    velocity: [f64; 2],
    t: f64,
    tau: f64,
) -> Result<(), TestCaseError> {
    // The paper's ellipse, still or moving.
    let shape = paper_ellipse().shape().clone();
    let o = Obstacle::new("o", shape, vec![-0.5, 0.7], None, Some(velocity.to_vec())).unwrap();
    for method in all_methods() {
        let mut f = field(vec![o.clone()], method, 2);
        let mut out = [0.0; 2];
        f.add(t, &x, &v, tau, &mut out);
        prop_assert!(out.iter().all(|p| p.is_finite()), "{}: {:?}", method.name(), out);
    }
    Ok(())
}

// -----------------------------------------------------------------------------------------------------------
// Several robots on one phase
// -----------------------------------------------------------------------------------------------------------

/// Three robots on a circle of radius 1, each going to the point opposite its start turned by `skew`: the
/// three straight paths pass close to the centre at the same time. Everything is turned by `turn`.
fn three_robots(turn: f64, skew: f64, robot_avoidance: Method) -> (Primitive, RepulsiveField) {
    let (mut start, mut goal) = (Vec::new(), Vec::new());
    for i in 0..3 {
        let a = turn + 2.0 * PI * i as f64 / 3.0;
        let b = a + PI + skew;
        start.extend([a.cos(), a.sin()]);
        goal.extend([b.cos(), b.sin()]);
    }
    let p = Primitive::straight_line(50, 4.0, vec![1050.0; 6], None, 1.0, start, goal).unwrap();
    let agents = (0..3)
        .map(|i| Agent {
            id: format!("r{i}"),
            dims: vec![2 * i, 2 * i + 1],
            footprint: Some(superquadric(&[0.3, 0.3], &[1.0, 1.0])),
        })
        .collect();
    let scene = Scene {
        obstacles: Vec::new(),
        avoidance: Avoidance::NONE,
        agents,
        robot_avoidance: Avoidance::new(robot_avoidance),
        point_samples: 50,
    };
    (p, RepulsiveField::new(scene, 6).unwrap())
}

fn robot_contacts(r: &Rollout) -> usize {
    r.contacts.iter().filter(|(_, c)| matches!(c, Contact::Robot { .. })).count()
}

fn min_pair_distance(r: &Rollout) -> f64 {
    let t = &r.trajectory;
    let mut min = f64::INFINITY;
    for k in 0..t.len() {
        let x = t.position(k);
        for i in 0..3 {
            for j in i + 1..3 {
                min = min.min(dist(&x[2 * i..2 * i + 2], &x[2 * j..2 * j + 2]));
            }
        }
    }
    min
}

proptest! {
    #![proptest_config(config(8))]

    #[test]
    fn three_crossing_robots_avoid_each_other_and_arrive(
        turn in 0.0f64..(2.0 * PI),
        skew_deg in 5.0f64..12.0,
    ) {
        three_crossing_robots_avoid_each_other_and_arrive_case(turn, skew_deg)?;
    }
}

fn three_crossing_robots_avoid_each_other_and_arrive_case(
    turn: f64,
    skew_deg: f64,
) -> Result<(), TestCaseError> {
    let skew = skew_deg.to_radians();
    let (p, mut blind) = three_robots(turn, skew, Method::None);
    let collide = run(&p, &Motion::of(&p), &mut blind, 1e-3, 3.0);
    prop_assert!(robot_contacts(&collide) > 0, "the paths do not cross: nothing to avoid");
    let (p, mut careful) = three_robots(turn, skew, dynamic_volumetric(60.0, 2.0, 0.2));
    let r = run(&p, &Motion::of(&p), &mut careful, 1e-3, 3.0);
    let (closest_blind, closest) = (min_pair_distance(&collide), min_pair_distance(&r));
    eprintln!(
        "three robots, skew {skew_deg:.1} deg: closest centres {closest_blind:.3} without avoidance, \
         {closest:.3} with"
    );
    prop_assert!(r.trajectory.is_finite());
    prop_assert_eq!(robot_contacts(&r), 0, "{:?}", r.contacts.first());
    prop_assert!(closest > 0.3);
    prop_assert!(r.stalls.is_empty(), "{:?}", r.stalls);
    let end = last_position(&r);
    for i in 0..3 {
        let d = dist(&end[2 * i..2 * i + 2], &p.goal[2 * i..2 * i + 2]);
        prop_assert!(d < 1e-3, "robot {} ends {} from its goal", i, d);
    }
    Ok(())
}
