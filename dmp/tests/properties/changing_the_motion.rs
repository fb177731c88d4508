//! Changing the motion between two steps.

use dmp::{Integrator, Motion, State};
use proptest::prelude::*;

use crate::fixtures::{PAPER, config, dist, empty_field, motion, norm};

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
