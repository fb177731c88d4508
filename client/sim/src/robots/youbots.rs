//! Three youBots in one room, on one shared phase (the paper's simulated youBots: "Experiments with robots in
//! simulation"), each a moving obstacle for the others, around walls and cubes known in advance.
//!
//! # The cell (metres, `z` up, the room's corner at the origin)
//! - A room of 6 x 4: four walls 0.1 thick just outside `[0, 6] x [0, 4]` (long thin boxes).
//! - Three cubes on the floor: `cube-a` (0.4 m) at `(2.03, 1.35)`, `cube-b` (0.3 m) at `(3.36, 2.95)`, `cube-c`
//!   (0.5 m) at `(4.32, 1.47)`.
//! - Three youBots (0.58 x 0.38 rectangles, [`ROBOT_HALF`], their centre controlled, heading fixed along `x`: the
//!   base is omnidirectional and the paper does not control the orientation):
//!   `youbot1` from `(1.06, 1.56)` to `(4.34, 2.44)` and `youbot2` from `(4.26, 2.75)` to `(0.98, 1.87)`, two
//!   oncoming robots on lanes 0.32 m apart (15 degrees to the walls); `youbot3` from `(5.20, 0.90)` to
//!   `(4.30, 3.30)`, across `youbot1`'s lane behind it.
//!
//! On their straight lines `youbot1` and `youbot2` collide head-on in the middle of the room (their rectangles
//! overlap by 6 cm, their footprints by much more), and every robot clips a cube: `youbot1` the corner of `cube-a`,
//! `youbot2` of `cube-b`, `youbot3` of `cube-c`, each between 20 and 35 % of its way (2 to 4 cm into the true
//! shape). The design avoids what makes the dynamic potential chatter: it only repels motion *toward* an obstacle,
//! so a robot that the DMP keeps pressing against an obstacle for long (driving along a cube's face, or two robots
//! crossing at right angles, slowly) slides onto the isopotential, where the term becomes too stiff for any fixed
//! step. Oncoming robots pass each other fast, and clipping a corner at an angle is brief.
//!
//! # The planner's view
//! - Walls and cubes: rounded boxes (superquadrics of exponents `(2, 2)`) through the corners of the obstacle
//!   inflated by the robot's size: half-sides `h + ROBOT_HALF + OBSTACLE_MARGIN`, semi-axes those times `2^(1/4)`.
//!   With the heading fixed, the rectangle grown by the robot's half-sides is exactly the set of centres where the
//!   robot touches the obstacle (their Minkowski sum), so the robot's centre outside the rounded box means no
//!   contact; [`OBSTACLE_MARGIN`] keeps a few centimetres of air.
//! - Robots: each robot's footprint, what the others avoid, is the ellipse (exponents `(1, 1)`) of semi-axes
//!   `sqrt(2) (0.58, 0.38) + FOOTPRINT_MARGIN`, centred on it: the smallest ellipse of that shape around the
//!   rectangle of half-sides `(0.58, 0.38)` of centres where two youBots touch, plus [`FOOTPRINT_MARGIN`] (the
//!   paper takes the full size `(0.58, 0.38)` as semi-axes, which lets the corners touch).
//! - Robots avoid each other with the dynamic volumetric potential on the relative velocity ([`ROBOTS`]); the
//!   fixed obstacles with the static ([`STATIC`]) or the dynamic ([`DYNAMIC`]) volumetric potential.
//!
//! # Primitives (`K = 3050`, `D = 2 sqrt(K)`, `alpha = 4`, `N = 50`, integrated and streamed at 1 kHz)
//! - `line`: null weights (a straight line). Such a DMP is fastest at its start: `tau` is chosen so that the
//!   longest drive peaks at [`NULL_PEAK_SPEED`] without obstacles.
//! - `constant-speed`: learned by the server from a synthetic demonstration per robot, a straight line at constant
//!   speed between smooth ramps ([`ramped_line`](super::demonstration::ramped_line), [`RAMP_S`]), all three of
//!   the same duration so that they share `tau`; the longest drive cruises at [`CRUISE_SPEED`].
//!
//! The youBot's top speed is 0.8 m/s; the speeds are lower so that avoiding at speed stays within a plausible
//! acceleration (the path does not depend on `tau`: accelerations scale as `1 / tau^2`). The step is the paper's
//! 1 ms: at 10 ms the robot-robot term chatters when the oncoming robots pass.
//!
//! # Runs
//! Each primitive with each potential for the fixed obstacles (the paper's four figures), one ExecuteGroup each,
//! one after the other (a group's robots publish their states to the cell). Report keys: `youbot1/line-static` etc.
//!
//! # The true world
//! Walls and cubes as boxes, each robot as its rectangle; clearances to the obstacles and to the other robots at
//! the same time, with parry (2-D shapes as prisms, `super::world`).

