//! The safety distance: no point handed out brings a robot closer than the margin `m` to an obstacle's true shape,
//! where the robot can still brake; where the field cannot keep it, the robot brakes to rest before the margin
//! (blocked), and goes on when the way clears.
//!
//! # The invariant
//! Every point handed out near an obstacle has a **verified brake**: the time-optimal jerk-limited stop from its
//! state (position, velocity, acceleration) within the robot's limits, whose whole path keeps the margin. A
//! candidate point (the DMP's, or the final stage's, [`super::tracking`]) is handed out only if its own brake keeps
//! the margin; otherwise the robot follows the brake of the last point handed out, which was verified, and is
//! blocked. While blocked, each point's candidate is tried again from where the robot is: the first whose brake keeps
//! the margin releases it. So a robot that could stop keeps the margin whatever the field does: a goal inside an
//! obstacle, an obstacle that appears or moves in front of it (one braking distance ahead or more).
//!
//! # The brake
//! Each axis brakes on its own to rest (Ruckig's velocity interface towards zero velocity and acceleration, no
//! synchronisation), under its share `w_i` of the norm bounds (`sum w_i² = 1`, so the norms keep the robot's limits;
//! the shares follow the velocity's direction and are never below the state's own use of an axis,
//! [`super::tracking::split`]): the same per-axis stop the final stage falls back on.
//!
//! # Keeping the margin along a path
//! Every obstacle is convex, so it lies in the half-space behind the tangent plane at the point `z` of its surface
//! nearest to the candidate `p` (with `n = (p - z) / |p - z|`): `n . (y - z) <= 0` for every `y` of it. A brake
//! sample `q` at time `s` with `n . (q - z - w s) >= m` (the obstacle moving at `w`) is at least `m` from the whole
//! shape. Samples are `Δ` apart in time; between them the path is within `v Δ / 2` of one (with `v` the largest
//! speed of the brake), which the test adds to `m`. The nearest point is exact ([`crate::distance`]).
//!
//! An obstacle is checked only when its bounding ball can come within `m` of the brake: with `R` its bounding radius,
//! `S` a bound on the brake's length (`v_p t_a + v_p² / (2 A) + v_p A / (2 J)`, where `v_p = |v| + |a|² / (2 J)` is
//! the speed's peak while the acceleration returns to zero in `t_a = |a| / J`) and `T` on its duration, it is
//! skipped when `|p - c| - R - |w| T > m + S`. Likewise no brake is planned when the exact clearance `d` leaves
//! room for the brake, `d - S_axes - |w| T >= m`, with `S_axes` the same bound per axis under its share, summed as a
//! vector: a brake planned later from that point (at a rejection) keeps the margin.
//!
//! A robot already within the margin (an obstacle moved or appeared there) is held to its clearance at the last
//! point handed out instead: it may move away, never closer.

use rsruckig::prelude::{
    ControlInterface, DataArrayOrVec, IgnoreErrorHandler, InputParameter, Ruckig, RuckigResult,
    Synchronization, Trajectory,
};

use super::limiter::Limiter;
use super::limits::Bounds;
use super::tracking::{MIN_WEIGHT, peak_speed, split};
use crate::distance::nearest_surface_point;
use crate::obstacle::{Obstacle, WorldEval, rotate};

/// Brake samples checked per brake (at most; at least one per output step).
const BRAKE_SAMPLES: usize = 24;

