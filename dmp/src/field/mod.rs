//! The repulsive field of a whole scene: fixed and moving obstacles, and robots that are obstacles for each other.

mod contacts;
mod kernel;

use kernel::DynamicVolumetricKernel;

use crate::avoidance::{self, Avoidance, Method, dot};
use crate::error::{InvalidInput, Result};
use crate::integrate::Perturbation;
use crate::isopotential::{Isopotential, Shape};
use crate::obstacle::{Obstacle, WorldEval, mat_vec, rotate, rotate_transposed};

/// Floor on `C` in the volumetric terms: inside an obstacle (`C <= 0`) they are undefined, so they are evaluated at
/// this value, which pushes outward along `grad C`. The step is flagged as a collision by [`RepulsiveField::contacts`].
pub const C_FLOOR: f64 = 1e-6;

/// Default cap on the norm of one robot's summed repulsive term, in units of `tau dv/dt`. It only binds at or
/// inside an obstacle's surface, where the potentials diverge; a typical drive `K (g - x)` is of order 1e3.
pub const DEFAULT_MAX_PERTURBATION: f64 = 1e6;

/// A robot that owns some dimensions of a shared DMP (the paper's youBot test).
#[derive(Debug, Clone, PartialEq)]
pub struct Agent {
    /// Its name.
    pub id: String,
    /// The DMP dimensions it owns, in order.
    pub dims: Vec<usize>,
    /// Its footprint, centred on its position: what the other robots avoid. `None`: invisible to the others.
    pub footprint: Option<Shape>,
}

/// Everything that repels: obstacles with their method, robots with theirs.
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    /// The obstacles, each in the dimension of the robots (or of the whole DMP when there are no robots).
    pub obstacles: Vec<Obstacle>,
    /// The method for `obstacles`.
    pub avoidance: Avoidance,
    /// Robots on one shared phase; empty means one implicit robot that owns every dimension.
    pub agents: Vec<Agent>,
    /// The method of the robot-robot terms.
    pub robot_avoidance: Avoidance,
    /// Boundary samples per obstacle (or footprint) for the point methods.
    pub point_samples: usize,
}

impl Scene {
    /// A scene with obstacles only.
    pub fn with_obstacles(obstacles: Vec<Obstacle>, avoidance: Avoidance, point_samples: usize) -> Self {
        Self { obstacles, avoidance, agents: Vec::new(), robot_avoidance: Avoidance::NONE, point_samples }
    }

    /// Nothing to avoid.
    pub fn empty() -> Self {
        Self::with_obstacles(Vec::new(), Avoidance::NONE, 0)
    }
}

/// Where a robot touched something.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Contact {
    /// Robot `agent` is inside obstacle `obstacle` (`C` is its isopotential there).
    Obstacle {
        /// Index of the robot.
        agent: usize,
        /// Index of the obstacle.
        obstacle: usize,
        /// `C <= 0`.
        c: f64,
    },
    /// The centre of robot `agent` is inside the footprint of robot `other`.
    Robot {
        /// Index of the robot.
        agent: usize,
        /// Index of the other robot.
        other: usize,
        /// `C <= 0`.
        c: f64,
    },
}

/// A compiled [`Scene`] for a DMP of a given dimension: boundary samples precomputed, scratch allocated once, so
/// that evaluating the field allocates nothing.
#[derive(Debug, Clone)]
pub struct RepulsiveField {
    scene: Scene,
    agents: Vec<Agent>,
    sub_dim: usize,
    obstacle_samples: Vec<Vec<f64>>,
    footprint_samples: Vec<Vec<f64>>,
    /// The shapes the potentials act on, each obstacle's true shape inflated by `keep_off`
    /// ([`RepulsiveField::keeping_off`]); empty: the true shapes.
    avoided: Vec<Shape>,
    keep_off: f64,
    max_perturbation: f64,
    /// Classified parameters of the dynamic volumetric method for obstacles and for robots, when used.
    kernels: [Option<DynamicVolumetricKernel>; 2],
    s: Scratch,
}

#[derive(Debug, Clone)]
struct Scratch {
    x: Vec<f64>,
    v: Vec<f64>,
    u: Vec<f64>,
    r: Vec<f64>,
    phi: Vec<f64>,
    center: Vec<f64>,
    hu: Vec<f64>,
    hg: Vec<f64>,
    u_local: Vec<f64>,
    phi_local: Vec<f64>,
    eval: WorldEval,
}