use dmp::Method;
use dmp::avoidance::{DynamicVolumetric, StaticVolumetric};
use dmp::scenario::ObstacleSpec;
use dmp::{Agent, Integrator, Motion, NoPerturbation, Primitive, Shape, State, Superquadric, Trajectory};
use dmp_client::grpc::DmpClient;
use dmp_proto::obstacle_json::JsonObstacle;
use dmp_proto::v1;

use super::clearance::{closest_approach, measure_fast, side_by_side};
use super::demonstration::{ramped_duration, ramped_line};
use super::profile::put_profile;
use super::report::{Figure, Other, SimReport, write_figure};
use super::robot::Executed;
use super::world::{Body, SolidShape, robot_body};
use super::{SimOptions, avoidance, execute_group, free_plan, pacing, server_robot, within};
use crate::error::SimError;

/// Control period (and integration step): 1 kHz.
pub(crate) const DT: f64 = 1e-3;
/// Step of the obstacle-free plans (figures, and the clearances without avoidance): 100 Hz is plenty.
pub(crate) const FREE_DT: f64 = 0.01;
/// Half-sides of the youBot.
pub(crate) const ROBOT_HALF: [f64; 2] = [0.29, 0.19];
/// Air kept between a robot and a wall or cube, on top of the robot's size.
pub(crate) const OBSTACLE_MARGIN: f64 = 0.05;
/// Air kept between two robots, on top of the ellipse around the rectangle of contact.
pub(crate) const FOOTPRINT_MARGIN: f64 = 0.05;
/// Obstacle-free peak speed of the longest null-weight drive, m/s.
pub(crate) const NULL_PEAK_SPEED: f64 = 0.6;
/// Cruise speed of the longest constant-speed drive, m/s.
pub(crate) const CRUISE_SPEED: f64 = 0.4;
/// Duration of each ramp of the constant-speed demonstrations, seconds.
pub(crate) const RAMP_S: f64 = 1.0;
/// Static volumetric potential for the walls and cubes.
pub(crate) const STATIC: Method = Method::StaticVolumetric(StaticVolumetric { a: 9.0, eta: 0.8 });
/// Dynamic volumetric potential for the walls and cubes.
pub(crate) const DYNAMIC: Method =
    Method::DynamicVolumetric(DynamicVolumetric { lambda: 3.2, beta: 2.0, eta: 1.7 });
/// Dynamic volumetric potential between robots (on the relative velocity).
pub(crate) const ROBOTS: Method =
    Method::DynamicVolumetric(DynamicVolumetric { lambda: 20.0, beta: 2.0, eta: 1.0 });

const K: f64 = 3050.0;
const ALPHA: f64 = 4.0;
const N_BASIS: usize = 50;

/// A youBot's drive.
#[derive(Debug, Clone, Copy)]
struct Bot {
    id: &'static str,
    start: [f64; 2],
    goal: [f64; 2],
}

/// The limit profile of every youBot base, in its robot record.
pub(crate) const PROFILE: dmp::Limits = dmp::Limits::YOUBOT_BASE;

/// The robots of this simulation (the server knows them as [`server_robot`] of these).
pub(crate) const ROBOT_IDS: &[&str] = &["youbot1", "youbot2", "youbot3"];

const BOTS: [Bot; 3] = [
    Bot { id: ROBOT_IDS[0], start: [1.06, 1.56], goal: [4.34, 2.44] },
    Bot { id: ROBOT_IDS[1], start: [4.26, 2.75], goal: [0.98, 1.87] },
    Bot { id: ROBOT_IDS[2], start: [5.2, 0.9], goal: [4.3, 3.3] },
];

