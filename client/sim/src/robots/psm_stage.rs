//! The stages of the da Vinci peg transfer (`super::psm`, which has the cell and the geometry): the two arms' legs
//! of each stage, how a stage runs, and the transfer run stage after stage, measured and drawn.
//!
//! # Shared phase or pose runs
//! The server runs a pose primitive alone: a group joins position primitives only (`dmp::execution::join_group`:
//! "a pose primitive (with orientation) runs alone, not in a group"). So a stage runs either
//! - on one phase (`ExecuteGroup`, one 6-D DMP), the arms avoiding each other's jaws, each holding its orientation;
//! - or as two pose runs (`Execute`, one per arm, streamed at once), the jaws turning on each arm's own phase.
//!   The arms then do not avoid each other: only stages where they stay apart without the robot term run so (the
//!   report still measures the jaws' clearance to each other at equal times).

use dmp::Method;
use dmp::avoidance::StaticVolumetric;
use dmp::{Agent, Shape, Superquadric, Trajectory};
use dmp_client::grpc::DmpClient;
use dmp_plot::PoseTrace;
use dmp_proto::obstacle_json::JsonObstacle;
use dmp_proto::v1;

use super::clearance::{closest_approach, distance, side_by_side};
use super::demonstration::min_jerk_turn;
use super::pose::{about, add_pose, mul, outline_samples, rows};
use super::profile::put_profile;
use super::psm::{
    CENTRE, DT, HOME1, HOME2, JAW_HALF_LENGTH, JAW_RADIUS, PEG_HALF_HEIGHT, PROFILE, PSM1, PSM2, RETREAT1,
    RING, RING_RADIUS, ROBOT_IDS, STANDBY2, STATIC_A, TARGET, TAU, demonstration, footprint,
    footprint_semi_axes, handover, jaws, place, planned, robot_method, world,
};
use super::report::{CONTACT_M, Figure, Other, RobotReport, SimReport, measure, position, write_figure};
use super::robot::Executed;
use super::world::{SolidShape, robot_body};
use super::{SimOptions, avoidance, execute, execute_group, learn_parameters, pacing, server_robot, within};
use crate::error::SimError;

/// The jaws' orientations (module documentation): at home, upright (the frame of the cell).
pub const Q_HOME: [f64; 4] = [0.0, 0.0, 0.0, 1.0];

/// PSM1's jaws grasping the ring: tilted `GRASP_TILT_DEG` about `y` and rolled `GRASP_ROLL_DEG` about their
/// axis, across the ring's rim.
pub fn q_grasp() -> [f64; 4] {
    mul(
        &about([0.0, 1.0, 0.0], GRASP_TILT_DEG.to_radians()),
        &about([0.0, 0.0, 1.0], GRASP_ROLL_DEG.to_radians()),
    )
}

/// Each arm's jaws at the handover: upright, rolled to open towards the other arm (PSM1 a quarter turn one way,
/// PSM2 the other).
pub fn q_handover(arm: usize) -> [f64; 4] {
    let sign = if arm == 0 { 1.0 } else { -1.0 };
    about([0.0, 0.0, 1.0], sign * std::f64::consts::FRAC_PI_2)
}

/// PSM2's jaws at its standby point: half way rolled towards the handover.
pub fn q_standby() -> [f64; 4] {
    about([0.0, 0.0, 1.0], -std::f64::consts::FRAC_PI_4)
}

/// Tilt of PSM1's jaws at the ring, degrees.
pub(crate) const GRASP_TILT_DEG: f64 = 20.0;
/// Roll of PSM1's jaws at the ring, degrees.
pub(crate) const GRASP_ROLL_DEG: f64 = 45.0;

