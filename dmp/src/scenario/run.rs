//! Turning a scenario into engine objects (validating every field on the way) and running it offline.

use super::model::{FootprintSpec, Scenario};
use super::pose::{self, PoseSetup};
use super::to_engine::superquadric;
use crate::avoidance::Avoidance;
use crate::error::{DmpError, InvalidInput, Result, ensure_positive};
use crate::field::{Agent, RepulsiveField, Scene};
use crate::integrate::Motion;
use crate::isopotential::Shape;
use crate::learn::{Demonstration, LearnConfig, learn};
use crate::metrics::{Metrics, metrics};
use crate::primitive::Primitive;
use crate::rollout::{MAX_ROLLOUT_STEPS, Rollout, rollout, rollout_pose};

/// A validated scenario, learned and ready to roll out.
#[derive(Debug, Clone)]
pub struct Prepared {
    /// The scenario's name.
    pub name: String,
    /// The demonstration.
    pub demonstration: Demonstration,
    /// The learned primitive.
    pub primitive: Primitive,
    /// Start, goal and tau of the rollout.
    pub motion: Motion,
    /// Obstacles, robots and methods.
    pub scene: Scene,
    /// Fixed step.
    pub dt: f64,
    /// Number of steps (`duration / dt`, rounded).
    pub steps: usize,
    /// Physical duration.
    pub duration: f64,
    /// A pose scenario's chart and tool (`None`: a position scenario).
    pub pose: Option<PoseSetup>,
}

impl Prepared {
    /// Rolls the primitive out avoiding `field`'s scene (a pose scenario with its chart, holding its tool).
    pub fn roll_out(&self, field: &RepulsiveField) -> Result<Rollout> {
        match &self.pose {
            None => rollout(&self.primitive, &self.motion, field, self.dt, self.steps),
            Some(pose) => rollout_pose(
                &self.primitive,
                &self.motion,
                field,
                self.dt,
                self.steps,
                pose.chart,
                pose.tool.clone(),
            ),
        }
    }

    /// The dimensions of the positions (all of them but a pose primitive's last three).
    pub fn position_dim(&self) -> usize {
        self.primitive.position_dim()
    }

    /// The compiled repulsive field of the scene.
    pub fn field(&self) -> Result<RepulsiveField> {
        RepulsiveField::new(self.scene.clone(), self.primitive.dim)
    }

    /// The same robots with nothing to avoid: the obstacle-free DMP.
    pub(crate) fn free_field(&self) -> Result<RepulsiveField> {
        let scene = Scene { obstacles: Vec::new(), robot_avoidance: Avoidance::NONE, ..self.scene.clone() };
        RepulsiveField::new(scene, self.primitive.dim)
    }
}

/// The result of [`run`].
#[derive(Debug, Clone)]
pub struct ScenarioOutcome {
    /// The obstacle-free rollout.
    pub free: Rollout,
    /// The rollout with avoidance.
    pub adapted: Rollout,
    /// The SPEC's metrics (`compute_seconds` is left at zero: the caller owns the clock).
    pub metrics: Metrics,
}

