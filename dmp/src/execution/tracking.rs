//! The final stage: a jerk-limited online trajectory generator that tracks the DMP within a robot's limits.
//!
//! The DMP, with its avoidance, is the reference: its state `(x_r, v_r, a_r)` at every output point. Where the
//! reference's point keeps the limits (checked as the backward finite differences of the output positions, the way
//! a robot judges them, with [`super::limiter::CHECK_MARGIN`] of room, by [`super::limiter`]), the output is the
//! reference's position, handed out with the motion of the output positions there (so that what the robot is told
//! agrees with where it goes). Where it does not, a time-optimal jerk-limited generator takes over from the last
//! state handed out: Ruckig (Berscheid and Kröger, "Jerk-limited Real-time Trajectory Generation with Arbitrary
//! Target States", RSS 2021), through its pure-Rust port `rsruckig`, which agrees with the reference implementation
//! to 1e-14 on random state-to-state problems. Each output point is one control cycle of the generator, so every
//! setpoint is within the limits by construction, and braking is time-optimal. Near the reference the generator
//! replans at every point and hands back once it has caught up ([`CAUGHT_UP`]). After a rollback it takes over at
//! once, from the last point kept: the DMP restarts from that state, which the positions before it need not
//! continue smoothly.
//!
//! # Targets
//! Every [`REPLAN_POINTS`] output points (and at once when it takes over) the generator's target becomes the
//! reference's state at that point, made admissible:
//! - `a_t` is `a_r` within the acceleration bound, and `v_t` is `v_r` within the speed bound less what bringing
//!   `a_t` to zero at the largest jerk adds, `|v_t + a_t |a_t| / (2 J)| <= V` (a target Ruckig can hold);
//! - **forward:** on each axis, `|v_t|` is at most the speed gained over the way to the target,
//!   `sqrt(v0² + v_b(d)²)` with `d = |x_r - x|` (a faster target is reached only by a run-up, backwards first);
//! - **never past the goal:** on each axis that moves towards the goal `g`, `|v_t|` is at most the speed from which
//!   braking within the axis's bounds stops at `g` from `x_r`:
//!   `v_b(d) = (d² J)^(1/3)` for `d <= A³ / J²`, else `v_b(d) = -A² / (2 J) + sqrt(A⁴ / (4 J²) + 2 A d)`, with
//!   `d = |g - x_r|` (from `d = v² / (2 A) + v A / (2 J)`, the distance to brake from speed `v` at zero
//!   acceleration).
//!
//! Between targets the generator follows its last plan (no recalculation: a plan costs a few microseconds, a
//! sample of it a few tens of nanoseconds); a plan that has arrived is replaced at the next point, and `v_t` also
//! leaves room for one cycle at `a_t` (Ruckig holds the target's acceleration past the end of a plan).
//!
//! # Norm bounds on axes
//! The bounds are Euclidean norms over a group's dimensions (a robot's position, or its orientation); Ruckig's are
//! per axis. Each plan gives axis `i` the bounds `w_i (V, A, J)` with `sum w_i² = 1`, so that the norms keep
//! `(V, A, J)`: `w` follows the direction from the output to the target, is never below [`MIN_WEIGHT`] (no axis
//! is frozen), nor below the current state's own use of an axis (the generator never starts outside its bounds;
//! Ruckig also finds no plan from a state exactly at a bound, hence [`FLOOR_ROOM`]), and leaves the state able to
//! brake within them (else it moves back towards the last plan's split). The caps on the target's velocity scale
//! the reference's velocity as one vector. The axes are planned in phase: from a state in line with the target,
//! along the straight chord to it (time-optimally on a straight reach), which the lag's allowance below relies on.
//! Where that is impossible Ruckig synchronises the axes' durations instead.
//!
//! # The phase waits for the robot
//! While the output lags behind the reference, cutting across the reference's curve would leave its path: the chord
//! of an arc of curvature `κ` deviates from it by `L² κ / 8` at length `L`. So the lag is allowed up to
//! `L_max = sqrt(8 ε / κ)`, with `κ = |v_r × a_r| / |v_r|³` the largest curvature of the reference over the last
//! [`CURVATURE_MEMORY`] seconds and `ε` the path tolerance ([`PATH_TOLERANCE`]; [`ANGLE_TOLERANCE`] for an
//! orientation); above it the temporal coupling of [`super::limiting`] slows the phase. On a straight reach the lag
//! is free, and the motion is the time-optimal one to the goal.

