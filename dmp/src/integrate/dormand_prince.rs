//! Dormand–Prince 5(4): an explicit Runge–Kutta pair whose fifth-order solution advances the run and whose
//! embedded fourth-order one estimates the step's error, so that a caller can choose the step.
//!
//! On `y = (x, dx/dt)`, `y' = (dx/dt, d²x/dt²)` (the acceleration of [`Integrator::acceleration`]), seven stages
//!
//! `k_i = f(t0 + c_i h, y0 + h Σ_j a_ij k_j)`, `y1 = y0 + h Σ_j b_j k_j`, `ê = h Σ_j e_j k_j`,
//!
//! with the coefficients of Dormand & Prince (1980), RK5(4)7M. The last stage is evaluated at `(t0 + h, y1)`
//! ("first same as last"): it is the acceleration at the new state, which the next step starts from and which a
//! dense output needs. The phase follows its closed form at each stage time. The error is measured per component
//! against `tol (1 + max(|y0|, |y1|))`, metres on positions and metres per second on velocities, and reported as
//! the largest ratio: a step is within the tolerance when it is at most 1.

use super::{Integrator, Perturbation, State};
use crate::canonical::phase_after;

/// Stage times, as fractions of the step.
const C: [f64; 7] = [0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0];

/// Stage coefficients `a_ij` (row `i`, the stages `j < i` it combines). Row 6 is the fifth-order solution `b`.
const A: [[f64; 6]; 7] = [
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [1.0 / 5.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
    [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
    [19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0, 0.0, 0.0],
    [9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0, 0.0],
    [35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0],
];

/// `e_j = b_j - b̂_j`: the fifth-order weights minus the embedded fourth-order ones.
const E: [f64; 7] =
    [71.0 / 57600.0, 0.0, -71.0 / 16695.0, 71.0 / 1920.0, -17253.0 / 339200.0, 22.0 / 525.0, -1.0 / 40.0];

/// Order of the error estimate plus one: the step-size exponent `1 / 5`.
pub(crate) const ERROR_ORDER: f64 = 5.0;

/// The stages of one step, allocated once.
#[derive(Debug, Clone)]
pub(super) struct Stages {
    kx: [Vec<f64>; 7],
    ka: [Vec<f64>; 7],
    xs: Vec<f64>,
    xds: Vec<f64>,
}

impl Stages {
    pub(super) fn new(dim: usize) -> Self {
        let z = || vec![0.0; dim];
        Self { kx: std::array::from_fn(|_| z()), ka: std::array::from_fn(|_| z()), xs: z(), xds: z() }
    }
}

impl Integrator {
    /// One Dormand–Prince 5(4) step of length `h` from `state`, which becomes the fifth-order solution. Writes the
    /// acceleration at the state before the step into `acc_before` (with `first_known`, it already holds it, as
    /// in [`Integrator::step_from`], and is not evaluated again) and the one at the new state into `acc_after`.
    /// Returns the error estimate scaled by `tol` (see the module): the caller accepts the step at or below 1, or
    /// restores its state and retries with a smaller `h`. Not finite if the state stopped being finite.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn step_dormand_prince<P: Perturbation + ?Sized>(
        &mut self,
        motion: &crate::Motion,
        perturbation: &mut P,
        state: &mut State,
        h: f64,
        acc_before: &mut [f64],
        first_known: bool,
        acc_after: &mut [f64],
        tol: f64,
    ) -> f64 {
        let d = self.dim;
        let (t0, s0) = (state.t, state.s);
        let mut st = std::mem::replace(&mut self.dp, Stages::new(0));
        st.kx[0].copy_from_slice(&state.xd);
        if first_known {
            st.ka[0].copy_from_slice(&acc_before[..d]);
        } else {
            self.acceleration(motion, perturbation, t0, s0, &state.x, &state.xd, &mut st.ka[0]);
        }
        let mut s_end = s0;
        for i in 1..7 {
            for k in 0..d {
                let (mut x, mut v) = (state.x[k], state.xd[k]);
                for j in 0..i {
                    x += h * A[i][j] * st.kx[j][k];
                    v += h * A[i][j] * st.ka[j][k];
                }
                st.xs[k] = x;
                st.xds[k] = v;
            }
            st.kx[i].copy_from_slice(&st.xds);
            let s = phase_after(s0, self.alpha, motion.tau, C[i] * h);
            self.acceleration(motion, perturbation, t0 + C[i] * h, s, &st.xs, &st.xds, &mut st.ka[i]);
            s_end = s;
        }
        // The last stage's state is the fifth-order solution.
        let mut err: f64 = 0.0;
        for k in 0..d {
            let (mut ex, mut ev) = (0.0, 0.0);
            for j in 0..7 {
                ex += E[j] * st.kx[j][k];
                ev += E[j] * st.ka[j][k];
            }
            let scale_x = tol * (1.0 + state.x[k].abs().max(st.xs[k].abs()));
            let scale_v = tol * (1.0 + state.xd[k].abs().max(st.xds[k].abs()));
            // A NaN anywhere (which `max` would drop) is an infinite error: the step is retried shorter.
            let (e_x, e_v) = ((h * ex).abs() / scale_x, (h * ev).abs() / scale_v);
            let finite = [e_x, e_v, st.xs[k], st.xds[k], st.ka[6][k]].iter().all(|v| v.is_finite());
            err = if finite { err.max(e_x).max(e_v) } else { f64::INFINITY };
        }
        acc_before[..d].copy_from_slice(&st.ka[0]);
        acc_after[..d].copy_from_slice(&st.ka[6]);
        state.x.copy_from_slice(&st.xs);
        state.xd.copy_from_slice(&st.xds);
        state.t = t0 + h;
        // The last stage is at the step's end (c = 1).
        state.s = s_end;
        self.dp = st;
        err
    }
}

/// The step after one of `h` whose scaled error was `err`: the classical controller
/// `h 0.9 err^(-1/5)`, changed by at most a factor of five either way (a non-finite error gives the smallest).
pub(crate) fn next_step(h: f64, err: f64) -> f64 {
    let factor = if err.is_finite() {
        if err == 0.0 { 5.0 } else { (0.9 * err.powf(-1.0 / ERROR_ORDER)).clamp(0.2, 5.0) }
    } else {
        0.2
    };
    h * factor
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Motion, NoPerturbation, Primitive};

    /// A curved demonstration in 2-D, with a non-zero forcing term.
    fn primitive() -> Primitive {
        let n = 400;
        let t: Vec<f64> = (0..n).map(|i| i as f64 * 0.005).collect();
        let x: Vec<Vec<f64>> =
            t.iter().map(|&t| vec![t.sin() + 0.3 * (3.0 * t).sin(), 1.0 - (1.5 * t).cos()]).collect();
        let demo = crate::learn::Demonstration::new(t, x).unwrap();
        let config = crate::learn::LearnConfig { k: vec![100.0], ..crate::learn::LearnConfig::paper() };
        crate::learn::learn(&demo, &config).unwrap()
    }

    /// A position-dependent push, smooth: `phi = 5 (sin 3 x1, cos 2 x0)`.
    struct Swirl;
    impl Perturbation for Swirl {
        fn add(&mut self, _: f64, x: &[f64], v: &[f64], _: f64, out: &mut [f64]) {
            out[0] += 5.0 * (3.0 * x[1]).sin() + 0.5 * v[1];
            out[1] += 5.0 * (2.0 * x[0]).cos();
        }
    }

    fn run_rk4(p: &Primitive, m: &Motion, h: f64, until: f64) -> State {
        let mut i = Integrator::new(p).unwrap();
        let mut s = State::at_rest(&m.start);
        let mut acc = vec![0.0; p.dim];
        for _ in 0..(until / h).round() as usize {
            i.step(m, &mut Swirl, &mut s, h, &mut acc);
        }
        s
    }

    fn run_dp(p: &Primitive, m: &Motion, h: f64, until: f64) -> (State, f64) {
        let mut i = Integrator::new(p).unwrap();
        let mut s = State::at_rest(&m.start);
        let (mut a0, mut a1) = (vec![0.0; p.dim], vec![0.0; p.dim]);
        let mut worst: f64 = 0.0;
        for k in 0..(until / h).round() as usize {
            let err = i.step_dormand_prince(m, &mut Swirl, &mut s, h, &mut a0, k > 0, &mut a1, 1.0);
            worst = worst.max(err);
            a0.copy_from_slice(&a1);
        }
        (s, worst)
    }

    fn dist(a: &State, b: &State) -> f64 {
        a.x.iter().zip(&b.x).chain(a.xd.iter().zip(&b.xd)).map(|(p, q)| (p - q).abs()).fold(0.0, f64::max)
    }

    #[test]
    fn the_solution_is_fifth_order_and_the_estimate_fourth() {
        let p = primitive();
        let m = Motion { start: vec![0.1, -0.2], goal: vec![1.2, 0.8], tau: 1.5 };
        let reference = run_rk4(&p, &m, 1e-4, 1.2);
        let (coarse, e_coarse) = run_dp(&p, &m, 0.01, 1.2);
        let (fine, e_fine) = run_dp(&p, &m, 0.005, 1.2);
        let (g_coarse, g_fine) = (dist(&coarse, &reference), dist(&fine, &reference));
        // Halving the step divides the global error by 2^5 = 32 and the local estimate by 2^5 as well (the
        // estimate is the fourth-order solution's local error, O(h^5)); at 0.04 -> 0.02 s the narrow Gaussians of
        // the forcing term keep both out of their asymptotic range, hence these steps.
        assert!(g_coarse / g_fine > 20.0, "global {g_coarse:e} -> {g_fine:e}");
        assert!(e_coarse / e_fine > 16.0 && e_coarse / e_fine < 64.0, "estimate {e_coarse:e} -> {e_fine:e}");
        assert!(g_fine < 1e-9, "{g_fine:e}");
    }

    #[test]
    fn the_estimate_bounds_the_error_of_one_step() {
        let p = primitive();
        let m = Motion { start: vec![0.1, -0.2], goal: vec![1.2, 0.8], tau: 1.5 };
        let mut s = run_rk4(&p, &m, 1e-4, 0.3);
        let reference = {
            let mut i = Integrator::new(&p).unwrap();
            let mut r = s.clone();
            let mut acc = vec![0.0; 2];
            for _ in 0..500 {
                i.step(&m, &mut Swirl, &mut r, 1e-4, &mut acc);
            }
            r
        };
        let mut i = Integrator::new(&p).unwrap();
        let (mut a0, mut a1) = (vec![0.0; 2], vec![0.0; 2]);
        let tol = 1e-9;
        let err = i.step_dormand_prince(&m, &mut Swirl, &mut s, 0.05, &mut a0, false, &mut a1, tol);
        // The estimate is that of the fourth-order solution: the fifth-order one is closer still.
        let actual = dist(&s, &reference) / (tol * 2.0);
        assert!(err > actual, "estimate {err} below the actual error {actual}");
        assert!(err < 1e6 * actual.max(1e-3), "estimate {err} far above {actual}");
    }

    #[test]
    fn the_last_stage_is_the_acceleration_at_the_new_state_and_a_known_first_stage_changes_nothing() {
        let p = primitive();
        let m = Motion { start: vec![0.1, -0.2], goal: vec![1.2, 0.8], tau: 1.5 };
        let mut i = Integrator::new(&p).unwrap();
        let mut s = State::at_rest(&m.start);
        let (mut a0, mut a1) = (vec![0.0; 2], vec![0.0; 2]);
        i.step_dormand_prince(&m, &mut Swirl, &mut s, 0.03, &mut a0, false, &mut a1, 1e-6);
        let mut direct = vec![0.0; 2];
        i.acceleration(&m, &mut Swirl, s.t, s.s, &s.x, &s.xd, &mut direct);
        assert_eq!(direct, a1);
        let (mut s2, mut s3) = (s.clone(), s.clone());
        let (mut b0, mut b1) = (a1.clone(), vec![0.0; 2]);
        let (mut c0, mut c1) = (vec![0.0; 2], vec![0.0; 2]);
        let e2 = i.step_dormand_prince(&m, &mut Swirl, &mut s2, 0.03, &mut b0, true, &mut b1, 1e-6);
        let e3 = i.step_dormand_prince(&m, &mut Swirl, &mut s3, 0.03, &mut c0, false, &mut c1, 1e-6);
        assert_eq!((s2, b0, b1, e2), (s3, c0, c1, e3));
    }

    #[test]
    fn without_a_perturbation_it_follows_rk4() {
        let p = primitive();
        let m = Motion { start: vec![0.0, 0.0], goal: vec![1.0, 1.0], tau: 1.0 };
        let mut i = Integrator::new(&p).unwrap();
        let (mut a, mut b) = (State::at_rest(&m.start), State::at_rest(&m.start));
        let (mut a0, mut a1, mut acc) = (vec![0.0; 2], vec![0.0; 2], vec![0.0; 2]);
        let mut j = Integrator::new(&p).unwrap();
        for _ in 0..200 {
            i.step_dormand_prince(&m, &mut NoPerturbation, &mut a, 0.005, &mut a0, false, &mut a1, 1e-6);
            for _ in 0..5 {
                j.step(&m, &mut NoPerturbation, &mut b, 0.001, &mut acc);
            }
        }
        assert!(dist(&a, &b) < 1e-9, "{}", dist(&a, &b));
        assert!((a.t - 1.0).abs() < 1e-12 && (a.s - b.s).abs() < 1e-12);
    }

    #[test]
    fn the_controller_grows_and_shrinks_within_bounds() {
        assert_eq!(next_step(0.01, 0.0), 0.05);
        assert!((next_step(0.01, 1.0) - 0.009).abs() < 1e-15);
        assert_eq!(next_step(0.01, 1e12), 0.002);
        assert_eq!(next_step(0.01, f64::NAN), 0.002);
        assert!((next_step(0.01, 0.5f64.powi(5)) - 0.018).abs() < 1e-12);
    }
}