/// A box on the floor.
#[derive(Debug, Clone, Copy)]
struct Block {
    id: &'static str,
    center: [f64; 2],
    half: [f64; 2],
}

const BLOCKS: [Block; 7] = [
    Block { id: "wall-south", center: [3.0, -0.05], half: [3.1, 0.05] },
    Block { id: "wall-north", center: [3.0, 4.05], half: [3.1, 0.05] },
    Block { id: "wall-west", center: [-0.05, 2.0], half: [0.05, 2.0] },
    Block { id: "wall-east", center: [6.05, 2.0], half: [0.05, 2.0] },
    Block { id: "cube-a", center: [2.03, 1.35], half: [0.2, 0.2] },
    Block { id: "cube-b", center: [3.36, 2.95], half: [0.15, 0.15] },
    Block { id: "cube-c", center: [4.32, 1.47], half: [0.25, 0.25] },
];

/// The two primitives.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Line,
    ConstantSpeed,
}

impl Kind {
    fn name(self) -> &'static str {
        match self {
            Kind::Line => "line",
            Kind::ConstantSpeed => "constant-speed",
        }
    }
}

/// Peak speed of a null-weight DMP over a unit distance with `tau = 1` (so `peak * length / tau` in general).
fn null_weight_peak_speed() -> Result<f64, SimError> {
    let p = Primitive::straight_line(N_BASIS, ALPHA, vec![K], None, 1.0, vec![0.0], vec![1.0])
        .map_err(|e| SimError::argument("primitive", e.to_string()))?;
    let mut integrator = Integrator::new(&p).map_err(|e| SimError::argument("primitive", e.to_string()))?;
    let motion = Motion::of(&p);
    let mut state = State::at_rest(&p.start);
    let mut acc = [0.0];
    let mut peak = 0.0f64;
    while state.t < 1.0 {
        integrator.step(&motion, &mut NoPerturbation, &mut state, 1e-4, &mut acc);
        peak = peak.max(state.xd[0].abs());
    }
    Ok(peak)
}

fn length(b: &Bot) -> f64 {
    (b.goal[0] - b.start[0]).hypot(b.goal[1] - b.start[1])
}

fn longest() -> f64 {
    BOTS.iter().map(length).fold(0.0, f64::max)
}

/// The planner's obstacle of a block (module documentation).
fn planned(b: &Block) -> JsonObstacle {
    let k = 2f64.powf(0.25);
    JsonObstacle {
        spec: ObstacleSpec {
            id: b.id.into(),
            center: b.center.to_vec(),
            semi_axes: (0..2).map(|i| (b.half[i] + ROBOT_HALF[i] + OBSTACLE_MARGIN) * k).collect(),
            exponents: Some(vec![2.0, 2.0]),
            rotation: None,
            velocity: None,
            nested: None,
        },
        margin: 0.0,
        ttl_s: 0.0,
    }
}

fn footprint_axes() -> Vec<f64> {
    (0..2).map(|i| 2f64.sqrt() * 2.0 * ROBOT_HALF[i] + FOOTPRINT_MARGIN).collect()
}

fn footprint() -> v1::Superquadric {
    v1::Superquadric { semi_axes: footprint_axes(), exponents: vec![1.0, 1.0] }
}

/// The true shapes.
fn world() -> Vec<Body> {
    BLOCKS.iter().map(|b| Body::new(b.id, SolidShape::rectangle(b.half[0], b.half[1]), &b.center)).collect()
}

/// Stores both primitives of every robot; returns the `tau` of each.
async fn store_primitives(client: &DmpClient) -> Result<(f64, f64), SimError> {
    let tau_line = null_weight_peak_speed()? * longest() / NULL_PEAK_SPEED;
    let duration = ramped_duration(longest(), CRUISE_SPEED, RAMP_S);
    for b in &BOTS {
        let line = Primitive::straight_line(
            N_BASIS,
            ALPHA,
            vec![K; 2],
            None,
            tau_line,
            b.start.to_vec(),
            b.goal.to_vec(),
        )
        .map_err(|e| SimError::argument("primitive", e.to_string()))?;
        within("put", client.put_primitive(&server_robot(b.id), Kind::Line.name(), &line)).await??;
        let (t, rows) = ramped_line(&b.start, &b.goal, duration, RAMP_S, DT);
        let parameters =
            v1::LearnParameters { n_basis: N_BASIS as u32, k: vec![K], d: Vec::new(), alpha: ALPHA };
        within("learn", client.learn(&server_robot(b.id), Kind::ConstantSpeed.name(), &t, &rows, parameters))
            .await??;
        put_profile(client, &server_robot(b.id), &PROFILE, None).await?;
    }
    Ok((tau_line, duration))
}