use rsruckig::prelude::{
    ControlInterface, IgnoreErrorHandler, InputParameter, OutputParameter, Ruckig, RuckigError, RuckigResult,
    Synchronization,
};

use super::limiter::Limiter;
use super::limits::Bounds;

/// The generator replans towards the reference every this many output points.
pub(super) const REPLAN_POINTS: usize = 10;
/// The share of the way to the target over which the speed gained counts towards a target's speed (the rest is room
/// for the jerk's ramps and the current acceleration).
const REACH_SHARE: f64 = 0.5;
/// A target's speed is checked for being reachable going forward only while it is this many times the robot's
/// (a robot starting after a reference that is already fast): tracking a reference at speed, the next plans close
/// the gap.
const RUN_UP: f64 = 2.0;
/// Smallest weight of an axis in the split of a norm bound.
pub(super) const MIN_WEIGHT: f64 = 0.05;
/// Largest deviation from the reference's path that the lag may cause, in the position's units (metres).
pub(super) const PATH_TOLERANCE: f64 = 0.002;
/// The same for an orientation, radians.
pub(super) const ANGLE_TOLERANCE: f64 = 0.005;
/// How long the largest curvature of the reference is remembered, seconds.
pub(super) const CURVATURE_MEMORY: f64 = 0.2;
/// The output has caught up with the reference when within this of it in position (and `CAUGHT_UP / 0.01` in
/// velocity, and a fifth of the jerk bound's step in acceleration): the reference then goes on from there.
const CAUGHT_UP: f64 = 1e-7;
/// Near the reference (within this in position, and a twentieth of the speed bound in velocity) the generator
/// replans at every point, so that it converges onto the reference and hands back to it.
const NEAR: f64 = 1e-3;
/// Smallest weight of an axis when the state's own use of the axes fills the norm bound.
const LEAST_WEIGHT: f64 = 0.005;
/// Relative room above the state's own use of an axis in the split of the bounds.
const FLOOR_ROOM: f64 = 1e-3;
/// Relative room the generator keeps under each bound: Ruckig keeps its bounds to its own numerical tolerance, and
/// where its plans join or it takes over, the finite differences of its positions may exceed them by a few parts
/// in 10³.
const GENERATOR_ROOM: f64 = 5e-3;
/// Relative room left under a bound for the generator's targets (Ruckig fails on targets exactly at a bound).
const TARGET_ROOM: f64 = 1e-6;

/// The generator of one group of dimensions.
struct GroupTracker {
    dims: Vec<usize>,
    bounds: Bounds,
    otg: Ruckig<0, IgnoreErrorHandler>,
    input: InputParameter<0>,
    output: OutputParameter<0>,
    /// Generating (not following the reference).
    active: bool,
    /// The last point came from the generator.
    generated: bool,
    /// Take over at the next point whatever the reference's point (after a rollback: the points handed out before
    /// it are the only state the robot has).
    force: bool,
    /// Output points since the last plan.
    since_plan: usize,
    /// The largest curvature of the reference, and how long it is still remembered.
    curvature: f64,
    curvature_left: f64,
    /// Path tolerance of the group.
    tolerance: f64,
    /// The output step.
    h: f64,
    /// The split of the bounds over the axes of the last plan (speed, acceleration, jerk), while generating.
    weights: Option<Weights>,
}

/// A split of a group's bounds over its axes (at most 16): speed, acceleration and jerk weights.
type Weights = ([f64; 16], [f64; 16], [f64; 16]);

impl std::fmt::Debug for GroupTracker {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GroupTracker")
            .field("dims", &self.dims)
            .field("bounds", &self.bounds)
            .field("active", &self.active)
            .finish_non_exhaustive()
    }
}

/// What the final stage did at one point.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(super) struct Tracking {
    /// The generator, not the reference, gave the point (in some group).
    pub(super) generated: bool,
    /// The largest lag over the allowed lag, over the groups (0 when following the reference).
    pub(super) lag_usage: f64,
}

/// The final stage of a run: one generator per limited group.
#[derive(Debug, Default)]
pub(super) struct Tracker {
    groups: Vec<GroupTracker>,
    h: f64,
}

fn norm(v: impl Iterator<Item = f64>) -> f64 {
    v.map(|x| x * x).sum::<f64>().sqrt()
}

