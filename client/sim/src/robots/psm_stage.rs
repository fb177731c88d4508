//! A stage of the da Vinci peg transfer (`super::psm`): the two arms' legs, and how they run.
//!
//! # Shared phase or pose runs
//! The server runs a pose primitive alone: a group joins position primitives only (`dmp::execution::join_group`:
//! "a pose primitive (with orientation) runs alone, not in a group"). So a stage runs either
//! - on one phase (`ExecuteGroup`, one 6-D DMP), the arms avoiding each other's jaws, each holding its orientation;
//! - or as two pose runs (`Execute`, one per arm, streamed at once), the jaws turning on each arm's own phase. The arms then do not avoid each other: only stages where they stay apart
//!   without the robot term run so (the report still measures the jaws' clearance to each other at equal times).

use dmp_client::grpc::DmpClient;
use dmp_proto::obstacle_json::JsonObstacle;
use dmp_proto::v1;

use super::pose::{about, mul, outline_samples, rows};
use super::psm::{
    DT, HOME1, HOME2, JAW_HALF_LENGTH, JAW_RADIUS, PSM1, PSM2, RETREAT1, RING, RING_RADIUS, STANDBY2,
    STATIC_A, TAU, footprint, handover, place, planned, world,
};
use super::report::{Figure, position, write_figure};
use super::robot::Executed;
use super::world::{Solid, robot_body};
use super::{Method, SimOptions, avoidance, execute, execute_group, pacing, server_robot};
use crate::error::SimError;
use dmp_plot::PoseTrace;

/// The jaws' orientations (module documentation): at home, upright (the frame of the cell).
pub const Q_HOME: [f64; 4] = [0.0, 0.0, 0.0, 1.0];

/// PSM1's jaws grasping the ring: tilted [`GRASP_TILT_DEG`] about `y` and rolled [`GRASP_ROLL_DEG`] about their
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
pub const GRASP_TILT_DEG: f64 = 20.0;
/// Roll of PSM1's jaws at the ring, degrees.
pub const GRASP_ROLL_DEG: f64 = 45.0;

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
    pub robot: &'static str,
    /// Nominal start (of the demonstration).
    pub start: Vec<f64>,
    pub goal: Vec<f64>,
    /// Nominal start and goal orientation of the jaws (of a pose stage's demonstration).
    pub start_q: [f64; 4],
    pub goal_q: [f64; 4],
    pub carrying: bool,
}

#[derive(Debug, Clone)]
pub(super) struct Stage {
    pub key: &'static str,
    pub title: &'static str,
    pub legs: [Leg; 2],
    pub obstacles: Vec<JsonObstacle>,
    /// On one phase (a group of position primitives); else two pose runs (module documentation).
    pub shared_phase: bool,
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
        let obstacles = if free { Method::None } else { Method::Static { a: STATIC_A, eta: 2.0 } };
        let robots = if avoid == Avoid::Everything && self.shared_phase {
            super::psm::robot_method()
        } else {
            Method::None
        };
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
    pub async fn execute(
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
        (Solid::Ball { radius: RING_RADIUS }, vec![RING_RADIUS; 3], vec![1.0; 3])
    } else {
        (
            Solid::CylinderZ { radius: JAW_RADIUS, half_height: JAW_HALF_LENGTH },
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