/// The guard of one robot's position (a group of the final stage).
struct GuardGroup {
    dims: Vec<usize>,
    bounds: Bounds,
    otg: Ruckig<0, IgnoreErrorHandler>,
    input: InputParameter<0>,
    /// The verified brake of the point handed out at run time `plan_at` (`verified`).
    plan: Trajectory<0>,
    plan_at: f64,
    verified: bool,
    /// A candidate's brake.
    spare: Trajectory<0>,
    /// The per-axis bounds `plan` and `spare` were planned with (speed, acceleration, jerk per axis).
    plan_bounds: Vec<f64>,
    spare_bounds: Vec<f64>,
    /// The brake being followed (or last followed), from the state at run time `brake_from`.
    brake: Trajectory<0>,
    brake_from: f64,
    /// The recent brakes, the last one last (at most [`EPISODES`]).
    episodes: std::collections::VecDeque<Episode>,
    /// Clearance of the last point handed out from the nearest obstacle checked (infinite: none near).
    clearance: f64,
    /// Clearance of the candidate point.
    candidate_clearance: f64,
    /// Scratch.
    sample: DataArrayOrVec<f64, 0>,
    position: Vec<f64>,
    local: Vec<f64>,
    center: Vec<f64>,
    eval: WorldEval,
    halfspaces: Vec<HalfSpace>,
}

/// Brakes remembered for rollbacks.
const EPISODES: usize = 64;

/// One brake: from its first point (`since`) to the first point handed out after it (`ended`), planned with
/// `bounds` per axis. A per-axis time-optimal brake planned again with the same bounds from one of its points goes on
/// the same way, so a rollback into it plans it again from the point kept.
#[derive(Debug, Clone)]
struct Episode {
    since: f64,
    ended: Option<f64>,
    bounds: Vec<f64>,
}

/// A half-space that holds an obstacle: `n . (y - z - w s) <= 0` at time `s` after the candidate's.
#[derive(Debug, Clone)]
struct HalfSpace {
    n: Vec<f64>,
    z: Vec<f64>,
    w: Vec<f64>,
}

impl std::fmt::Debug for GuardGroup {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GuardGroup")
            .field("dims", &self.dims)
            .field("bounds", &self.bounds)
            .field("verified", &self.verified)
            .field("episodes", &self.episodes)
            .finish_non_exhaustive()
    }
}

/// The safety distance of a run: one guard per robot whose position has finite acceleration and jerk bounds.
#[derive(Debug, Default)]
pub(super) struct Guard {
    margin: f64,
    groups: Vec<GuardGroup>,
    h: f64,
}

/// What the guard did at a point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Guarded {
    /// The candidate point is handed out.
    Clear,
    /// The point is the brake's: the robot is blocked.
    Braking,
}