/// The speed from which braking at jerk `j` and acceleration `a` (from zero acceleration) covers `d`.
pub(super) fn braking_speed(d: f64, a: f64, j: f64) -> f64 {
    let d = d.max(0.0);
    match (a.is_finite(), j.is_finite()) {
        (false, false) => f64::INFINITY,
        (true, false) => (2.0 * a * d).sqrt(),
        (false, true) => (d * d * j).cbrt(),
        (true, true) => {
            if d <= a * a * a / (j * j) {
                (d * d * j).cbrt()
            } else {
                let c = a * a / (2.0 * j);
                -c + (c * c + 2.0 * a * d).sqrt()
            }
        }
    }
}

/// The largest speed an axis at speed `v` and acceleration `a` reaches while its acceleration comes back to zero at
/// jerk `j`: `max(|v|, |v + a |a| / (2 j)|)`, a speed no plan can avoid (`|v|` without a jerk bound).
pub(super) fn peak_speed(v: f64, a: f64, j: f64) -> f64 {
    if j.is_finite() { v.abs().max((v + a * a.abs() / (2.0 * j)).abs()) } else { v.abs() }
}

/// A finite stand-in for "no bound" on an axis (Ruckig needs numbers): far beyond anything a point can use.
fn finite(x: f64, scale: f64) -> f64 {
    if x.is_finite() { x } else { scale }
}

/// The bounds a generator keeps for a robot's `bounds` at points `h` apart: shrunk by [`GENERATOR_ROOM`], and
/// the speed bound by what a step can add. The speed handed out, `v* + a* h / 2`, can exceed the generator's own by
/// up to `J h² / 8`; and a state taken over from what was handed out (after a rollback) has the acceleration of the
/// positions a step back, up to `J h` off, so that it may still speed up by `A h + J h² / 2` before its
/// acceleration is back to zero.
pub(super) fn generator_bounds(bounds: Bounds, h: f64) -> Bounds {
    let shrink = 1.0 - GENERATOR_ROOM;
    let v_room = if bounds.a.is_finite() && bounds.j.is_finite() {
        bounds.j * h * h * (1.0 / 8.0 + 0.5) + bounds.a * h
    } else {
        0.0
    };
    Bounds { v: (bounds.v - v_room) * shrink, a: bounds.a * shrink, j: bounds.j * shrink }
}

impl Tracker {
    /// Generators for `groups` (dimensions and bounds, in the order of the limiter's; unlimited groups get none) of
    /// points `h` apart. The bounds are kept shrunk by [`GENERATOR_ROOM`].
    pub(super) fn new(groups: &[(Vec<usize>, Bounds)], h: f64) -> Self {
        let groups = groups
            .iter()
            .filter(|(dims, b)| !dims.is_empty() && !b.is_none())
            .map(|(dims, bounds)| {
                let n = dims.len();
                let mut input = InputParameter::new(Some(n));
                input.synchronization = Synchronization::Phase;
                GroupTracker {
                    dims: dims.clone(),
                    bounds: generator_bounds(*bounds, h),
                    otg: Ruckig::new(Some(n), h),
                    input,
                    output: OutputParameter::new(Some(n)),
                    active: false,
                    generated: false,
                    force: false,
                    since_plan: 0,
                    curvature: 0.0,
                    curvature_left: 0.0,
                    tolerance: PATH_TOLERANCE,
                    h,
                    weights: None,
                }
            })
            .collect();
        Self { groups, h }
    }

    /// Marks the group of `dims` as an orientation (its path tolerance is an angle).
    pub(super) fn set_angular(&mut self, dims: &[usize]) {
        for g in &mut self.groups {
            if g.dims == dims {
                g.tolerance = ANGLE_TOLERANCE;
            }
        }
    }

    /// True when no group is limited.
    pub(super) fn is_off(&self) -> bool {
        self.groups.is_empty()
    }

    /// Whether a generator is giving the points (the output lags behind the DMP).
    pub(super) fn is_active(&self) -> bool {
        self.groups.iter().any(|g| g.active)
    }

    /// Whether group `g`'s generator gave the last point (it was tracking, or it has just handed back).
    pub(super) fn generated(&self, g: usize) -> bool {
        self.groups[g].generated
    }

    /// The output restarts (a rollback, new limits, a change of coordinates): with `handed`, the last points handed
    /// out stay (a rollback into the run), and the generator goes on from them at the next point, whatever the
    /// DMP's; without, the DMP gives the next points while it keeps the bounds.
    pub(super) fn reset(&mut self, handed: bool) {
        for g in &mut self.groups {
            g.active = false;
            g.force = handed;
            g.curvature = 0.0;
            g.curvature_left = 0.0;
        }
    }