impl RepulsiveField {
    /// Compiles `scene` for a DMP of dimension `dim`, checking that every part fits.
    pub fn new(scene: Scene, dim: usize) -> Result<Self> {
        let agents = if scene.agents.is_empty() {
            vec![Agent { id: "robot".into(), dims: (0..dim).collect(), footprint: None }]
        } else {
            scene.agents.clone()
        };
        let sub_dim = validate_agents(&agents, dim, !scene.agents.is_empty())?;
        for (i, o) in scene.obstacles.iter().enumerate() {
            if o.dim() != sub_dim {
                return Err(InvalidInput::new(
                    format!("obstacles[{i}]"),
                    format!("has {} dimensions, but each robot moves in {sub_dim}", o.dim()),
                )
                .into());
            }
        }
        if !scene.obstacles.is_empty() {
            scene.avoidance.method.validate("avoidance", sub_dim)?;
        }
        if agents.len() > 1 {
            scene.robot_avoidance.method.validate("robot_avoidance", sub_dim)?;
            if scene.robot_avoidance.method != Method::None
                && let Some(i) = agents.iter().position(|a| a.footprint.is_none())
            {
                return Err(InvalidInput::new(
                    format!("robots[{i}].footprint"),
                    "is required for robot avoidance",
                )
                .into());
            }
        }
        let uses_points = (!scene.obstacles.is_empty() && scene.avoidance.method.is_point_method())
            || (agents.len() > 1 && scene.robot_avoidance.method.is_point_method());
        if uses_points && scene.point_samples == 0 {
            return Err(InvalidInput::new("point_samples", "must be at least 1 for the point methods").into());
        }
        let n = if uses_points { scene.point_samples } else { 0 };
        let obstacle_samples = scene.obstacles.iter().map(|o| o.boundary_offsets(n)).collect();
        let footprint_samples = agents
            .iter()
            .map(|a| match &a.footprint {
                Some(f) => Obstacle::new(&a.id, f.clone(), vec![0.0; sub_dim], None, None)
                    .map(|o| o.boundary_offsets(n))
                    .unwrap_or_default(),
                None => Vec::new(),
            })
            .collect();
        let s = Scratch {
            x: vec![0.0; sub_dim],
            v: vec![0.0; sub_dim],
            u: vec![0.0; sub_dim],
            r: vec![0.0; sub_dim],
            phi: vec![0.0; sub_dim],
            center: vec![0.0; sub_dim],
            hu: vec![0.0; sub_dim],
            hg: vec![0.0; sub_dim],
            u_local: vec![0.0; sub_dim],
            phi_local: vec![0.0; sub_dim],
            eval: WorldEval::new(sub_dim),
        };
        let (scene_avoidance, scene_robot_avoidance) = (scene.avoidance.method, scene.robot_avoidance.method);
        Ok(Self {
            scene,
            agents,
            sub_dim,
            obstacle_samples,
            footprint_samples,
            avoided: Vec::new(),
            keep_off: 0.0,
            max_perturbation: DEFAULT_MAX_PERTURBATION,
            kernels: [kernel_of(&scene_avoidance), kernel_of(&scene_robot_avoidance)],
            s,
        })
    }

    /// The same field with its potentials acting on every obstacle's shape inflated by `distance` (its semi-axes
    /// enlarged, [`Shape::inflated`]), so that the avoidance keeps off the true shapes by about that much: a safety
    /// distance. Contacts ([`RepulsiveField::contacts`]) stay those with the true shapes. 0 keeps the true shapes.
    pub fn keeping_off(mut self, distance: f64) -> Result<Self> {
        if !(distance.is_finite() && distance >= 0.0) {
            return Err(InvalidInput::new(
                "margin",
                format!("must be finite and not negative, not {distance}"),
            )
            .into());
        }
        if distance == 0.0 || self.scene.obstacles.is_empty() {
            self.avoided.clear();
            self.keep_off = 0.0;
            return Ok(self);
        }
        let n = self.obstacle_samples.first().map_or(0, |s| s.len() / self.sub_dim.max(1));
        let inflated =
            self.scene.obstacles.iter().map(|o| o.inflated(distance)).collect::<Result<Vec<_>>>()?;
        self.obstacle_samples = inflated.iter().map(|o| o.boundary_offsets(n)).collect();
        self.avoided = inflated.into_iter().map(|o| o.shape().clone()).collect();
        self.keep_off = distance;
        Ok(self)
    }

    /// How far beyond the true shapes the potentials act ([`RepulsiveField::keeping_off`]).
    pub fn keep_off(&self) -> f64 {
        self.keep_off
    }

    /// Moves obstacle `i` in place (centre at time zero, constant velocity), keeping everything compiled: the
    /// cheap update of a moving obstacle whose shape stays the same. False (and no change) when `i` is out of range
    /// or the values do not fit ([`Obstacle::set_motion`]).
    pub(crate) fn set_obstacle_motion(&mut self, i: usize, center: &[f64], velocity: &[f64]) -> bool {
        self.scene.obstacles.get_mut(i).is_some_and(|o| o.set_motion(center, velocity))
    }

