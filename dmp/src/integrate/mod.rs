//! Integration of the transformation system: classical RK4 at a fixed step, or Dormand–Prince 5(4) with an error
//! estimate for an adaptive step (`integrate/dormand_prince.rs`), both with the phase in closed form.

pub(crate) mod dormand_prince;
pub mod goal_filter;

use crate::basis::{ForcingTerm, GaussianBasis};
use crate::canonical::phase_after;
use crate::error::{InvalidInput, Result, check_vector, ensure_positive};
use crate::primitive::Primitive;
use goal_filter::GoalFilter;

/// A repulsive term `phi(x, v, t)` added to `tau dv/dt` (paper, `eq:dmp_acc_obst`).
pub trait Perturbation {
    /// Adds `phi` to `out`. `x` is the position, `v = tau dx/dt` the DMP's velocity state, `t` the time since the
    /// start of the run (obstacles move with it).
    fn add(&mut self, t: f64, x: &[f64], v: &[f64], tau: f64, out: &mut [f64]);
}

/// No repulsive term.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoPerturbation;

impl Perturbation for NoPerturbation {
    fn add(&mut self, _: f64, _: &[f64], _: &[f64], _: f64, _: &mut [f64]) {}
}

impl<P: Perturbation + ?Sized> Perturbation for &mut P {
    fn add(&mut self, t: f64, x: &[f64], v: &[f64], tau: f64, out: &mut [f64]) {
        (**self).add(t, x, v, tau, out)
    }
}

/// What a replay may change: start `x0`, goal `g` and time scale `tau`. Each may change between two steps; the
/// position and the velocity `dx/dt` stay continuous.
#[derive(Debug, Clone, PartialEq)]
pub struct Motion {
    /// `x0`, the start the forcing term is scaled from.
    pub start: Vec<f64>,
    /// `g`.
    pub goal: Vec<f64>,
    /// `tau`: larger is slower.
    pub tau: f64,
}

impl Motion {
    /// The demonstration's own start, goal and duration.
    pub fn of(p: &Primitive) -> Self {
        Self { start: p.start.clone(), goal: p.goal.clone(), tau: p.tau }
    }

    /// Checks the motion against a primitive of dimension `dim`.
    pub fn validate(&self, dim: usize) -> Result<(), InvalidInput> {
        check_vector("start", &self.start, dim)?;
        check_vector("goal", &self.goal, dim)?;
        ensure_positive(|| "tau".into(), self.tau)
    }
}

/// The state of a run: time, phase, position and velocity `dx/dt` (not `tau dx/dt`, so that a change of `tau`
/// leaves it continuous).
#[derive(Debug, Clone, PartialEq)]
pub struct State {
    /// Time since the start of the run.
    pub t: f64,
    /// Phase `s` in `(0, 1]`.
    pub s: f64,
    /// Position.
    pub x: Vec<f64>,
    /// Velocity `dx/dt`.
    pub xd: Vec<f64>,
}

impl State {
    /// At rest at `start`, time 0, phase 1.
    pub fn at_rest(start: &[f64]) -> Self {
        Self { t: 0.0, s: 1.0, x: start.to_vec(), xd: vec![0.0; start.len()] }
    }
}

/// Steps a primitive. Holds the compiled forcing term and every buffer, so stepping allocates nothing.
#[derive(Debug, Clone)]
pub struct Integrator {
    forcing: ForcingTerm,
    k: Vec<f64>,
    d: Vec<f64>,
    alpha: f64,
    dim: usize,
    /// Last two phases at which the forcing term was evaluated, with their values (RK4's last stage is the next
    /// step's first).
    cache: [(f64, Vec<f64>); 2],
    cache_next: usize,
    b: Buffers,
    dp: dormand_prince::Stages,
    /// The goal the transformation system sees (off unless set: the goal is then `motion.goal` exactly).
    goal_filter: GoalFilter,
}

#[derive(Debug, Clone)]
struct Buffers {
    v: Vec<f64>,
    phi: Vec<f64>,
    /// The filtered goal at a stage.
    g: Vec<f64>,
    xs: Vec<f64>,
    xds: Vec<f64>,
    kx: [Vec<f64>; 4],
    ka: [Vec<f64>; 4],
}

impl Integrator {
    /// Compiles `p` (which must be valid, see [`Primitive::validate`]).
    pub fn new(p: &Primitive) -> Result<Self> {
        p.validate()?;
        let basis = GaussianBasis::new(p.n_basis, p.alpha)?;
        let dim = p.dim;
        let z = || vec![0.0; dim];
        Ok(Self {
            forcing: ForcingTerm::new(basis, &p.weights),
            k: p.k.clone(),
            d: p.d.clone(),
            alpha: p.alpha,
            dim,
            cache: [(f64::NAN, z()), (f64::NAN, z())],
            cache_next: 0,
            b: Buffers {
                v: z(),
                phi: z(),
                g: z(),
                xs: z(),
                xds: z(),
                kx: [z(), z(), z(), z()],
                ka: [z(), z(), z(), z()],
            },
            dp: dormand_prince::Stages::new(dim),
            goal_filter: GoalFilter::new(0.0, &p.goal),
        })
    }

    /// Dimension.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Canonical decay.
    pub fn alpha(&self) -> f64 {
        self.alpha
    }

