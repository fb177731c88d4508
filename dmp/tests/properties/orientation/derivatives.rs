//! The angular velocity and acceleration a run hands out are the derivatives of its orientations: world frame,
//! `q̇ = ½ (0, ω) ⊗ q`, checked against finite differences of the output, which must converge at their order.

use dmp::orientation::quaternion::log;
use dmp::{OrientationMotion, OrientationPrimitive, OrientationRun, rollout_orientation};
use nalgebra::Vector3;

use super::fixtures::{CHANGING, DT, SINGLE, new_motion};

/// Both primitives, with the demonstration's motion and a new one (whose path no longer keeps a fixed axis).
fn cases() -> Vec<(&'static str, OrientationMotion, &'static OrientationPrimitive)> {
    let mut out = Vec::new();
    for (name, p) in [("single axis", &*SINGLE), ("changing axis", &*CHANGING)] {
        out.push((name, OrientationMotion::of(p).unwrap(), p));
        out.push((name, new_motion(p), p));
    }
    out
}

/// Largest differences, over the interior rows of a run at step `dt`, between the output and finite differences
/// of the output, with the largest `|ω|` and `|ω̇|`.
#[derive(Debug)]
struct Errors {
    /// `ω` against `log(q_{k+1} ⊗ q̄_{k-1}) / 2dt` (the rotation vector over `2 dt`, world frame): `O(dt²)`.
    central: f64,
    /// `ω` against `log(q_{k+1} ⊗ q̄_k) / dt`, that is `2 log(q_{k+1} ⊗ q̄_k) / dt` with the half-angle logarithm:
    /// `O(dt)`.
    forward: f64,
    /// `ω̇` against `(ω_{k+1} - ω_{k-1}) / 2dt`: `O(dt²)`.
    acceleration: f64,
    omega: f64,
    omega_dot: f64,
}

fn errors(p: &OrientationPrimitive, m: &OrientationMotion, dt: f64) -> Errors {
    let tr = rollout_orientation(p, m, dt, (1.5 * m.tau / dt).round() as usize).unwrap();
    let mut e = Errors { central: 0.0, forward: 0.0, acceleration: 0.0, omega: 0.0, omega_dot: 0.0 };
    for k in 1..tr.len() - 1 {
        let (omega, omega_dot) = (tr.angular_velocity(k), tr.angular_acceleration(k));
        let (before, here, after) = (tr.orientation(k - 1), tr.orientation(k), tr.orientation(k + 1));
        e.central = e.central.max((log(&(after * before.conjugate())) / (2.0 * dt) - omega).norm());
        e.forward = e.forward.max((log(&(after * here.conjugate())) / dt - omega).norm());
        let fd = (tr.angular_velocity(k + 1) - tr.angular_velocity(k - 1)) / (2.0 * dt);
        e.acceleration = e.acceleration.max((fd - omega_dot).norm());
        e.omega = e.omega.max(omega.norm());
        e.omega_dot = e.omega_dot.max(omega_dot.norm());
    }
    e
}

#[test]
fn the_angular_velocity_and_acceleration_are_the_derivatives_of_the_output() {
    for (name, m, p) in cases() {
        let (coarse, fine) = (errors(p, &m, DT), errors(p, &m, 0.5 * DT));
        for (dt, e) in [("dt", &coarse), ("dt / 2", &fine)] {
            eprintln!(
                "{name} at {dt}: |ω| <= {:.2}, |ω̇| <= {:.2}; central ω {:.1e}, forward ω {:.1e}, central ω̇ {:.1e}",
                e.omega, e.omega_dot, e.central, e.forward, e.acceleration
            );
        }
        assert!(coarse.omega > 0.5 && coarse.omega_dot > 1.0, "{name}: the run hardly turns");
        // Small, and falling at the order of each difference: a wrong ω or ω̇ (another frame, a missing term of
        // the Jacobian's derivative) would leave an error that does not fall with dt.
        assert!(coarse.central <= 1e-4 * coarse.omega, "{name}: {coarse:?}");
        assert!(coarse.forward <= 5e-3 * coarse.omega, "{name}: {coarse:?}");
        assert!(coarse.acceleration <= 1e-2 * coarse.omega_dot, "{name}: {coarse:?}");
        for (what, ratio, order) in [
            ("central ω", coarse.central / fine.central, 4.0),
            ("forward ω", coarse.forward / fine.forward, 2.0),
            ("central ω̇", coarse.acceleration / fine.acceleration, 4.0),
        ] {
            assert!((0.8 * order..1.25 * order).contains(&ratio), "{name}: {what} error falls by {ratio}");
        }
    }
}

#[test]
fn a_run_that_starts_turning_hands_out_that_angular_velocity() {
    let p = &*CHANGING;
    let m = new_motion(p);
    let omega0 = Vector3::new(0.3, -1.2, 0.5);
    let mut run = OrientationRun::moving(p, &m, omega0).unwrap();
    let first = run.sample();
    assert!((first.omega - omega0).norm() < 1e-14, "{:?}", first.omega);
    // The first step turns by ω0 dt + ω̇0 dt² / 2 + O(dt³) (the DMP's damping makes the O(dt³) term about
    // 2e-4 |ω0| dt here).
    run.step(DT).unwrap();
    let turned = log(&(run.sample().q * first.q.conjugate())) / DT;
    let expected = omega0 + first.omega_dot * (0.5 * DT);
    assert!((turned - expected).norm() < 1e-3 * omega0.norm(), "{turned:?} vs {expected:?}");
}