/// Validates `s` and learns its primitive.
pub fn prepare(s: &Scenario) -> Result<Prepared> {
    let demonstration = Demonstration::new(s.demonstration.t.clone(), s.demonstration.x.clone())?;
    let dim = demonstration.dim();
    let config = LearnConfig {
        n_basis: s.dmp.n,
        k: s.dmp.k.to_vec(),
        d: s.dmp.d.as_ref().map(|d| d.to_vec()),
        alpha: s.dmp.alpha,
    };
    let posed = !s.demonstration.q.is_empty();
    if !posed {
        let needs_q = "needs a pose demonstration: give `demonstration.q`, one orientation per sample";
        if s.tool.is_some() {
            return Err(InvalidInput::new("tool", needs_q).into());
        }
        for (q, field) in [
            (s.rollout.start_orientation, "rollout.start_orientation"),
            (s.rollout.goal_orientation, "rollout.goal_orientation"),
        ] {
            if q.is_some() {
                return Err(InvalidInput::new(field, needs_q).into());
            }
        }
    } else if !s.robots.is_empty() {
        return Err(InvalidInput::new(
            "robots",
            "a pose scenario has one robot (it owns the position dimensions): leave `robots` empty",
        )
        .into());
    }
    let primitive =
        if posed { pose::learn(s, &demonstration, &config)? } else { learn(&demonstration, &config)? };

    let r = &s.rollout;
    ensure_positive(|| "rollout.dt".into(), r.dt)?;
    ensure_positive(|| "rollout.duration".into(), r.duration)?;
    let steps_f = (r.duration / r.dt).round();
    if steps_f > MAX_ROLLOUT_STEPS as f64 {
        return Err(InvalidInput::new(
            "rollout.duration",
            format!("duration / dt = {steps_f:e} steps, more than the limit of {MAX_ROLLOUT_STEPS}"),
        )
        .into());
    }
    let steps = (steps_f as usize).max(1);
    let motion = Motion {
        start: r.start.clone().unwrap_or_else(|| primitive.start[..dim].to_vec()),
        goal: r.goal.clone().unwrap_or_else(|| primitive.goal[..dim].to_vec()),
        tau: r.tau.unwrap_or(primitive.tau),
    };
    motion.validate(dim).map_err(|e| prefixed("rollout", e))?;
    let (motion, pose) = if posed {
        let (motion, chart) = pose::motion(s, &primitive, motion)?;
        let tool = s.tool.as_ref().map(pose::tool).transpose()?;
        (motion, Some(PoseSetup { chart, tool }))
    } else {
        (motion, None)
    };

    let mut obstacles = Vec::with_capacity(s.obstacles.len());
    for (i, o) in s.obstacles.iter().enumerate() {
        if s.obstacles[..i].iter().any(|p| p.id == o.id) {
            return Err(
                InvalidInput::new(format!("obstacles[{i}].id"), format!("`{}` is used twice", o.id)).into()
            );
        }
        obstacles.push(o.to_obstacle().map_err(|e| prefixed_err(&format!("obstacles[{i}]"), e))?);
    }
    let mut agents = Vec::with_capacity(s.robots.len());
    for (i, r) in s.robots.iter().enumerate() {
        if s.robots[..i].iter().any(|p| p.id == r.id) {
            return Err(
                InvalidInput::new(format!("robots[{i}].id"), format!("`{}` is used twice", r.id)).into()
            );
        }
        let footprint =
            footprint(&r.footprint).map_err(|e| prefixed_err(&format!("robots[{i}].footprint"), e))?;
        agents.push(Agent { id: r.id.clone(), dims: r.dims.clone(), footprint: Some(footprint) });
    }
    if posed {
        // The one robot of a pose run owns the position dimensions, as in its execution.
        agents = vec![Agent { id: "robot".into(), dims: (0..dim).collect(), footprint: None }];
    }
    let scene = Scene {
        obstacles,
        avoidance: s.avoidance,
        agents,
        robot_avoidance: s.robot_avoidance.unwrap_or(Avoidance::NONE),
        point_samples: s.point_samples,
    };
    // Compiling the field checks dimensions and method parameters.
    RepulsiveField::new(scene.clone(), primitive.dim)?;
    Ok(Prepared {
        name: s.name.clone(),
        demonstration,
        primitive,
        motion,
        scene,
        dt: r.dt,
        steps,
        duration: r.duration,
        pose,
    })
}

/// Rolls the prepared scenario out with and without obstacles and measures it.
pub fn run(p: &Prepared) -> Result<ScenarioOutcome> {
    let free = p.roll_out(&p.free_field()?)?;
    let adapted = p.roll_out(&p.field()?)?;
    let metrics = metrics(p, &free, &adapted)?;
    Ok(ScenarioOutcome { free, adapted, metrics })
}

fn footprint(f: &FootprintSpec) -> Result<Shape> {
    superquadric(&f.semi_axes, f.exponents.as_deref())
}

fn prefixed(prefix: &str, e: InvalidInput) -> DmpError {
    InvalidInput::new(format!("{prefix}.{}", e.field), e.rule).into()
}

fn prefixed_err(prefix: &str, e: DmpError) -> DmpError {
    match e {
        DmpError::Invalid(i) => prefixed(prefix, i),
        other => other,
    }
}