    /// The output point for the reference point `(x, xd, xdd)` (rewritten in place where the generator gives it),
    /// with the goal `goal`. `keeps[k]` says whether group `k`'s reference point keeps its bounds after the last
    /// output (the limiter's check); a generator takes over from the last state handed out (the limiter's).
    pub(super) fn track(
        &mut self,
        x: &mut [f64],
        xd: &mut [f64],
        xdd: &mut [f64],
        goal: &[f64],
        keeps: &[bool],
        limiter: &Limiter,
    ) -> Tracking {
        let mut out = Tracking::default();
        let h = self.h;
        for (gi, g) in self.groups.iter_mut().enumerate() {
            g.remember_curvature(xd, xdd, h);
            g.generated = false;
            if !g.active && !g.force && keeps[gi] {
                continue;
            }
            g.generated = true;
            g.force = false;
            if !g.active {
                // Take over from the last output state.
                g.active = true;
                g.weights = None;
                g.since_plan = REPLAN_POINTS;
                for (k, &i) in g.dims.iter().enumerate() {
                    let (p, v, a) = limiter.last_state(i);
                    g.input.current_position[k] = p;
                    g.input.current_velocity[k] = v;
                    g.input.current_acceleration[k] = a;
                }
            }
            if g.since_plan >= REPLAN_POINTS {
                g.since_plan = 0;
                g.set_target(x, xd, xdd, goal);
            }
            g.since_plan += 1;
            let mut result = g.otg.update(&g.input, &mut g.output);
            let mut ok = g.step_is_sound(&result);
            if !ok && g.input.target_acceleration.iter().any(|a| *a != 0.0) {
                // Ruckig finds no plan to some targets with an acceleration near an axis's bound, and on rare
                // others returns one whose first step exceeds an axis's jerk: the same state at zero acceleration
                // (its speed was bounded for that too).
                g.input.target_acceleration.iter_mut().for_each(|a| *a = 0.0);
                result = g.otg.update(&g.input, &mut g.output);
                ok = g.step_is_sound(&result);
            }
            if ok && matches!(result, Ok(RuckigResult::Finished)) {
                // The plan has reached its target: past it, Ruckig would go on at the target's velocity and
                // acceleration, which only the DMP can say. Replan at the next point.
                g.since_plan = REPLAN_POINTS;
            }
            if !ok {
                // No plan (a numerical corner of the generator): brake to rest from the current state, which
                // Ruckig's velocity interface always can.
                // Each axis on its own: Ruckig's synchronisation of velocity profiles can exceed an axis's jerk.
                g.input.control_interface = ControlInterface::Velocity;
                g.input.synchronization = Synchronization::None;
                g.input.target_velocity.iter_mut().for_each(|v| *v = 0.0);
                g.input.target_acceleration.iter_mut().for_each(|a| *a = 0.0);
                // Without a plan either, the state goes on one step at its acceleration (continuous, no jerk), and
                // the next point replans.
                let braking = g.otg.update(&g.input, &mut g.output);
                if !g.step_is_sound(&braking) {
                    for k in 0..g.dims.len() {
                        let (p, v, a) = (
                            g.input.current_position[k],
                            g.input.current_velocity[k],
                            g.input.current_acceleration[k],
                        );
                        g.output.new_position[k] = p + v * h + 0.5 * a * h * h;
                        g.output.new_velocity[k] = v + a * h;
                        g.output.new_acceleration[k] = a;
                    }
                }
                g.since_plan = REPLAN_POINTS;
            }
            g.output.pass_to_input(&mut g.input);
            let (mut lag2, mut dv2, mut da2) = (0.0, 0.0, 0.0);
            for (k, &i) in g.dims.iter().enumerate() {
                lag2 += (x[i] - g.output.new_position[k]).powi(2);
                dv2 += (xd[i] - g.output.new_velocity[k]).powi(2);
                da2 += (xdd[i] - g.output.new_acceleration[k]).powi(2);
                // The position is the generator's; the velocity and acceleration handed out with it are the output
                // positions' own motion (`v* + a* h / 2`, `a*`), as for the DMP's points: the generator's
                // profiles switch jerk within a cycle, and its exact samples would not account for the change
                // between two points.
                // (Only under finite acceleration and jerk bounds: without, `a* h / 2` is not bounded.)
                let (p, v, a) = if g.bounds.a.is_finite() && g.bounds.j.is_finite() {
                    limiter.motion_to(i, g.output.new_position[k])
                } else {
                    (g.output.new_position[k], g.output.new_velocity[k], g.output.new_acceleration[k])
                };
                x[i] = p;
                xd[i] = v;
                xdd[i] = a;
            }
            let lag = lag2.sqrt();
            out.generated = true;
            out.lag_usage = out.lag_usage.max(lag / g.allowed_lag());
            let dv = dv2.sqrt();
            if lag <= CAUGHT_UP && dv <= CAUGHT_UP / 0.01 && da2.sqrt() <= 0.2 * g.bounds.j * h {
                // On the reference again: it gives the next points while it keeps the bounds.
                g.active = false;
            } else if lag <= NEAR && dv <= 0.05 * g.bounds.v {
                // Close: replan at every point, to converge onto the reference.
                g.since_plan = REPLAN_POINTS;
            }
        }
        out
    }
}

