//! Holding (pause, and the deceleration of a stop): the phase is frozen and the robot comes to rest under the DMP's
//! damping alone, integrated exactly.

use crate::integrate::State;
use crate::primitive::Primitive;

/// The damping a holding robot decelerates with, per dimension: the primitive's `D / tau`, or critical damping if
/// it has none (a robot must come to rest). `tau` is the run's own (the request's), not the one temporal coupling
/// stretched to keep the limits: a robot slowed tenfold must still stop as fast as its DMP would, the limiter keeping
/// the deceleration within the limits.
fn hold_rate(p: &Primitive, tau: f64, i: usize) -> f64 {
    let damping = if p.d[i] > 0.0 { p.d[i] } else { 2.0 * p.k[i].sqrt() };
    damping / tau
}

/// The holding acceleration `d2x/dt2 = -(D / tau) dx/dt`.
pub(super) fn hold_acc(p: &Primitive, tau: f64, xd: &[f64], acc: &mut [f64]) {
    for i in 0..p.dim {
        acc[i] = -hold_rate(p, tau, i) * xd[i];
    }
}

/// One step `h` of holding: the phase is frozen and the robot decelerates under the DMP's damping alone,
/// `d2x/dt2 = -(D / tau) dx/dt`, integrated exactly. Writes the acceleration before the step into `acc_before`.
pub(super) fn hold_step(p: &Primitive, tau: f64, state: &mut State, h: f64, acc_before: &mut [f64]) {
    hold_acc(p, tau, &state.xd, acc_before);
    for i in 0..p.dim {
        let k = hold_rate(p, tau, i);
        let v0 = state.xd[i];
        let decay = (-k * h).exp();
        state.x[i] += if k > 0.0 { v0 * (1.0 - decay) / k } else { v0 * h };
        state.xd[i] = v0 * decay;
    }
    state.t += h;
}