fn spec(b: &Bot, kind: Kind, method: Method, tau: f64) -> v1::MotionSpec {
    v1::MotionSpec {
        robot_id: server_robot(b.id),
        primitive: kind.name().into(),
        start: b.start.to_vec(),
        goal: b.goal.to_vec(),
        tau,
        avoidance: Some(avoidance(method)),
        robot_avoidance: Some(avoidance(ROBOTS)),
        footprint: Some(footprint()),
        // The cell is known in advance: it travels with the request.
        extra_obstacles: BLOCKS.iter().map(|b| planned(b).to_proto()).collect(),
        ignore_scene: true,
        ..Default::default()
    }
}

/// One run: the three robots on one phase with `kind` and `method`.
async fn run_one(
    client: &DmpClient,
    options: &SimOptions,
    kind: Kind,
    (method_name, method): (&str, Method),
    tau: f64,
    report: &mut SimReport,
) -> Result<(), SimError> {
    let specs: Vec<v1::MotionSpec> = BOTS.iter().map(|b| spec(b, kind, method, tau)).collect();
    let request = v1::ExecuteGroupRequest {
        members: specs.iter().map(|m| v1::GroupMember { motion: Some(m.clone()) }).collect(),
        dt: DT,
        segment_s: 0.1,
        pacing: pacing(options.realtime),
        tau,
        ..Default::default()
    };
    let runs = execute_group(client, request, options.realtime).await?;
    let key = format!("{}-{method_name}", kind.name());
    let world = world();
    let bodies: Vec<Body> =
        BOTS.iter().map(|b| robot_body(b.id, SolidShape::rectangle(ROBOT_HALF[0], ROBOT_HALF[1]))).collect();
    for (i, (b, exec)) in BOTS.iter().zip(&runs).enumerate() {
        let others: Vec<Other<'_>> = (0..BOTS.len())
            .filter(|&j| j != i)
            .map(|j| Other { id: BOTS[j].id, traj: &runs[j].traj, body: &bodies[j], orientations: None })
            .collect();
        report.add(
            &format!("{}/{key}", b.id),
            measure_fast(exec, DT, &b.goal, Some(&PROFILE), &bodies[i], &world, &others),
        );
    }
    let executed: Vec<&Trajectory> = runs.iter().map(|r| &r.traj).collect();
    let (when, closest) = closest_approach(&executed);
    report.metrics.insert(format!("youbots/{key}/tau_s"), tau);
    report.metrics.insert(format!("youbots/{key}/closest_centres_m"), closest);
    report.metrics.insert(format!("youbots/{key}/closest_centres_time_s"), when);
    // The figure: the straight lines (dashed), the free and the adapted paths, the planner's obstacles, and each
    // robot's footprint (what the others avoid) when two robots are closest.
    let mut free = Vec::with_capacity(BOTS.len());
    for s in &specs {
        free.push(free_plan(client, s, FREE_DT).await?);
    }
    // Without avoidance (the free plans) every robot touches a cube and some robots touch each other.
    let mut free_robots = f64::INFINITY;
    for (i, b) in BOTS.iter().enumerate() {
        let as_run = |traj: &Trajectory| Executed {
            id: b.id.into(),
            traj: traj.clone(),
            orientations: None,
            late_setpoints: 0,
            late_splices: Vec::new(),
            segments: 0,
            final_status: v1::SegmentStatus::Unspecified,
        };
        let others: Vec<Other<'_>> = (0..BOTS.len())
            .filter(|&j| j != i)
            .map(|j| Other { id: BOTS[j].id, traj: &free[j], body: &bodies[j], orientations: None })
            .collect();
        let r = measure_fast(&as_run(&free[i]), FREE_DT, &b.goal, None, &bodies[i], &world, &others);
        let cubes = r.min_clearance_m.iter().filter(|(id, _)| id.starts_with("cube"));
        let cube = cubes.map(|(_, d)| *d).fold(f64::INFINITY, f64::min);
        report.metrics.insert(format!("youbots/{key}/free_min_cube_clearance_m/{}", b.id), cube);
        let robots = others.iter().map(|o| r.min_clearance_m[o.id]).fold(f64::INFINITY, f64::min);
        free_robots = free_robots.min(robots);
    }
    report.metrics.insert(format!("youbots/{key}/free_min_robot_clearance_m"), free_robots);
    let free = side_by_side(&free.iter().collect::<Vec<_>>());
    let adapted = side_by_side(&executed);
    let obstacles: Vec<dmp::Obstacle> = BLOCKS
        .iter()
        .map(|b| planned(b).to_engine())
        .collect::<Result<_, _>>()
        .map_err(|e| SimError::Plot(e.to_string()))?;
    let shape =
        Superquadric::new(footprint_axes(), vec![1.0, 1.0]).map_err(|e| SimError::Plot(e.to_string()))?;
    let agents: Vec<Agent> = BOTS
        .iter()
        .enumerate()
        .map(|(i, b)| Agent {
            id: b.id.into(),
            dims: vec![2 * i, 2 * i + 1],
            footprint: Some(Shape::Superquadric(shape.clone())),
        })
        .collect();
    let start: Vec<f64> = BOTS.iter().flat_map(|b| b.start).collect();
    let goal: Vec<f64> = BOTS.iter().flat_map(|b| b.goal).collect();
    let primitive = match kind {
        Kind::Line => "null weights",
        Kind::ConstantSpeed => "constant speed",
    };
    let title = format!("Three youBots: {primitive}, {method_name} potential");
    let file = format!("{key}.svg");
    let fig = Figure {
        title: &title,
        line: (&start, &goal),
        free: &free,
        adapted: &adapted,
        obstacles: &obstacles,
        robots: &agents,
        time: when,
        world: &world,
        seen: &[],
        body: None,
        method: method.name(),
        events: &[],
        pose: None,
    };
    write_figure(&options.out, &file, &fig)?;
    report.plots.push(file);
    Ok(())
}