impl GroupTracker {
    /// Keeps the largest curvature of the reference over [`CURVATURE_MEMORY`].
    fn remember_curvature(&mut self, xd: &[f64], xdd: &[f64], h: f64) {
        let v2: f64 = self.dims.iter().map(|&i| xd[i] * xd[i]).sum();
        let a2: f64 = self.dims.iter().map(|&i| xdd[i] * xdd[i]).sum();
        let va: f64 = self.dims.iter().map(|&i| xd[i] * xdd[i]).sum();
        // |v x a|² = |v|² |a|² - (v . a)², any dimension.
        let cross = (v2 * a2 - va * va).max(0.0).sqrt();
        let speed = v2.sqrt();
        // Below a speed the direction is not defined: the lag is small there anyway.
        let floor = self.bounds.v.min(1.0) * 1e-3;
        let kappa = cross / speed.max(floor).powi(3);
        if kappa >= self.curvature || self.curvature_left <= 0.0 {
            self.curvature = kappa;
            self.curvature_left = CURVATURE_MEMORY;
        } else {
            self.curvature_left -= h;
        }
    }

    /// The lag allowed by the reference's curvature.
    fn allowed_lag(&self) -> f64 {
        if self.curvature <= 0.0 { f64::INFINITY } else { (8.0 * self.tolerance / self.curvature).sqrt() }
    }