pub(super) fn stages() -> Vec<Stage> {
    let leg = |robot,
               (start, start_q): (&[f64], [f64; 4]),
               (goal, goal_q): (Vec<f64>, [f64; 4]),
               carrying| Leg { robot, start: start.to_vec(), goal, start_q, goal_q, carrying };
    vec![
        Stage {
            key: "move-to-ring",
            title: "da Vinci: move to ring (PSM1), PSM2 to standby, turning the jaws",
            legs: [
                leg(PSM1, (&HOME1, Q_HOME), (RING.to_vec(), q_grasp()), false),
                leg(PSM2, (&HOME2, Q_HOME), (STANDBY2.to_vec(), q_standby()), false),
            ],
            obstacles: planned(JAW_HALF_LENGTH, None),
            shared_phase: false,
        },
        Stage {
            key: "transfer",
            title: "da Vinci: transfer between PSMs, the jaws turning to the handover",
            legs: [
                leg(PSM1, (&RING, q_grasp()), (handover(0), q_handover(0)), true),
                leg(PSM2, (&STANDBY2, q_standby()), (handover(1), q_handover(1)), false),
            ],
            obstacles: planned(RING_RADIUS, None),
            shared_phase: false,
        },
        Stage {
            key: "move-to-peg",
            title: "da Vinci: move to peg (PSM2), PSM1 retreats",
            legs: [
                leg(PSM1, (&handover(0), q_handover(0)), (RETREAT1.to_vec(), q_handover(0)), false),
                leg(PSM2, (&handover(1), q_handover(1)), (place(), q_handover(1)), true),
            ],
            obstacles: planned(RING_RADIUS, Some("target-peg")),
            shared_phase: true,
        },
    ]
}

/// One arm's part of a stage.
#[derive(Debug, Clone)]
pub(super) struct Leg {
    pub(crate) robot: &'static str,
    /// Nominal start (of the demonstration).
    pub(crate) start: Vec<f64>,
    pub(crate) goal: Vec<f64>,
    /// Nominal start and goal orientation of the jaws (of a pose stage's demonstration).
    pub(crate) start_q: [f64; 4],
    pub(crate) goal_q: [f64; 4],
    pub(crate) carrying: bool,
}

#[derive(Debug, Clone)]
pub(super) struct Stage {
    pub(crate) key: &'static str,
    pub(crate) title: &'static str,
    pub(crate) legs: [Leg; 2],
    pub(crate) obstacles: Vec<JsonObstacle>,
    /// On one phase (a group of position primitives); else two pose runs (module documentation).
    pub(crate) shared_phase: bool,
}

/// What a run of a stage avoids.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Avoid {
    /// Nothing (the free plan).
    Nothing,
    /// The obstacles, not the other arm.
    Obstacles,
    /// The obstacles and the other arm (on a shared phase; two pose runs avoid the obstacles only).
    Everything,
}

impl Stage {
    /// One arm's motion, starting at `start` turned by `start_q` (a pose stage's).
    fn motion(&self, leg: &Leg, start: &[f64], start_q: [f64; 4], avoid: Avoid) -> v1::MotionSpec {
        let free = avoid == Avoid::Nothing;
        let obstacles = if free {
            Method::None
        } else {
            Method::StaticVolumetric(StaticVolumetric { a: STATIC_A, eta: 2.0 })
        };
        let robots =
            if avoid == Avoid::Everything && self.shared_phase { robot_method() } else { Method::None };
        let (start_orientation, goal_orientation) = if self.shared_phase {
            (Vec::new(), Vec::new())
        } else {
            (start_q.to_vec(), leg.goal_q.to_vec())
        };
        v1::MotionSpec {
            robot_id: server_robot(leg.robot),
            primitive: self.key.into(),
            start: start.to_vec(),
            goal: leg.goal.clone(),
            start_orientation,
            goal_orientation,
            avoidance: Some(avoidance(obstacles)),
            robot_avoidance: Some(avoidance(robots)),
            footprint: Some(footprint()),
            extra_obstacles: if free {
                Vec::new()
            } else {
                self.obstacles.iter().map(JsonObstacle::to_proto).collect()
            },
            // The scene is known in advance: it travels with the request.
            ignore_scene: true,
            ..Default::default()
        }
    }

