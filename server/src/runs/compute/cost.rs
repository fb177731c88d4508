//! What a request will cost the compute threads, estimated before it is admitted.
//!
//! The unit is a *work unit*: one term evaluated in one dimension at one stage of a step, weighted by what that
//! term costs next to one basis function of the forcing term (the cheapest term, weight 1). So a work unit is
//! about the time of one Gaussian of the forcing term in one dimension, whatever the machine; the budgets in
//! `[compute]` are in these units. A step costs
//!
//! `stages × dim × (N + 1 + Σ_obstacles samples × weight(method) + robots × samples × weight(robot method))`,
//!
//! i.e. obstacles × samples × dimensions × steps, as a request is costed. Each output point also checks contacts
//! (`dim` per obstacle) and is interpolated (`dim`).

use dmp::{Method, Stepping};

/// The stages of one fixed RK4 step.
const RK4_STAGES: f64 = 4.0;
/// The stages of one adaptive Dormand–Prince step (seven, the last reused on acceptance).
const DP_STAGES: f64 = 7.0;
/// Adaptive steps per largest step allowed: the steps it takes, rejected ones included, in the stiff parts of a
/// run, charged on average over the run.
const ADAPTIVE_STEPS_PER_LARGEST: f64 = 2.0;

/// What a run under limits costs per point, relative to the same run without: the final stage (a jerk-limited
/// generator that tracks the DMP) measured 14 – 22 % more per point on the benchmark's reaches (BENCHMARKS.md,
/// "Final stage"), charged at the top of that range with some room.
pub const LIMITED_COST: f64 = 1.25;

/// The weight of one boundary sample (point methods) or one obstacle (volumetric methods) of `method`, in basis
/// functions: the relative cost of its term, from the engine's step benchmark (`cargo bench -p dmp --bench step`).
pub fn term_weight(method: &Method) -> f64 {
    match method {
        Method::None => 0.0,
        Method::StaticPoint(_) => 3.0,
        Method::DynamicPoint(_) => 8.0,
        Method::SteeringAngle(_) => 13.0,
        Method::StaticVolumetric(_) | Method::DynamicVolumetric(_) => 25.0,
    }
}

/// The terms a method evaluates per obstacle: its boundary samples for the point methods, one for the volumetric.
pub fn samples_per_obstacle(method: &Method, point_samples: usize) -> f64 {
    match method {
        Method::None => 0.0,
        Method::StaticPoint(_) | Method::DynamicPoint(_) | Method::SteeringAngle(_) => point_samples as f64,
        Method::StaticVolumetric(_) | Method::DynamicVolumetric(_) => 1.0,
    }
}

/// The size of a run's work: what one of its steps and one of its output points cost.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Workload {
    /// Work units of one internal step.
    pub per_step: f64,
    /// Work units of one output point (interpolation and contact checks).
    pub per_point: f64,
    /// Internal steps per output point (at most one).
    pub steps_per_point: f64,
    /// Work units of building the run's field once (sampling every obstacle's boundary), paid again on each scene
    /// change.
    pub per_scene: f64,
}