/// A bound on how far one axis at speed `v` and acceleration `a` (magnitudes) travels while braking to rest at
/// acceleration `am` and jerk `jm`: its speed peaks at `v_p = v + a² / (2 jm)` while the acceleration returns to
/// zero (in `a / jm`), then braking from `v_p` covers `v_p² / (2 am) + v_p am / (2 jm)`.
fn stopping_distance(v: f64, a: f64, am: f64, jm: f64) -> f64 {
    let v_p = v + a * a / (2.0 * jm);
    v_p * a / jm + v_p * v_p / (2.0 * am) + v_p * am / (2.0 * jm)
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

impl Guard {
    /// Guards for the position groups `groups` (dimensions and the final stage's bounds) of points `h` apart,
    /// keeping `margin` (0: no guard). Groups without finite acceleration and jerk bounds cannot brake and get none.
    pub(super) fn new(groups: &[(Vec<usize>, Bounds)], margin: f64, h: f64) -> Self {
        if margin <= 0.0 {
            return Self { margin: 0.0, groups: Vec::new(), h };
        }
        let groups = groups
            .iter()
            .filter(|(dims, b)| !dims.is_empty() && b.a.is_finite() && b.j.is_finite())
            .map(|(dims, bounds)| {
                let n = dims.len();
                let mut input = InputParameter::new(Some(n));
                input.control_interface = ControlInterface::Velocity;
                input.synchronization = Synchronization::None;
                GuardGroup {
                    dims: dims.clone(),
                    bounds: *bounds,
                    otg: Ruckig::new(Some(n), h),
                    input,
                    plan: Trajectory::new(Some(n)),
                    plan_at: f64::NEG_INFINITY,
                    verified: false,
                    spare: Trajectory::new(Some(n)),
                    plan_bounds: vec![0.0; 3 * n],
                    spare_bounds: vec![0.0; 3 * n],
                    brake: Trajectory::new(Some(n)),
                    brake_from: 0.0,
                    episodes: Default::default(),
                    clearance: f64::INFINITY,
                    candidate_clearance: f64::INFINITY,
                    sample: DataArrayOrVec::new(Some(n), 0.0),
                    position: vec![0.0; n],
                    local: vec![0.0; n],
                    center: vec![0.0; n],
                    eval: WorldEval::new(n),
                    halfspaces: Vec::new(),
                }
            })
            .collect();
        Self { margin, groups, h }
    }

    /// Whether the last point handed out was a brake's (braking, or held at rest, before the margin).
    pub(super) fn is_blocked(&self) -> bool {
        self.groups.iter().any(|g| g.episodes.back().is_some_and(|e| e.ended.is_none()))
    }

    /// True when there is nothing to guard.
    pub(super) fn is_off(&self) -> bool {
        self.groups.is_empty()
    }

    /// The output restarts (new limits): no brake is known any more.
    pub(super) fn reset(&mut self) {
        for g in &mut self.groups {
            g.verified = false;
            g.episodes.clear();
            g.clearance = f64::INFINITY;
        }
    }

    /// The run rolled back: the last point kept is at run time `kept`, its state in `limiter`. A brake it was part
    /// of goes on from it (planned again with the same bounds); from a point that was handed out as a candidate, a
    /// brake is planned afresh when needed: the one it was checked with.
    pub(super) fn rollback(&mut self, kept: f64, limiter: &Limiter) {
        let half = 0.5 * self.h;
        for g in &mut self.groups {
            while g.episodes.back().is_some_and(|e| e.since > kept + half) {
                g.episodes.pop_back();
            }
            if let Some(e) = g.episodes.back_mut()
                && e.ended.is_none_or(|end| kept < end - half)
            {
                e.ended = None;
                let bounds = e.bounds.clone();
                g.plan_brake(limiter, Some(&bounds));
                g.brake_from = kept;
            }
            // The verified brake belongs to a later point, unless it is the kept one's.
            g.verified &= (g.plan_at - kept).abs() < half;
            g.clearance = f64::INFINITY;
        }
    }

    /// Guards the candidate point `(x, xd, xdd)` at run time `t` against `obstacles` (their true shapes): hands it
    /// out as it is when every robot's brake from it keeps the margin, else rewrites every guarded robot's
    /// position with the next point of the brake of the last point handed out (from `limiter`, which gives the
    /// motion handed out with it).
    pub(super) fn guard(
        &mut self,
        t: f64,
        x: &mut [f64],
        xd: &mut [f64],
        xdd: &mut [f64],
        obstacles: &[Obstacle],
        limiter: &Limiter,
    ) -> Guarded {
        let margin = self.margin;
        let h = self.h;
        let mut clear = true;
        for g in &mut self.groups {
            clear &= g.check(t, x, xd, xdd, obstacles, margin, h);
        }
        if clear {
            for g in &mut self.groups {
                g.accept(t);
            }
            return Guarded::Clear;
        }
        for g in &mut self.groups {
            g.brake_step(t, x, xd, xdd, limiter, h);
            g.note_clearance(t, x, obstacles, margin);
        }
        Guarded::Braking
    }
}

impl GuardGroup {
    /// The per-axis bounds of a brake from `(v, a)` into `self.input`: shares along the velocity, never below the
    /// state's own use of an axis.
    fn set_brake_bounds(&mut self) {
        let n = self.dims.len();
        let b = self.bounds;
        let (mut wv, mut wa, mut wj, mut fv, mut fa) =
            (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        let speed = (0..n).map(|k| self.input.current_velocity[k].powi(2)).sum::<f64>().sqrt();
        for k in 0..n {
            let along = if speed > 1e-12 {
                self.input.current_velocity[k].abs() / speed
            } else {
                1.0 / (n as f64).sqrt()
            };
            wv[k] = along.max(MIN_WEIGHT);
        }
        wa.copy_from_slice(&wv);
        wj.copy_from_slice(&wv);
        split(&mut wj, &vec![0.0; n]);
        for k in 0..n {
            let (v, a) = (self.input.current_velocity[k], self.input.current_acceleration[k]);
            fv[k] = if b.v.is_finite() { peak_speed(v, a, b.j * wj[k]) / b.v } else { 0.0 };
            fa[k] = a.abs() / b.a;
        }
        split(&mut wv, &fv);
        split(&mut wa, &fa);
        for k in 0..n {
            let (v, a) = (self.input.current_velocity[k], self.input.current_acceleration[k]);
            let top = peak_speed(v, a, b.j * wj[k]);
            self.input.max_velocity[k] =
                if b.v.is_finite() { (b.v * wv[k]).max(top) } else { top.max(1.0) * 1e3 };
            self.input.max_acceleration[k] = (b.a * wa[k]).max(a.abs());
            self.input.max_jerk[k] = b.j * wj[k];
            self.input.target_velocity[k] = 0.0;
            self.input.target_acceleration[k] = 0.0;
        }
    }

    /// The clearance of the point `p` at time `t` from `obstacles`: exact for those whose bounding ball comes
    /// within `band` of it, else the bound the ball gives. With `halfspaces`, also the half-space that holds each
    /// obstacle checked exactly (empty when `p` is inside one).
    #[allow(clippy::too_many_arguments)]
    fn clearance_at(
        t: f64,
        p: &[f64],
        obstacles: &[Obstacle],
        band: impl Fn(f64) -> f64,
        center: &mut [f64],
        local: &mut [f64],
        eval: &mut WorldEval,
        mut halfspaces: Option<&mut Vec<HalfSpace>>,
    ) -> f64 {
        let n = p.len();
        let mut nearest = f64::INFINITY;
        for o in obstacles.iter().filter(|o| o.dim() == n) {
            o.center_at(t, center);
            let r = o.shape().bounding_radius_sq().sqrt();
            let from_centre = p.iter().zip(center.iter()).map(|(a, c)| (a - c) * (a - c)).sum::<f64>().sqrt();
            if from_centre - r > band(norm(o.velocity())) {
                nearest = nearest.min(from_centre - r);
                continue;
            }
            if eval.value(o.shape(), o.rotation(), center, p) <= 0.0 {
                return 0.0;
            }
            WorldEval::to_local(o.rotation(), center, p, local);
            let (d, z_local) = nearest_surface_point(o.shape(), local);
            if !(d.is_finite() && d > 0.0) {
                return 0.0;
            }
            nearest = nearest.min(d);
            if let Some(hs) = halfspaces.as_deref_mut() {
                let mut z = vec![0.0; n];
                rotate(o.rotation(), &z_local, &mut z);
                z.iter_mut().zip(center.iter()).for_each(|(zk, c)| *zk += c);
                let normal = p.iter().zip(&z).map(|(a, b)| (a - b) / d).collect();
                hs.push(HalfSpace { n: normal, z, w: o.velocity().to_vec() });
            }
        }
        nearest
    }

    /// Whether the brake from the candidate point keeps the margin (its plan then waits in `spare`).
    #[allow(clippy::too_many_arguments)]
    fn check(
        &mut self,
        t: f64,
        x: &[f64],
        xd: &[f64],
        xdd: &[f64],
        obstacles: &[Obstacle],
        margin: f64,
        h: f64,
    ) -> bool {
        let n = self.dims.len();
        let b = self.bounds;
        for (k, &i) in self.dims.iter().enumerate() {
            self.position[k] = x[i];
        }
        let speed = self.dims.iter().map(|&i| xd[i] * xd[i]).sum::<f64>().sqrt();
        let acc = self.dims.iter().map(|&i| xdd[i] * xdd[i]).sum::<f64>().sqrt();
        // Bounds on the brake's length and duration.
        let t_a = acc / b.j;
        let v_p = speed + acc * acc / (2.0 * b.j);
        let reach = v_p * t_a + v_p * v_p / (2.0 * b.a) + v_p * b.a / (2.0 * b.j);
        let duration = t_a + v_p / b.a + b.a / b.j + h;
        // The clearance required: the margin, or less where the robot already is (it may not come closer).
        let required = margin.min(self.clearance) * (1.0 - 1e-9);
        self.halfspaces.clear();
        let band = |w: f64| required + reach + v_p * h + w * duration;
        let d = Self::clearance_at(
            t,
            &self.position,
            obstacles,
            band,
            &mut self.center,
            &mut self.local,
            &mut self.eval,
            Some(&mut self.halfspaces),
        );
        self.candidate_clearance = d;
        if d < required {
            return false;
        }
        if self.halfspaces.is_empty() {
            return true;
        }
        for (k, &i) in self.dims.iter().enumerate() {
            self.input.current_position[k] = x[i];
            self.input.current_velocity[k] = xd[i];
            self.input.current_acceleration[k] = xdd[i];
        }
        self.set_brake_bounds();
        self.save_bounds(false);
        // Every brake from here with these shares stays within `axes` of the candidate (each axis within its own
        // stopping distance), plus what the obstacles travel: one computed later from it (at a rejection) keeps the
        // margin as well, so none is planned now.
        let axes = (0..n)
            .map(|k| {
                let (v, a) = (self.input.current_velocity[k].abs(), self.input.current_acceleration[k].abs());
                let (am, jm) = (self.input.max_acceleration[k], self.input.max_jerk[k]);
                stopping_distance(v, a, am, jm).powi(2)
            })
            .sum::<f64>()
            .sqrt();
        let travel = self.halfspaces.iter().map(|hs| norm(&hs.w)).fold(0.0, f64::max) * duration;
        if d - axes - travel - v_p * h >= required {
            self.halfspaces.clear();
            return true;
        }
        // The candidate's brake, sampled.
        if !matches!(
            self.otg.calculate(&self.input, &mut self.spare),
            Ok(RuckigResult::Working | RuckigResult::Finished)
        ) {
            return false;
        }
        let total = self.spare.get_duration();
        let steps = ((total / h).ceil() as usize).clamp(1, BRAKE_SAMPLES);
        let delta = total / steps as f64;
        let top = v_p.max(speed);
        for s in 0..=steps {
            let at = s as f64 * delta;
            self.spare.at_time(at, &mut Some(&mut self.sample), &mut None, &mut None, &mut None, &mut None);
            for hs in &self.halfspaces {
                let gap: f64 = (0..n).map(|k| hs.n[k] * (self.sample[k] - hs.z[k] - hs.w[k] * at)).sum();
                let slack = if s == 0 { 0.0 } else { 0.5 * delta * (top + norm(&hs.w)) };
                if gap < required + slack {
                    return false;
                }
            }
        }
        true
    }

    /// Notes the clearance of the point handed out, `x` at time `t` (a brake's: exact within the margin's reach).
    fn note_clearance(&mut self, t: f64, x: &[f64], obstacles: &[Obstacle], margin: f64) {
        for (k, &i) in self.dims.iter().enumerate() {
            self.position[k] = x[i];
        }
        self.clearance = Self::clearance_at(
            t,
            &self.position,
            obstacles,
            |_| 2.0 * margin,
            &mut self.center,
            &mut self.local,
            &mut self.eval,
            None,
        );
    }

    /// The candidate at run time `t` is handed out: its brake (if it was computed) becomes the verified one.
    fn accept(&mut self, t: f64) {
        if self.halfspaces.is_empty() {
            self.verified = false;
        } else {
            std::mem::swap(&mut self.plan, &mut self.spare);
            std::mem::swap(&mut self.plan_bounds, &mut self.spare_bounds);
            self.plan_at = t;
            self.verified = true;
        }
        if let Some(e) = self.episodes.back_mut().filter(|e| e.ended.is_none()) {
            e.ended = Some(t);
        }
        self.clearance = self.candidate_clearance;
    }

    /// Copies the per-axis bounds in `self.input` into `plan_bounds` (`to_plan`) or `spare_bounds`.
    fn save_bounds(&mut self, to_plan: bool) {
        let n = self.dims.len();
        let out = if to_plan { &mut self.plan_bounds } else { &mut self.spare_bounds };
        for k in 0..n {
            out[3 * k] = self.input.max_velocity[k];
            out[3 * k + 1] = self.input.max_acceleration[k];
            out[3 * k + 2] = self.input.max_jerk[k];
        }
    }

    /// Plans `brake` from the last point handed out (in `limiter`), with the per-axis `bounds` given (a brake
    /// planned again) or those of its state (a new one, saved in `plan_bounds`). False when Ruckig finds no plan.
    fn plan_brake(&mut self, limiter: &Limiter, bounds: Option<&[f64]>) -> bool {
        for (k, &i) in self.dims.iter().enumerate() {
            let (p, v, a) = limiter.last_state(i);
            self.input.current_position[k] = p;
            self.input.current_velocity[k] = v;
            self.input.current_acceleration[k] = a;
        }
        self.set_brake_bounds();
        match bounds {
            Some(b) => {
                for k in 0..self.dims.len() {
                    self.input.max_velocity[k] = b[3 * k];
                    self.input.max_acceleration[k] =
                        b[3 * k + 1].max(self.input.current_acceleration[k].abs());
                    self.input.max_jerk[k] = b[3 * k + 2];
                }
            }
            None => self.save_bounds(true),
        }
        self.otg.calculate(&self.input, &mut self.brake).is_ok()
    }

    /// Rewrites the group's dimensions of the point at run time `t` with the brake's point there: the brake being
    /// followed, or else the verified brake of the last point handed out, or else (nothing was near at that point,
    /// or it had room enough for any brake) one planned from it now.
    fn brake_step(
        &mut self,
        t: f64,
        x: &mut [f64],
        xd: &mut [f64],
        xdd: &mut [f64],
        limiter: &Limiter,
        h: f64,
    ) {
        let following = self.episodes.back().is_some_and(|e| e.ended.is_none());
        if !following {
            let last = t - h;
            let planned = if self.verified && (self.plan_at - last).abs() < 0.5 * h {
                std::mem::swap(&mut self.brake, &mut self.plan);
                self.verified = false;
                true
            } else {
                self.plan_brake(limiter, None)
            };
            if !planned {
                // No plan at all (not expected from a state within the bounds): hold the last position.
                for &i in &self.dims {
                    let (p, _, _) = limiter.last_state(i);
                    let (p, v, a) = limiter.motion_to(i, p);
                    (x[i], xd[i], xdd[i]) = (p, v, a);
                }
                return;
            }
            self.brake_from = last;
            if self.episodes.len() == EPISODES {
                self.episodes.pop_front();
            }
            self.episodes.push_back(Episode { since: t, ended: None, bounds: self.plan_bounds.clone() });
        }
        self.brake.at_time(
            t - self.brake_from,
            &mut Some(&mut self.sample),
            &mut None,
            &mut None,
            &mut None,
            &mut None,
        );
        for (k, &i) in self.dims.iter().enumerate() {
            let (p, v, a) = limiter.motion_to(i, self.sample[k]);
            (x[i], xd[i], xdd[i]) = (p, v, a);
        }
    }
}