    /// Runs the stage, the arms starting at `starts` turned by `orientations`.
    pub(crate) async fn execute(
        &self,
        client: &DmpClient,
        options: &SimOptions,
        (starts, orientations): (&[Vec<f64>; 2], [[f64; 4]; 2]),
        avoid: Avoid,
    ) -> Result<[Executed; 2], SimError> {
        let realtime = options.realtime;
        if self.shared_phase {
            let members = (0..2)
                .map(|i| v1::GroupMember {
                    motion: Some(self.motion(&self.legs[i], &starts[i], orientations[i], avoid)),
                })
                .collect();
            let request = v1::ExecuteGroupRequest {
                members,
                dt: DT,
                segment_s: 0.01,
                pacing: pacing(realtime),
                max_duration_s: 4.0 * TAU,
                ..Default::default()
            };
            let mut runs = execute_group(client, request, realtime).await?;
            // A group streams positions only: each arm holds the orientation it had.
            for (run, q) in runs.iter_mut().zip(orientations) {
                run.orientations = Some(held(run.traj.len(), q));
            }
            return <[Executed; 2]>::try_from(runs)
                .map_err(|_| SimError::protocol("a group of two answered for another count".into()));
        }
        // Both arms at once, as a cell runs them (on the simulated clock each from the stage's start anyway).
        let request = |i: usize| v1::ExecuteRequest {
            motion: Some(self.motion(&self.legs[i], &starts[i], orientations[i], avoid)),
            dt: DT,
            segment_s: 0.01,
            pacing: pacing(realtime),
            max_duration_s: 4.0 * TAU,
            ..Default::default()
        };
        let robot = |i: usize| options.robot_client(client, &server_robot(self.legs[i].robot));
        let (c0, c1) = (robot(0)?, robot(1)?);
        let (a, b) = tokio::try_join!(
            execute(&c0, request(0), realtime, |_| {}),
            execute(&c1, request(1), realtime, |_| {})
        )?;
        Ok([a, b])
    }
}

/// `q` held for `rows` rows, at rest.
fn held(rows: usize, q: [f64; 4]) -> dmp::execution::OrientationPoints {
    dmp::execution::OrientationPoints {
        q: q.repeat(rows),
        omega: vec![0.0; 3 * rows],
        omega_dot: vec![0.0; 3 * rows],
    }
}

/// The figure of arm `i` of a stage run as two pose runs: its path, its jaws (or the ring) outlined along it and
/// their rotation from the start; returns its file name.
pub(super) fn arm_figure(
    options: &SimOptions,
    stage: &Stage,
    i: usize,
    (run, free): (&Executed, &Executed),
    engine: &[dmp::Obstacle],
) -> Result<String, SimError> {
    let leg = &stage.legs[i];
    let (solid, semi, exponents) = if leg.carrying {
        (SolidShape::Ball { radius: RING_RADIUS }, vec![RING_RADIUS; 3], vec![1.0; 3])
    } else {
        (
            SolidShape::CylinderZ { radius: JAW_RADIUS, half_height: JAW_HALF_LENGTH },
            vec![JAW_RADIUS, JAW_RADIUS, JAW_HALF_LENGTH],
            vec![1.0, 1.0, 4.0],
        )
    };
    let body = robot_body(leg.robot, solid);
    let q = |e: &Executed| e.orientations.as_ref().map(|o| rows(&o.q)).unwrap_or_default();
    let (adapted_q, free_q) = (q(run), q(free));
    let surface = outline_samples(&semi, &exponents)?;
    let start = position(&run.traj, 0).to_vec();
    let world = world();
    let title = format!("{} ({})", stage.title, leg.robot);
    let fig =
        Figure {
            title: &title,
            line: (&start, &leg.goal),
            free: &free.traj,
            adapted: &run.traj,
            obstacles: engine,
            robots: &[],
            time: 0.0,
            world: &world,
            seen: &[],
            body: Some(&body),
            method: "static_volumetric",
            events: &[],
            pose: (adapted_q.len() == run.traj.len() && free_q.len() == free.traj.len()).then_some(
                PoseTrace { orientations: &adapted_q, free_orientations: &free_q, tool_surface: &surface },
            ),
        };
    let name = format!("{}-{}.svg", stage.key, leg.robot);
    write_figure(&options.out, &name, &fig)?;
    Ok(name)
}

/// Row `k` of an execution (`usize::MAX`: the last row).
fn row_of(exec: &Executed, k: usize) -> Result<Vec<f64>, SimError> {
    if exec.traj.is_empty() {
        return Err(SimError::protocol(format!("{} streamed no setpoint", exec.id)));
    }
    Ok(position(&exec.traj, k.min(exec.traj.len() - 1)).to_vec())
}

/// The last orientation of an execution (`held` if it has none).
fn last_orientation(exec: &Executed, held: [f64; 4]) -> [f64; 4] {
    exec.orientations
        .as_ref()
        .and_then(|o| o.q.rchunks_exact(4).next())
        .map_or(held, |q| [q[0], q[1], q[2], q[3]])
}

/// How long a stage took: until both arms stopped.
fn stage_duration(runs: &[Executed; 2]) -> f64 {
    runs.iter().map(|r| r.traj.t.last().copied().unwrap_or(0.0)).fold(0.0, f64::max)
}

/// The last position of an execution.
fn last(exec: &Executed) -> Result<Vec<f64>, SimError> {
    row_of(exec, usize::MAX)
}