/// Runs both primitives with both potentials, one group after the other.
pub(crate) async fn run(client: &DmpClient, options: &SimOptions) -> Result<SimReport, SimError> {
    let (tau_line, tau_constant) = store_primitives(client).await?;
    let mut report = SimReport::new("youbots", options.realtime);
    report.notes.push(format!(
        "set-up: see client/sim/src/robots/youbots.rs; tau {tau_line:.2} s (null weights, peak {NULL_PEAK_SPEED} m/s), \
         {tau_constant:.2} s (constant speed, cruise {CRUISE_SPEED} m/s)"
    ));
    for (kind, tau) in [(Kind::Line, tau_line), (Kind::ConstantSpeed, tau_constant)] {
        for method in [("static", STATIC), ("dynamic", DYNAMIC)] {
            run_one(client, options, kind, method, tau, &mut report).await?;
        }
    }
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn null_weight_speed() {
        let v = null_weight_peak_speed().unwrap();
        assert!((3.0..3.2).contains(&v), "{v}");
    }

    #[test]
    fn every_straight_line_hits_something() {
        // The inflated obstacles contain each robot's straight line somewhere (so avoiding is needed), and no
        // start or goal is near any of them.
        let mut hits = [false; 3];
        for (i, b) in BOTS.iter().enumerate() {
            for blk in &BLOCKS {
                let o = planned(blk).to_engine().unwrap();
                let c = |p: &[f64]| {
                    let y: Vec<f64> = (0..2).map(|k| p[k] - blk.center[k]).collect();
                    dmp::Isopotential::value(o.shape(), &y)
                };
                assert!(c(&b.start) > 2.0 && c(&b.goal) > 2.0, "{} near {}", b.id, blk.id);
                if blk.id.starts_with("wall") {
                    continue;
                }
                for k in 0..=100 {
                    let w = k as f64 / 100.0;
                    let p = [
                        b.start[0] + w * (b.goal[0] - b.start[0]),
                        b.start[1] + w * (b.goal[1] - b.start[1]),
                    ];
                    hits[i] |= c(&p) < 0.0;
                }
            }
        }
        assert_eq!(hits, [true; 3]);
    }
}