    /// The target: the reference's state, admissible, and the per-axis bounds of the plan.
    fn set_target(&mut self, x: &[f64], xd: &[f64], xdd: &[f64], goal: &[f64]) {
        let n = self.dims.len();
        let b = self.bounds;
        let room = 1.0 - TARGET_ROOM;
        // The split of the norm bounds: along the way to the target, at least the state's own use of each axis.
        let dir = norm(self.dims.iter().enumerate().map(|(k, &i)| x[i] - self.input.current_position[k]));
        let vref = norm(self.dims.iter().map(|&i| xd[i]));
        if n > 16 {
            return self.set_target_uniform(x, xd, xdd, goal);
        }
        let (mut wv, mut wa, mut wj) = ([0.0f64; 16], [0.0f64; 16], [0.0f64; 16]);
        let (wv, wa, wj) = (&mut wv[..n], &mut wa[..n], &mut wj[..n]);
        // The floors: the current state's use of each axis, of the speed bound and of the acceleration bound
        // (split apart: a state within the norms has each set's squares summing to at most 1).
        let (mut fv, mut fa) = ([0.0f64; 16], [0.0f64; 16]);
        let (fv, fa) = (&mut fv[..n], &mut fa[..n]);
        for (k, &i) in self.dims.iter().enumerate() {
            let along = if dir > 1e-12 {
                (x[i] - self.input.current_position[k]).abs() / dir
            } else if vref > 1e-12 {
                xd[i].abs() / vref
            } else {
                1.0 / (n as f64).sqrt()
            };
            wv[k] = along.max(MIN_WEIGHT);
        }
        wa.copy_from_slice(wv);
        wj.copy_from_slice(wv);
        split(wj, &[0.0; 16][..n]);
        for k in 0..n {
            let (v, a) = (self.input.current_velocity[k], self.input.current_acceleration[k]);
            fv[k] = if b.v.is_finite() { peak_speed(v, a, b.j * wj[k]) / b.v } else { 0.0 };
            fa[k] = if b.a.is_finite() { a.abs() / b.a } else { 0.0 };
        }
        split(wv, fv);
        split(wa, fa);
        // A new split must leave the state within its bounds, braking included: its speed's peak under the new
        // jerk weights within the new speed weights. A split along the new way that does not is moved back
        // towards the last plan's (which the state keeps, being on that plan), as far as needed.
        if let Some((pv, pa, pj)) = self.weights
            && !self.keeps_state(wv, wa, wj)
        {
            let (mut cv, mut ca, mut cj) = ([0.0; 16], [0.0; 16], [0.0; 16]);
            cv[..n].copy_from_slice(wv);
            ca[..n].copy_from_slice(wa);
            cj[..n].copy_from_slice(wj);
            let (cv, ca, cj) = (&cv[..n], &ca[..n], &cj[..n]);
            let mix = |out: &mut [f64], prev: &[f64], cand: &[f64], l: f64| {
                out.iter_mut().zip(prev.iter().zip(cand)).for_each(|(o, (p, c))| *o = (1.0 - l) * p + l * c)
            };
            let (mut lo, mut hi) = (0.0, 1.0);
            for _ in 0..12 {
                let mid = 0.5 * (lo + hi);
                mix(wv, &pv[..n], cv, mid);
                mix(wa, &pa[..n], ca, mid);
                mix(wj, &pj[..n], cj, mid);
                if self.keeps_state(wv, wa, wj) { lo = mid } else { hi = mid }
            }
            mix(wv, &pv[..n], cv, lo);
            mix(wa, &pa[..n], ca, lo);
            mix(wj, &pj[..n], cj, lo);
        }
        let mut kept: Weights = ([0.0; 16], [0.0; 16], [0.0; 16]);
        kept.0[..n].copy_from_slice(wv);
        kept.1[..n].copy_from_slice(wa);
        kept.2[..n].copy_from_slice(wj);
        self.weights = Some(kept);
        self.input.control_interface = ControlInterface::Position;
        let scale_v = vref.max(1.0) * 1e3;
        for (k, &i) in self.dims.iter().enumerate() {
            let (vk, ak, jk) = (b.v * wv[k], b.a * wa[k], b.j * wj[k]);
            self.input.max_velocity[k] = finite(vk, scale_v);
            self.input.max_acceleration[k] = finite(ak, scale_v * 1e3);
            self.input.max_jerk[k] = jk;
            let a_t = if ak.is_finite() { xdd[i].clamp(-ak * room, ak * room) } else { xdd[i] };
            let mut v_top = finite(vk, scale_v) * room;
            if jk.is_finite() {
                v_top -= a_t * a_t / (2.0 * jk);
            }
            // And room for the rest of a cycle at `a_t` once the plan has arrived (Ruckig goes on at the target's
            // acceleration until the next point replans).
            v_top -= a_t.abs() * self.h;
            let (a_t, v_top) = if v_top > 0.0 { (a_t, v_top) } else { (0.0, finite(vk, scale_v) * room) };
            // Never past the goal: at most the speed that still brakes at the goal, towards it.
            let to_goal = goal[i] - x[i];
            let v_goal = braking_speed(to_goal.abs(), ak, jk) * room;
            let mut v_t = xd[i];
            if v_t * to_goal > 0.0 {
                v_t = v_t.clamp(-v_goal, v_goal);
            }
            // Within the speed bound, with room for the target acceleration to come back to zero.
            let (lo, hi) = if a_t > 0.0 {
                (-finite(vk, scale_v) * room, v_top)
            } else {
                (-v_top, finite(vk, scale_v) * room)
            };
            let mut v_t = v_t.clamp(lo, hi);
            // Reachable going forward: at most the speed the axis can gain over the way to the target, from its
            // current speed (`sqrt(v0² + v_b(d)²)`, with `v_b` the speed that braking covers `d` from, the same
            // distance accelerating). A target faster than that is reached only by a run-up: backwards first.
            let ahead = x[i] - self.input.current_position[k];
            let v0 = self.input.current_velocity[k];
            if v_t * ahead > 0.0 && v_t.abs() > RUN_UP * v0.abs() {
                let gain = braking_speed(REACH_SHARE * ahead.abs(), ak, jk);
                let reach = (v0 * v0 + gain * gain).sqrt() * room;
                v_t = v_t.clamp(-reach, reach);
            }
            self.input.target_position[k] = x[i];
            self.input.target_velocity[k] = v_t;
            self.input.target_acceleration[k] = if v_t == xd[i] { a_t } else { 0.0 };
        }
        // The caps scale the reference's velocity as one vector (by the smallest of the axes' shares), so that the
        // target moves the way the reference does: on a straight reach, along its line.
        let share = self
            .dims
            .iter()
            .enumerate()
            .filter(|&(_, &i)| xd[i] != 0.0)
            .map(|(k, &i)| (self.input.target_velocity[k] / xd[i]).clamp(0.0, 1.0))
            .fold(1.0, f64::min);
        if share < 1.0 {
            for (k, &i) in self.dims.iter().enumerate() {
                self.input.target_velocity[k] = share * xd[i];
                self.input.target_acceleration[k] = 0.0;
            }
        }
        self.input.synchronization = Synchronization::Phase;
    }