/// Largest distance between the executed and the free path at the same times.
fn deviation(adapted: &Trajectory, free: &Trajectory) -> f64 {
    (0..adapted.len().min(free.len()))
        .map(|k| distance(position(adapted, k), position(free, k)))
        .fold(0.0, f64::max)
}

/// Measures one arm: its body (or the ring) against the true shapes, its jaws against the other arm's jaws.
fn measure_leg(stage: &Stage, i: usize, runs: &[Executed; 2]) -> RobotReport {
    let leg = &stage.legs[i];
    let other = &stage.legs[1 - i];
    let body = if leg.carrying {
        robot_body(leg.robot, SolidShape::Ball { radius: RING_RADIUS })
    } else {
        jaws(leg.robot)
    };
    let mut r = measure(&runs[i], DT, &leg.goal, Some(&PROFILE), &body, &world(), &[]);
    if !stage.shared_phase {
        let what =
            if leg.carrying { "the ring (a ball of its outer radius)" } else { "the jaws (a cylinder)" };
        add_pose(&mut r, &runs[i], leg.goal_q, Some(&PROFILE), what);
    }
    let other_jaws = jaws(other.robot);
    let theirs = runs[1 - i].orientations.as_ref().map(|o| o.q.as_slice());
    let with_arm =
        Other { id: other.robot, traj: &runs[1 - i].traj, body: &other_jaws, orientations: theirs };
    let arms = measure(&runs[i], DT, &leg.goal, None, &jaws(leg.robot), &[], &[with_arm]);
    for (id, d) in arms.min_clearance_m {
        if d <= CONTACT_M {
            r.collisions.push(id.clone());
        }
        r.min_clearance_m.insert(id, d);
    }
    r
}

/// Runs the three stages and records them.
pub(crate) async fn run(client: &DmpClient, options: &SimOptions) -> Result<SimReport, SimError> {
    let stages = stages();
    for stage in &stages {
        for leg in &stage.legs {
            let (t, rows) = demonstration(&leg.start, &leg.goal);
            // A pose stage's jaws turn on the demonstration's minimum-jerk profile; a shared phase's hold.
            let q = if stage.shared_phase {
                Vec::new()
            } else {
                min_jerk_turn(&leg.start_q, &leg.goal_q, TAU, 0.01)
            };
            let parameters = learn_parameters(3050.0);
            within(
                "learn",
                client.learn_pose(&server_robot(leg.robot), stage.key, &t, &rows, &q, parameters),
            )
            .await??;
        }
    }
    for robot in ROBOT_IDS {
        put_profile(client, &server_robot(robot), &PROFILE, Some(-1.0)).await?;
    }
    let mut report = SimReport::new("psm", options.realtime);
    report.notes.push(
        "geometry, stages and gains: see client/sim/src/robots/psm.rs (two PSMs on one 6-D DMP; pegs planned as \
         superquadrics (1, 1, 2) with the static potential, the arms avoid each other's jaws with the dynamic \
         potential)"
            .into(),
    );
    report.notes.push(
        "orientation: the jaws turn in move-to-ring and transfer (PSM1 tilts and rolls them to grasp the ring, both \
         arms roll them to open towards each other at the handover), as two pose runs each: the server runs a pose \
         primitive alone, not in a group; move-to-peg, where the arms must avoid each other, runs on one phase, \
         the jaws holding their handover orientation (see client/sim/src/robots/psm_stage.rs)"
            .into(),
    );
    let mut starts = [HOME1.to_vec(), HOME2.to_vec()];
    let mut orientations = [Q_HOME, Q_HOME];
    let mut clock = 0.0;
    for stage in &stages {
        let from = (&starts, orientations);
        // The runs are independent (each its own phase), one after the other: they move the same robots, and a
        // robot executes one stream at a time.
        let runs = stage.execute(client, options, from, Avoid::Everything).await?;
        let without_robots = if stage.shared_phase {
            stage.execute(client, options, from, Avoid::Obstacles).await?
        } else {
            // Two pose runs never avoid each other.
            runs.clone()
        };
        let free = stage.execute(client, options, from, Avoid::Nothing).await?;
        record(options, stage, &runs, &free, clock, &mut report)?;
        // How close the jaws came without the robot term.
        for i in 0..2 {
            let (arm, other) = (stage.legs[i].robot, stage.legs[1 - i].robot);
            let d = measure_leg(stage, i, &without_robots).min_clearance_m.get(other).copied();
            let k = format!("{arm}/{}/no_robot_term_min_clearance_m/{other}", stage.key);
            report.metrics.insert(k, d.unwrap_or(f64::INFINITY));
        }
        starts = [last(&runs[0])?, last(&runs[1])?];
        orientations =
            [last_orientation(&runs[0], orientations[0]), last_orientation(&runs[1], orientations[1])];
        clock += stage_duration(&runs);
    }
    Ok(report)
}

