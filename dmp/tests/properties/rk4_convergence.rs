//! RK4 convergence: the error falls sixteenfold when `dt` halves, with and without obstacles.

use dmp::{Integrator, Motion, Obstacle, Perturbation, RepulsiveField, State};

use crate::fixtures::{
    PAPER, dist, dynamic_volumetric, ellipsoid, empty_field, field, integrate_to, norm, paper_ellipse, run,
    static_volumetric,
};

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
    let free = run(p, &Motion::of(p), &empty_field(2), 1e-3, 1.0).trajectory;
    let pushed = run(p, &Motion::of(p), &make_field(), 1e-3, 1.0).trajectory;
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