    /// The goal filter ([`goal_filter`]): off unless set.
    pub fn goal_filter(&self) -> &GoalFilter {
        &self.goal_filter
    }

    /// The goal filter, to change it.
    pub(crate) fn goal_filter_mut(&mut self) -> &mut GoalFilter {
        &mut self.goal_filter
    }

    fn forcing_at(&mut self, s: f64) -> usize {
        for (i, (cs, _)) in self.cache.iter().enumerate() {
            if *cs == s {
                return i;
            }
        }
        let i = self.cache_next;
        self.cache_next = 1 - i;
        self.cache[i].0 = s;
        self.forcing.eval(s, &mut self.cache[i].1);
        i
    }

    /// The acceleration `d2x/dt2` at a state, written into `out`.
    ///
    /// # Formula
    /// `tau dv/dt = K (g - x) - D v - K (g - x0) s + K f(s) + phi(x, v)` (paper, `eq:dmp_acc_obst`) with
    /// `v = tau dx/dt`, so `d2x/dt2 = (tau dv/dt) / tau^2`; `g` is the goal filter's `g(t)` while it filters a
    /// change ([`goal_filter`]), `motion.goal` otherwise.
    #[allow(clippy::too_many_arguments)]
    pub fn acceleration<P: Perturbation + ?Sized>(
        &mut self,
        motion: &Motion,
        perturbation: &mut P,
        t: f64,
        s: f64,
        x: &[f64],
        xd: &[f64],
        out: &mut [f64],
    ) {
        let fi = self.forcing_at(s);
        let tau = motion.tau;
        for i in 0..self.dim {
            self.b.v[i] = tau * xd[i];
        }
        self.b.phi.fill(0.0);
        perturbation.add(t, x, &self.b.v, tau, &mut self.b.phi);
        let f = &self.cache[fi].1;
        let inv_tau2 = 1.0 / (tau * tau);
        let filtered = self.goal_filter.is_active();
        if filtered {
            self.goal_filter.goal_at(&motion.goal, t, tau, &mut self.b.g);
        }
        for i in 0..self.dim {
            let g = if filtered { self.b.g[i] } else { motion.goal[i] };
            let (x0, k) = (motion.start[i], self.k[i]);
            out[i] = (k * (g - x[i]) - self.d[i] * self.b.v[i] - k * (g - x0) * s + k * f[i] + self.b.phi[i])
                * inv_tau2;
        }
    }

    /// One classical RK4 step of length `dt` on `(x, dx/dt)`, with the phase advanced in closed form at each
    /// stage. Writes the acceleration at the state before the step into `acc_before` (it is RK4's first stage).
    pub fn step<P: Perturbation + ?Sized>(
        &mut self,
        motion: &Motion,
        perturbation: &mut P,
        state: &mut State,
        dt: f64,
        acc_before: &mut [f64],
    ) {
        self.step_from(motion, perturbation, state, dt, acc_before, false);
    }

    /// As [`Integrator::step`]; with `first_known`, `acc_before` already holds the acceleration at `state` under
    /// the same motion and perturbation (the last stage of the previous step's knot: "first same as last"), and
    /// RK4's first stage is not evaluated again. The result is the same to the last bit.
    pub fn step_from<P: Perturbation + ?Sized>(
        &mut self,
        motion: &Motion,
        perturbation: &mut P,
        state: &mut State,
        dt: f64,
        acc_before: &mut [f64],
        first_known: bool,
    ) {
        let d = self.dim;
        let tau = motion.tau;
        let (t0, s0) = (state.t, state.s);
        let s_half = phase_after(s0, self.alpha, tau, 0.5 * dt);
        let s_end = phase_after(s0, self.alpha, tau, dt);
        let mut kx = std::mem::take(&mut self.b.kx);
        let mut ka = std::mem::take(&mut self.b.ka);
        let mut xs = std::mem::take(&mut self.b.xs);
        let mut xds = std::mem::take(&mut self.b.xds);

        kx[0].copy_from_slice(&state.xd);
        if first_known {
            ka[0].copy_from_slice(&acc_before[..d]);
        } else {
            self.acceleration(motion, perturbation, t0, s0, &state.x, &state.xd, &mut ka[0]);
        }
        for (stage, (h, s)) in [(0.5 * dt, s_half), (0.5 * dt, s_half), (dt, s_end)].into_iter().enumerate() {
            for i in 0..d {
                xs[i] = state.x[i] + h * kx[stage][i];
                xds[i] = state.xd[i] + h * ka[stage][i];
            }
            kx[stage + 1].copy_from_slice(&xds);
            let (_, rest) = ka.split_at_mut(stage + 1);
            self.acceleration(motion, perturbation, t0 + h, s, &xs, &xds, &mut rest[0]);
        }
        for i in 0..d {
            state.x[i] += dt / 6.0 * (kx[0][i] + 2.0 * kx[1][i] + 2.0 * kx[2][i] + kx[3][i]);
            state.xd[i] += dt / 6.0 * (ka[0][i] + 2.0 * ka[1][i] + 2.0 * ka[2][i] + ka[3][i]);
        }
        acc_before[..d].copy_from_slice(&ka[0]);
        state.t = t0 + dt;
        state.s = s_end;
        self.b.kx = kx;
        self.b.ka = ka;
        self.b.xs = xs;
        self.b.xds = xds;
    }
}