fn record(
    options: &SimOptions,
    stage: &Stage,
    runs: &[Executed; 2],
    free: &[Executed; 2],
    clock: f64,
    report: &mut SimReport,
) -> Result<(), SimError> {
    let key = stage.key;
    let starts = [row_of(&runs[0], 0)?, row_of(&runs[1], 0)?];
    for i in 0..2 {
        let leg = &stage.legs[i];
        report.add(&format!("{}/{key}", leg.robot), measure_leg(stage, i, runs));
        // What the free plan would have touched.
        for (id, d) in measure_leg(stage, i, free).min_clearance_m {
            report.metrics.insert(format!("{}/{key}/free_min_clearance_m/{id}", leg.robot), d);
        }
        report.metrics.insert(
            format!("{}/{key}/max_deviation_from_free_m", leg.robot),
            deviation(&runs[i].traj, &free[i].traj),
        );
    }
    let (t_close, d_close) = closest_approach(&[&runs[0].traj, &runs[1].traj]);
    report.metrics.insert(format!("{key}/closest_approach_m"), d_close);
    report.metrics.insert(format!("{key}/closest_approach_time_s"), clock + t_close);
    report.metrics.insert(format!("{key}/start_time_s"), clock);
    match key {
        "transfer" => {
            report.metrics.insert("handover/time_s".into(), clock + stage_duration(runs));
            for (i, arm) in [PSM1, PSM2].iter().enumerate() {
                let d = distance(&last(&runs[i])?, &CENTRE);
                report.metrics.insert(format!("handover/{arm}_to_centre_m"), d);
            }
        }
        "move-to-peg" => {
            let ring = last(&runs[1])?;
            let offset = distance(&ring[..2], &TARGET);
            report.metrics.insert("ring/offset_from_peg_axis_m".into(), offset);
            report.metrics.insert("ring/height_above_peg_top_m".into(), ring[2] - 2.0 * PEG_HALF_HEIGHT);
            report
                .metrics
                .insert("ring/released_at_s".into(), clock + runs[1].traj.t.last().copied().unwrap_or(0.0));
        }
        _ => {}
    }
    // The figure: both arms' paths in 3-D projections, with the pegs as the planner sees them.
    let adapted = side_by_side(&[&runs[0].traj, &runs[1].traj]);
    let free6 = side_by_side(&[&free[0].traj, &free[1].traj]);
    let engine: Vec<dmp::Obstacle> = stage
        .obstacles
        .iter()
        .map(JsonObstacle::to_engine)
        .collect::<Result<_, _>>()
        .map_err(|e| SimError::Plot(e.to_string()))?;
    let shape = Superquadric::ellipsoid(footprint_semi_axes().to_vec())
        .map(Shape::Superquadric)
        .map_err(|e| SimError::Plot(e.to_string()))?;
    let agents: Vec<Agent> = stage
        .legs
        .iter()
        .enumerate()
        .map(|(i, leg)| Agent {
            id: leg.robot.into(),
            dims: (3 * i..3 * i + 3).collect(),
            footprint: Some(shape.clone()),
        })
        .collect();
    let start = starts.concat();
    let goal: Vec<f64> = stage.legs.iter().flat_map(|l| l.goal.clone()).collect();
    let name = format!("{key}.svg");
    let fig = Figure {
        title: stage.title,
        line: (&start, &goal),
        free: &free6,
        adapted: &adapted,
        obstacles: &engine,
        robots: &agents,
        time: t_close,
        world: &world(),
        seen: &[],
        body: None,
        // The pegs and the board with the static potential, the other arm's jaws with the dynamic one.
        method: "static_volumetric",
        events: &[],
        pose: None,
    };
    write_figure(&options.out, &name, &fig)?;
    report.plots.push(name);
    // Where the jaws turn on their own phases, each arm's figure shows them turning.
    if !stage.shared_phase {
        for i in 0..2 {
            report.plots.push(arm_figure(options, stage, i, (&runs[i], &free[i]), &engine)?);
        }
    }
    Ok(())
}
