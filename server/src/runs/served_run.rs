//! A run as the server serves it: the engine's [`Execution`] and what the server knows around it (whether the
//! cell's scene applies, the members' footprints as sent). The server's types are converted to the engine's here,
//! at the edge: the cell's obstacles with their age, the cell's other robots as [`CellMate`]s.

use std::sync::Arc;

use dmp::execution::{CellMate, CellMateAvoidance};
use dmp::field::{Agent, Scene};
use dmp::{Avoidance, Execution, Motion, Obstacle, Primitive, Stepping};
use dmp_proto::v1;

use crate::cells::cell::{ObstacleSet, SeenRobot};
use crate::error::ServerError;
use crate::runs::compute::cost::{Avoided, LIMITED_COST, Workload};
use crate::runs::verdict::Judge;

/// How a request asked its run to avoid things.
#[derive(Debug, Clone)]
pub(crate) struct RunAvoidance {
    /// Method for obstacles and its boundary sample count.
    pub obstacles: (Avoidance, usize),
    /// Method for other robots (of the group and of the cell) and its sample count.
    pub robots: (Avoidance, usize),
    /// Obstacles of this run only (centres at the start of the run).
    pub extra: Vec<Obstacle>,
    /// Ignore the cell's scene.
    pub ignore_scene: bool,
}

/// A served run.
#[derive(Debug)]
pub(crate) struct ServedRun {
    /// The engine's run.
    pub execution: Execution,
    /// The run does not avoid the cell's obstacles (only its own and the robots).
    pub ignore_scene: bool,
    /// Each member's footprint as sent, for its published state (in the members' order).
    pub footprints: Vec<Option<v1::Superquadric>>,
    /// The version of the cell's scene the run avoids.
    pub scene_version: u64,
    /// What the run's verdict depends on, recorded as its segments are made ([`crate::runs::verdict`]).
    pub judge: Judge,
    /// What the run's cost depends on besides the cell.
    costing: Costing,
}

/// What a run's cost depends on besides the cell's obstacles and robots.
#[derive(Debug, Clone)]
struct Costing {
    obstacles: (dmp::Method, usize),
    robots: (dmp::Method, usize),
    /// The run's own obstacles.
    extra: usize,
    /// Members of the group (each a moving obstacle for the others).
    members: usize,
    /// Gaussians of the forcing term (N + 1).
    basis: usize,
}

impl ServedRun {
    /// A run of `primitive` with `motion` for `members` (their footprints as sent alongside), avoiding as asked,
    /// stepping as asked, keeping `history` output points for rollbacks.
    pub(crate) fn new(
        primitive: Primitive,
        motion: Motion,
        members: Vec<(Agent, Option<v1::Superquadric>)>,
        avoidance: RunAvoidance,
        stepping: Stepping,
        history: usize,
    ) -> Result<Self, ServerError> {
        let (agents, footprints): (Vec<Agent>, Vec<_>) = members.into_iter().unzip();
        let group = agents.len() > 1;
        let costing = Costing {
            obstacles: (avoidance.obstacles.0.method, avoidance.obstacles.1),
            robots: (avoidance.robots.0.method, avoidance.robots.1),
            extra: avoidance.extra.len(),
            members: agents.len(),
            basis: primitive.weights.first().map_or(0, Vec::len),
        };
        let scene = Scene {
            obstacles: avoidance.extra,
            avoidance: avoidance.obstacles.0,
            agents,
            robot_avoidance: if group { avoidance.robots.0 } else { Avoidance::NONE },
            point_samples: avoidance.obstacles.1.max(avoidance.robots.1),
        };
        let cell_mates = CellMateAvoidance { method: avoidance.robots.0, point_samples: avoidance.robots.1 };
        let execution = Execution::new(primitive, motion, scene, cell_mates, stepping, history)?;
        Ok(Self {
            execution,
            ignore_scene: avoidance.ignore_scene,
            footprints,
            scene_version: 0,
            judge: Judge::default(),
            costing,
        })
    }

    /// What the run costs to compute in a cell of `cell_obstacles` obstacles and `cell_robots` other robots.
    pub(crate) fn workload(&self, cell_obstacles: usize, cell_robots: usize) -> Workload {
        let c = &self.costing;
        // A held tool feels every obstacle and robot at each of its control points.
        let points = self.execution.tool().map_or(1, |t| t.control_points().len());
        let avoided = Avoided {
            obstacles: (&c.obstacles.0, c.obstacles.1),
            obstacle_count: (c.extra + if self.ignore_scene { 0 } else { cell_obstacles }) * points,
            robots: (&c.robots.0, c.robots.1),
            // Each member avoids, in its own dimensions, the others of its group and the cell's robots.
            robot_count: (c.members.saturating_sub(1) + cell_robots) * points,
        };
        let w = Workload::of(self.execution.dim(), c.basis, avoided, self.execution.stepping());
        // The final stage tracks the DMP where a run keeps limits.
        if self.execution.limits().is_none() { w } else { w.scaled(LIMITED_COST) }
    }

    /// Sets the cell's obstacles (as they are at wall time `now_unix_s`, which is the run's current time) and its
    /// other robots.
    pub(crate) fn apply_scene(
        &mut self,
        snapshot: &ObstacleSet,
        others: &[Arc<SeenRobot>],
        now_unix_s: f64,
    ) -> Result<(), ServerError> {
        let seen = snapshot.obstacles.values().map(|o| (&o.engine, now_unix_s - o.received_unix_s));
        if self.ignore_scene {
            self.execution.set_obstacles(std::iter::empty())?;
        } else {
            self.execution.set_obstacles(seen)?;
        }
        self.scene_version = snapshot.version;
        self.set_cell_mates(others, now_unix_s)
    }

    /// Updates the cell's other robots from their last states (robots without a footprint are invisible).
    pub(crate) fn set_cell_mates(
        &mut self,
        others: &[Arc<SeenRobot>],
        now_unix_s: f64,
    ) -> Result<(), ServerError> {
        let mates = others.iter().filter_map(|r| {
            Some(CellMate {
                id: &r.state.robot_id,
                footprint: r.footprint.as_ref()?,
                position: &r.state.position,
                velocity: &r.state.velocity,
                age: now_unix_s - r.state.stamp_unix_s,
            })
        });
        Ok(self.execution.set_cell_mates(mates)?)
    }
}