    /// Whether Ruckig's answer is a step to use: a plan, whose step keeps each axis's jerk (the change of its
    /// acceleration over the step, `|Δa| <= j h`) and acceleration bound (or the current acceleration, when over
    /// it), to a part in 10⁶.
    fn step_is_sound(&self, result: &Result<RuckigResult, RuckigError>) -> bool {
        if !matches!(result, Ok(RuckigResult::Working | RuckigResult::Finished)) {
            return false;
        }
        let slack = 1.0 + 1e-6;
        (0..self.dims.len()).all(|k| {
            let (a0, a1) = (self.input.current_acceleration[k], self.output.new_acceleration[k]);
            (a1 - a0).abs() <= self.input.max_jerk[k] * self.h * slack
                && a1.abs() <= self.input.max_acceleration[k].max(a0.abs()) * slack
        })
    }

    /// Whether the current state is within the split `(wv, wa, wj)` of the bounds: each axis's speed, its speed's
    /// peak while its acceleration comes back to zero at the axis's jerk (`|v + a |a| / (2 j)|`), and its
    /// acceleration, within the axis's bounds (to a part in 10⁶).
    fn keeps_state(&self, wv: &[f64], wa: &[f64], wj: &[f64]) -> bool {
        let b = self.bounds;
        let slack = 1.0 + 1e-6;
        (0..wv.len()).all(|k| {
            let (v, a) = (self.input.current_velocity[k], self.input.current_acceleration[k]);
            (!b.v.is_finite() || peak_speed(v, a, b.j * wj[k]) <= wv[k] * b.v * slack)
                && (!b.a.is_finite() || a.abs() <= wa[k] * b.a * slack)
        })
    }

    /// More than 16 dimensions in a group: the norm bounds split evenly.
    fn set_target_uniform(&mut self, x: &[f64], xd: &[f64], _xdd: &[f64], _goal: &[f64]) {
        let n = self.dims.len() as f64;
        let b = self.bounds;
        let w = 1.0 / n.sqrt();
        let scale_v = 1e3;
        self.input.control_interface = ControlInterface::Position;
        self.input.synchronization = Synchronization::Phase;
        for (k, &i) in self.dims.iter().enumerate() {
            let vk = finite(b.v * w, scale_v);
            self.input.max_velocity[k] = vk;
            self.input.max_acceleration[k] = finite(b.a * w, scale_v * 1e3);
            self.input.max_jerk[k] = b.j * w;
            self.input.target_position[k] = x[i];
            self.input.target_velocity[k] = xd[i].clamp(-vk * 0.5, vk * 0.5);
            self.input.target_acceleration[k] = 0.0;
        }
    }
}