/// What a run avoids, for its cost.
#[derive(Debug, Clone, Copy)]
pub struct Avoided<'a> {
    /// The method for obstacles and its boundary samples.
    pub obstacles: (&'a Method, usize),
    /// Obstacles: the run's own and the cell's (when it does not ignore the scene).
    pub obstacle_count: usize,
    /// The method for robots and its boundary samples.
    pub robots: (&'a Method, usize),
    /// The other robots: the group's and the cell's.
    pub robot_count: usize,
}

impl Workload {
    /// The workload of a run in `dim` dimensions with `basis` Gaussians (N + 1), avoiding `avoided`, stepped by
    /// `stepping`.
    pub fn of(dim: usize, basis: usize, avoided: Avoided<'_>, stepping: &Stepping) -> Self {
        let d = dim.max(1) as f64;
        let (om, os) = avoided.obstacles;
        let (rm, rs) = avoided.robots;
        let obstacle_terms = avoided.obstacle_count as f64 * samples_per_obstacle(om, os) * term_weight(om);
        let robot_terms = avoided.robot_count as f64 * samples_per_obstacle(rm, rs) * term_weight(rm);
        let (stages, steps_per_point) = match stepping.tolerance {
            None => (RK4_STAGES, 1.0 / stepping.step_points.max(1) as f64),
            Some(_) => {
                (DP_STAGES, (ADAPTIVE_STEPS_PER_LARGEST / stepping.step_points.max(1) as f64).min(1.0))
            }
        };
        Self {
            per_step: stages * d * (basis as f64 + obstacle_terms + robot_terms),
            per_point: d * (2.0 + (avoided.obstacle_count + avoided.robot_count) as f64),
            steps_per_point,
            per_scene: d
                * (avoided.obstacle_count as f64 * samples_per_obstacle(om, os)
                    + avoided.robot_count as f64 * samples_per_obstacle(rm, rs)),
        }
    }

    /// The same workload with each step and point costing `factor` times as much (a run under limits,
    /// [`LIMITED_COST`]).
    pub fn scaled(self, factor: f64) -> Self {
        Self { per_step: self.per_step * factor, per_point: self.per_point * factor, ..self }
    }

    /// Work units of `points` output points.
    pub fn of_points(&self, points: f64) -> f64 {
        points * (self.per_point + self.steps_per_point * self.per_step)
    }

    /// Work units per second of run time at output step `dt` (a real-time stream's rate).
    pub fn per_second(&self, dt: f64) -> f64 {
        self.of_points(1.0 / dt)
    }
}

#[cfg(test)]
mod tests {
    use dmp::avoidance::{DynamicVolumetric, StaticPoint};

    use super::*;

    #[test]
    fn a_request_costs_obstacles_times_samples_times_dimensions_times_steps() {
        let point = Method::StaticPoint(StaticPoint { eta: 1.0, p0: 1.0 });
        let none = Method::None;
        let avoided =
            |n| Avoided { obstacles: (&point, 100), obstacle_count: n, robots: (&none, 0), robot_count: 0 };
        let rk4 = Stepping::rk4(0.001);
        let w0 = Workload::of(3, 51, avoided(0), &rk4);
        let w10 = Workload::of(3, 51, avoided(10), &rk4);
        let w20 = Workload::of(3, 51, avoided(20), &rk4);
        // Linear in the obstacles: each adds samples × weight × dim × stages to a step.
        assert_eq!(w10.per_step - w0.per_step, 4.0 * 3.0 * 10.0 * 100.0 * 3.0);
        assert_eq!(w20.per_step - w10.per_step, w10.per_step - w0.per_step);
        // Linear in the steps, and in the rate.
        assert_eq!(w10.of_points(2000.0), 2.0 * w10.of_points(1000.0));
        assert_eq!(w10.per_second(0.001), w10.of_points(1000.0));
        // A coarse step costs its steps, not its points.
        let coarse =
            Workload::of(3, 51, avoided(10), &Stepping { dt: 0.001, step_points: 10, tolerance: None });
        assert!(coarse.of_points(1000.0) < w10.of_points(1000.0) / 5.0);
    }

    #[test]
    fn a_limited_run_costs_more_per_point_and_per_step() {
        let none = Method::None;
        let a = Avoided { obstacles: (&none, 0), obstacle_count: 0, robots: (&none, 0), robot_count: 0 };
        let w = Workload::of(3, 51, a, &Stepping::rk4(0.001));
        let limited = w.scaled(LIMITED_COST);
        assert_eq!(limited.per_second(0.001), LIMITED_COST * w.per_second(0.001));
        assert_eq!(limited.per_scene, w.per_scene);
    }

    #[test]
    fn volumetric_terms_cost_one_evaluation_per_obstacle() {
        let v = Method::DynamicVolumetric(DynamicVolumetric { lambda: 1.0, beta: 2.0, eta: 1.0 });
        let a = Avoided { obstacles: (&v, 10_000), obstacle_count: 10, robots: (&v, 10_000), robot_count: 0 };
        let w = Workload::of(3, 51, a, &Stepping::rk4(0.001));
        assert_eq!(w.per_step, 4.0 * 3.0 * (51.0 + 10.0 * 25.0));
    }
}