    /// The scene it was built from.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The robots (one implicit robot when the scene names none).
    pub fn agents(&self) -> &[Agent] {
        &self.agents
    }

    /// Dimension each robot moves in.
    pub(crate) fn agent_dim(&self) -> usize {
        self.sub_dim
    }

    fn add_agent(&mut self, ai: usize, t: f64, x: &[f64], v: &[f64], tau: f64) {
        let s = &mut self.s;
        let a = &self.agents[ai];
        gather(x, &a.dims, &mut s.x);
        gather(v, &a.dims, &mut s.v);
        s.phi.fill(0.0);
        let av = self.scene.avoidance;
        if av.method != Method::None {
            for (oi, o) in self.scene.obstacles.iter().enumerate() {
                o.center_at(t, &mut s.center);
                for i in 0..self.sub_dim {
                    s.u[i] = if av.relative_velocity { s.v[i] - tau * o.velocity()[i] } else { s.v[i] };
                }
                apply(
                    &av.method,
                    self.kernels[0].as_ref(),
                    self.avoided.get(oi).unwrap_or(o.shape()),
                    o.rotation(),
                    &self.obstacle_samples[oi],
                    s,
                );
            }
        }
        let rv = self.scene.robot_avoidance;
        if self.agents.len() > 1 && rv.method != Method::None {
            for (bi, b) in self.agents.iter().enumerate() {
                let Some(footprint) = (bi != ai).then_some(b.footprint.as_ref()).flatten() else { continue };
                // The other robot: a moving obstacle centred on it, moving with its velocity v_b / tau.
                for (k, &dim) in b.dims.iter().enumerate() {
                    s.center[k] = x[dim];
                    s.u[k] = if rv.relative_velocity { s.v[k] - v[dim] } else { s.v[k] };
                }
                apply(&rv.method, self.kernels[1].as_ref(), footprint, None, &self.footprint_samples[bi], s);
            }
        }
        let norm = dot(&s.phi, &s.phi).sqrt();
        if norm > self.max_perturbation {
            let k = self.max_perturbation / norm;
            s.phi.iter_mut().for_each(|p| *p *= k);
        }
    }
}

impl RepulsiveField {
    /// Pushes onto `out` (once each) the indices of the obstacles whose own term is not finite at `(t, x, v)` for
    /// some robot: each obstacle evaluated alone, as [`Perturbation::add`] would sum it. The diagnosis of a step
    /// that is not finite; nothing in the hot path calls it.
    pub(crate) fn nonfinite_obstacles(
        &mut self,
        t: f64,
        x: &[f64],
        v: &[f64],
        tau: f64,
        out: &mut Vec<usize>,
    ) {
        let av = self.scene.avoidance;
        if av.method == Method::None {
            return;
        }
        for a in &self.agents {
            let s = &mut self.s;
            gather(x, &a.dims, &mut s.x);
            gather(v, &a.dims, &mut s.v);
            for (oi, o) in self.scene.obstacles.iter().enumerate() {
                o.center_at(t, &mut s.center);
                for i in 0..self.sub_dim {
                    s.u[i] = if av.relative_velocity { s.v[i] - tau * o.velocity()[i] } else { s.v[i] };
                }
                s.phi.fill(0.0);
                apply(
                    &av.method,
                    self.kernels[0].as_ref(),
                    self.avoided.get(oi).unwrap_or(o.shape()),
                    o.rotation(),
                    &self.obstacle_samples[oi],
                    s,
                );
                let finite = s.center.iter().chain(&s.phi).all(|v| v.is_finite());
                if !finite && !out.contains(&oi) {
                    out.push(oi);
                }
            }
        }
    }
}

impl Perturbation for RepulsiveField {
    fn add(&mut self, t: f64, x: &[f64], v: &[f64], tau: f64, out: &mut [f64]) {
        for ai in 0..self.agents.len() {
            self.add_agent(ai, t, x, v, tau);
            for (k, &dim) in self.agents[ai].dims.iter().enumerate() {
                out[dim] += self.s.phi[k];
            }
        }
    }
}