/// The split of a norm bound over axes: `w_i = max(f_i (1 + FLOOR_ROOM), c u_i)` with `c` such that
/// `sum w_i² = 1` (by bisection: the sum grows with `c`), written into `u`; the room over the floors `f` (the state's
/// own use of each axis) shrinks to what the norm leaves, and where the floors alone fill it,
/// `w = (1 + FLOOR_ROOM²) f / |f|`, never below `LEAST_WEIGHT`: a hair over the norm (the bounds the generator
/// keeps are [`GENERATOR_ROOM`] under the robot's), so that the state is never exactly at an axis's bound, where Ruckig
/// finds no plan, nor over it, where Ruckig would brake that axis first.
pub(super) fn split(u: &mut [f64], f: &[f64]) {
    let f2: f64 = f.iter().map(|f| f * f).sum();
    if f2 >= 1.0 / (1.0 + FLOOR_ROOM).powi(2) {
        let nf = f2.sqrt() / (1.0 + FLOOR_ROOM * FLOOR_ROOM);
        u.iter_mut().zip(f).for_each(|(u, f)| *u = (f / nf).max(LEAST_WEIGHT));
        return;
    }
    let room = 1.0 + FLOOR_ROOM;
    let sum = |c: f64| u.iter().zip(f).map(|(&u, &f)| (f * room).max(c * u).powi(2)).sum::<f64>();
    let (mut lo, mut hi) = (0.0, 1.0 / u.iter().copied().fold(f64::INFINITY, f64::min));
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if sum(mid) > 1.0 { hi = mid } else { lo = mid }
    }
    u.iter_mut().zip(f).for_each(|(u, &f)| *u = (f * room).max(lo * *u));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn braking_from_the_braking_speed_covers_the_distance() {
        for &(a, j) in &[(13.0, 6500.0), (1.0, 10.0), (2.0, 100.0)] {
            for &d in &[1e-5, 1e-3, 0.01, 0.1, 1.0] {
                let v = braking_speed(d, a, j);
                // The distance to brake from v at zero acceleration, jerk-limited.
                let dist =
                    if v >= a * a / j { v * v / (2.0 * a) + v * a / (2.0 * j) } else { v * (v / j).sqrt() };
                assert!((dist - d).abs() <= 1e-9 * (1.0 + d), "a {a} j {j} d {d}: v {v} brakes in {dist}");
            }
        }
        assert_eq!(braking_speed(2.0, 1.0, f64::INFINITY), 2.0);
    }

    #[test]
    fn a_split_keeps_its_floors_and_sums_to_one() {
        let mut w = [1.0, MIN_WEIGHT, MIN_WEIGHT];
        split(&mut w, &[0.0, 0.6, 0.0]);
        assert!(w[1] >= 0.6 && (w.iter().map(|w| w * w).sum::<f64>() - 1.0).abs() < 1e-9, "{w:?}");
        assert!(w[0] > 0.75 && w[2] < 0.1, "{w:?}");
        let mut w = [0.5, 0.5];
        split(&mut w, &[0.9, 0.9]);
        assert!((w[0] - w[1]).abs() < 1e-12 && (w[0] * w[0] * 2.0 - 1.0).abs() < 1e-5, "{w:?}");
        let mut w = [0.5, 0.5, 0.5];
        split(&mut w, &[0.0, 0.0, 1.0]);
        assert!(w[0] >= LEAST_WEIGHT && w[1] >= LEAST_WEIGHT && w[2] >= 1.0, "{w:?}");
    }

    /// What a robot checks between two setpoints (the sims' continuity bounds): the change of position and of
    /// velocity is what the velocities and accelerations handed out account for, also where the generator gives
    /// the points. A group of two robots at the PSM's profile, with a goal change and a rollback.
    #[test]
    fn the_motion_handed_out_accounts_for_the_steps_between_setpoints() {
        use crate::execution::tests::alone;
        use crate::execution::{Limits, Stepping};
        use crate::field::{Agent, Scene};
        use crate::primitive::Primitive;
        let d = 4;
        let p = Primitive::straight_line(
            20,
            4.0,
            vec![100.0; d],
            None,
            2.0,
            vec![0.0; d],
            vec![0.2, 0.1, -0.1, 0.15],
        )
        .unwrap();
        let mut scene = Scene::empty();
        scene.agents = vec![
            Agent { id: "a".into(), dims: vec![0, 1], footprint: None },
            Agent { id: "b".into(), dims: vec![2, 3], footprint: None },
        ];
        let mut e = alone(&p, scene, Stepping::rk4(1e-3), 200);
        e.set_limits(Limits::DVRK_PSM, false).unwrap();
        let (mut x, mut v, mut a) = (Vec::new(), Vec::new(), Vec::new());
        for seg in 0..800 {
            if seg == 150 {
                let t = e.time();
                e.rollback_to(t - 0.005);
                for buf in [&mut x, &mut v, &mut a] {
                    buf.truncate(buf.len() - 5 * d);
                }
                e.set_goal(vec![0.1, 0.2, 0.1, -0.1]).unwrap();
            }
            let s = e.advance(10).unwrap();
            x.extend_from_slice(&s.x);
            v.extend_from_slice(&s.xd);
            a.extend_from_slice(&s.xdd);
            if s.outcome.is_final() {
                break;
            }
        }
        assert!(e.cost().limited > 100, "{:?}", e.cost());
        let h = 1e-3;
        let n = x.len() / d;
        let mut bad = 0;
        for k in 1..n - 2 {
            for i in 0..d {
                let amax = (k - 1..=k + 2).map(|j| a[j * d + i].abs()).fold(0.0, f64::max);
                let da = (a[(k + 1) * d + i] - a[k * d + i]).abs();
                let slack = 1.5 * amax + da;
                let e1 = (x[(k + 1) * d + i] - x[k * d + i] - v[k * d + i] * h).abs();
                let e2 = (v[(k + 1) * d + i] - v[k * d + i]).abs();
                bad += usize::from(e1 > slack * h * h + 1e-9 || e2 > slack * h + 1e-9);
            }
        }
        assert_eq!(bad, 0, "{bad} steps of {n} the motion handed out does not account for");
    }
}
