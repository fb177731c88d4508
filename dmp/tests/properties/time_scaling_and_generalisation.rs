//! Time scaling and spatial generalisation.

use dmp::rollout;
use proptest::prelude::*;

use crate::fixtures::{PAPER, config, dist, empty_field, last_position, motion, norm, run};

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
    let fast = rollout(p, &fast_motion, &empty_field(2), dt, n).unwrap().trajectory;
    let slow = rollout(p, &slow_motion, &empty_field(2), dt, 2 * n).unwrap().trajectory;
    let slow_2dt = rollout(p, &slow_motion, &empty_field(2), 2.0 * dt, n).unwrap().trajectory;
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
    let r = run(p, &m, &empty_field(2), 1e-3, (3.0 * tau * 1e3).round() * 1e-3);
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