/// Adds the term of `method` for one obstacle (centre in `s.center`, relative velocity in `s.u`) to `s.phi`.
fn apply(
    method: &Method,
    kernel: Option<&DynamicVolumetricKernel>,
    shape: &Shape,
    rotation: Option<&[f64]>,
    samples: &[f64],
    s: &mut Scratch,
) {
    let d = s.x.len();
    if let (Some(k), Shape::Superquadric(sq)) = (kernel, shape) {
        match d {
            2 => return k.add::<2>(sq, rotation, &s.center, &s.x, &s.u, &mut s.phi),
            3 => return k.add::<3>(sq, rotation, &s.center, &s.x, &s.u, &mut s.phi),
            _ => {}
        }
    }
    match method {
        Method::None => {}
        Method::StaticPoint(p) => {
            for off in samples.chunks_exact(d) {
                sample_offset(s, off);
                avoidance::static_point::add_force(&s.r, p.eta, p.p0, &mut s.phi);
            }
        }
        Method::DynamicPoint(p) => {
            for off in samples.chunks_exact(d) {
                sample_offset(s, off);
                avoidance::dynamic_point::add_force(&s.r, &s.u, p.lambda, p.beta, &mut s.phi);
            }
        }
        Method::SteeringAngle(p) => {
            for off in samples.chunks_exact(d) {
                sample_offset(s, off);
                avoidance::steering_angle::add_force(&s.r, &s.v, &s.u, p.gamma, p.beta, &mut s.phi);
            }
        }
        Method::StaticVolumetric(p) => {
            let c = s.eval.eval(shape, rotation, &s.center, &s.x).max(C_FLOOR);
            avoidance::static_volumetric::add_force(c, &s.eval.grad, p.a, p.eta, &mut s.phi);
        }
        Method::DynamicVolumetric(p) => {
            // The potential is invariant under rotation: work in the obstacle's frame, where the Hessian of a
            // per-axis superquadric is diagonal, and rotate the term back.
            let c = s.eval.eval_local(shape, rotation, &s.center, &s.x).max(C_FLOOR);
            rotate_transposed(rotation, &s.u, &mut s.u_local);
            let e = &s.eval;
            if avoidance::dynamic_volumetric::is_active(&e.gy, &s.u_local) {
                mat_vec(&e.hy, &s.u_local, &mut s.hu);
                mat_vec(&e.hy, &e.gy, &mut s.hg);
                s.phi_local.fill(0.0);
                avoidance::dynamic_volumetric::add_force(
                    c,
                    &e.gy,
                    &s.hu,
                    &s.hg,
                    &s.u_local,
                    p,
                    &mut s.phi_local,
                );
                rotate(rotation, &s.phi_local, &mut s.hu);
                s.phi.iter_mut().zip(&s.hu).for_each(|(a, b)| *a += b);
            }
        }
    }
}

fn kernel_of(method: &Method) -> Option<DynamicVolumetricKernel> {
    match method {
        Method::DynamicVolumetric(p) => Some(DynamicVolumetricKernel::new(p)),
        _ => None,
    }
}

/// `r = x - (centre + offset)`.
fn sample_offset(s: &mut Scratch, off: &[f64]) {
    for i in 0..s.x.len() {
        s.r[i] = s.x[i] - s.center[i] - off[i];
    }
}

fn gather(src: &[f64], dims: &[usize], out: &mut [f64]) {
    for (o, &d) in out.iter_mut().zip(dims) {
        *o = src[d];
    }
}

/// Checks the robots against the DMP dimension; returns the dimension each robot moves in.
fn validate_agents(agents: &[Agent], dim: usize, explicit: bool) -> Result<usize> {
    let sub_dim = agents[0].dims.len();
    let mut owner = vec![None; dim];
    for (i, a) in agents.iter().enumerate() {
        if a.dims.is_empty() {
            return Err(
                InvalidInput::new(format!("robots[{i}].dims"), "must name at least one dimension").into()
            );
        }
        if a.dims.len() != sub_dim {
            return Err(InvalidInput::new(
                format!("robots[{i}].dims"),
                format!(
                    "every robot must own the same number of dimensions ({sub_dim}), found {}",
                    a.dims.len()
                ),
            )
            .into());
        }
        for &d in &a.dims {
            if d >= dim {
                return Err(InvalidInput::new(
                    format!("robots[{i}].dims"),
                    format!("dimension {d} does not exist (the DMP has {dim})"),
                )
                .into());
            }
            if let Some(j) = owner[d].replace(i) {
                return Err(InvalidInput::new(
                    format!("robots[{i}].dims"),
                    format!("dimension {d} is already owned by robots[{j}]"),
                )
                .into());
            }
        }
        if let Some(f) = &a.footprint
            && f.dim() != sub_dim
        {
            return Err(InvalidInput::new(
                format!("robots[{i}].footprint.semi_axes"),
                format!("must have {sub_dim} entries (one per owned dimension), found {}", f.dim()),
            )
            .into());
        }
        if explicit && a.id.is_empty() {
            return Err(InvalidInput::new(format!("robots[{i}].id"), "must not be empty").into());
        }
    }
    Ok(sub_dim)
}
