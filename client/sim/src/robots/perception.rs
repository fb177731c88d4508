//! One youBot down a corridor while a perception node finds an unknown box (the paper's section on the real youBot).
//!
//! # Set-up (metres, the youBot's start frame)
//! - The youBot (a 0.58 x 0.38 rectangle, its centre controlled, heading fixed along `x`) drives from `(0, 0)` to
//!   `(2, 0)` on a 2-D primitive learned by the server from a synthetic straight drive at a constant
//!   [`CRUISE_SPEED`] between smooth ramps of [`RAMP_S`] ([`super::demonstration::ramped_line`]), so
//!   `tau =` [`TAU`]; `K =` [`STIFFNESS`], `D = 2 sqrt(K)`, `alpha = 4`; integrated and streamed at 1 kHz ([`DT`]).
//!   - Not null weights: a null-weight DMP is fastest at its start, so within the youBot's 0.8 m/s it would need
//!     `tau` near 8 s for 2 m, most of it spent creeping to the goal (and the test runs in real time).
//!   - Not the paper's `K = 3050`: the box is straight ahead, so the robot goes round it for a long while with the
//!     DMP pulling it back towards the line, i.e. against the box. The dynamic potential only repels motion
//!     towards the box, so it holds the robot off with a sliding motion right on the isopotential, where its
//!     term is so stiff that any fixed step chatters (period-2 velocity oscillations of tens of m/s^2, at 10 ms
//!     and at 1 ms alike). A softer DMP (`sqrt(K) / tau` about 4.6 rad/s) pulls back less and the run is smooth;
//!     much softer (`K = 300`), the static potentials shift its rest point by more than the server's 1 mm arrival
//!     tolerance.
//! - Walls, known in advance (sent with the request): boxes of half-extents `(1.6, 0.05)` centred at `(1, +-1.2)`,
//!   planned as rounded boxes of exponent 2 through their corners, inflated by [`ROBOT_RADIUS`].
//! - The box, unknown: 0.2 x 0.2. A simulated perception node samples its outline (1 cm apart, a deterministic
//!   jitter of up to 3 mm), fits the PCA-aligned bounding ellipse ([`super::ellipse_fit`]) and publishes it over
//!   Zenoh only, with exponents `n = m = 1` and the robot's size [`ROBOT_RADIUS`] as margin.
//! - Two runs, each with the static (`A = 10, eta = 2`) and the dynamic (`lambda = 1, beta = 2, eta = 2`)
//!   potential (two robots streaming at once, seeing the same publications):
//!   `added`: the box at `(1, 0.08)` is published just after the start and stays;
//!   `temporary`: a box at `(1.6, 0.08)` is published when the robot has covered 30 % of the way, and deleted
//!   (Zenoh delete) at 42 % (`x` near 0.84, still short of the box's inflated ellipse, which starts near
//!   `x = 1.1`); the path then returns to the straight line. The times follow from the demonstration's profile
//!   ([`unknown_boxes`]).
//!
//! The server paces these runs in real time whatever the options say: a perception event happens at a time of the
//! run, and as fast as read the server would have computed the segments around that time before the event.
//!
//! The true world: the walls and the box as rectangles (the box only while it exists), the robot as its rectangle;
//! distances with parry (2-D shapes as prisms, `super::world`).

use std::time::Duration;

use dmp::Method;
use dmp::avoidance::{DynamicVolumetric, StaticVolumetric};
use dmp::scenario::ObstacleSpec;
use dmp_client::grpc::DmpClient;
use dmp_client::zenoh_pub::ObstaclePublisher;
use dmp_proto::obstacle_json::JsonObstacle;
use dmp_proto::v1;
use tokio::sync::watch;

use super::demonstration::{ramped_duration, ramped_line, ramped_time_at};
use super::ellipse_fit::Ellipse;
use super::profile::put_profile;
use super::report::{Figure, SimReport, measure, position, write_figure};
use super::robot::Executed;
use super::world::{Body, SolidShape, robot_body};
use super::{SimOptions, avoidance, execute, free_plan, server_robot, within};
use crate::error::SimError;

/// Control period (and integration step): 1 kHz.
pub(crate) const DT: f64 = 1e-3;
/// The limit profile of the youBot base, in each robot's record. The record's safety distance is none: the box and
/// the walls carry the robot's size as their own margin, and the static potential on shapes inflated further (the
/// field keeps off twice the margin) would hold the robot's rest point more than the 1 mm arrival tolerance short of
/// its goal.
pub(crate) const PROFILE: dmp::Limits = dmp::Limits::YOUBOT_BASE;
/// Cruise speed of the drive, m/s (the youBot's top speed is 0.8 m/s).
pub(crate) const CRUISE_SPEED: f64 = 0.4;
/// Duration of each ramp of the demonstration, seconds.
pub(crate) const RAMP_S: f64 = 0.8;
/// Stiffness `K` of the primitive (module documentation: why not the paper's 3050).
pub(crate) const STIFFNESS: f64 = 700.0;
/// Time scale of the 2 m drive (the demonstration's duration), seconds.
pub(crate) const TAU: f64 = ramped_duration(2.0, CRUISE_SPEED, RAMP_S);
/// Radius of the circle around the youBot's rectangle.
pub(crate) const ROBOT_RADIUS: f64 = 0.35;
/// Half-sides of the youBot.
pub(crate) const ROBOT_HALF: [f64; 2] = [0.29, 0.19];
/// The robots of this simulation, one per potential (the server knows them as [`server_robot`] of these).
pub(crate) const ROBOT_IDS: [&str; 2] = ["youbot-static", "youbot-dynamic"];
/// Half-side of the unknown box.
pub(crate) const BOX_HALF: f64 = 0.1;

const START: [f64; 2] = [0.0, 0.0];
const GOAL: [f64; 2] = [2.0, 0.0];
const WALL_HALF: [f64; 2] = [1.6, 0.05];
const WALLS: [(&str, [f64; 2]); 2] = [("wall-left", [1.0, 1.2]), ("wall-right", [1.0, -1.2])];

/// One perception scenario: the unknown box, and when the perception node publishes and deletes it.
#[derive(Debug, Clone, Copy)]
pub(crate) struct UnknownBox {
    /// Its name in the report.
    pub(crate) key: &'static str,
    /// The obstacle's id.
    pub(crate) id: &'static str,
    /// Centre of the box.
    pub(crate) center: [f64; 2],
    /// Published at this time of the run, seconds.
    pub(crate) add_at: f64,
    /// Deleted at this time of the run, if ever.
    pub(crate) remove_at: Option<f64>,
}

/// The two scenarios: the box that stays is published 0.05 s after the start; the temporary one when the robot
/// has covered 30 % of its way, and deleted at 42 % (times of the demonstration).
pub(crate) fn unknown_boxes() -> [UnknownBox; 2] {
    let at = |way| ramped_time_at(way, TAU, RAMP_S);
    [
        UnknownBox { key: "added", id: "box", center: [1.0, 0.08], add_at: 0.05, remove_at: None },
        UnknownBox {
            key: "temporary",
            id: "box-temporary",
            center: [1.6, 0.08],
            add_at: at(0.3),
            remove_at: Some(at(0.42)),
        },
    ]
}

fn walls(margin: f64) -> Vec<JsonObstacle> {
    let k = 2f64.powf(0.25);
    WALLS
        .iter()
        .map(|(id, c)| JsonObstacle {
            spec: ObstacleSpec {
                id: (*id).into(),
                center: c.to_vec(),
                semi_axes: WALL_HALF.iter().map(|h| h * k).collect(),
                exponents: Some(vec![2.0, 2.0]),
                rotation: None,
                velocity: None,
                nested: None,
            },
            margin,
            ttl_s: 0.0,
        })
        .collect()
}

/// What the depth camera sees of the box: its outline, 1 cm apart, with a deterministic jitter of up to 3 mm.
pub(crate) fn point_cloud(center: [f64; 2], half: f64) -> Vec<[f64; 2]> {
    let mut seed: u64 = 0x2545_f491_4f6c_dd1d;
    let mut jitter = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        ((seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 0.006
    };
    let n = (2.0 * half / 0.01).round() as usize;
    let mut pts = Vec::new();
    for i in 0..=n {
        let f = -half + 2.0 * half * i as f64 / n as f64;
        for (x, y) in [(f, -half), (f, half), (-half, f), (half, f)] {
            pts.push([center[0] + x + jitter(), center[1] + y + jitter()]);
        }
    }
    pts
}

/// The obstacle the perception node publishes for a cloud.
pub(crate) fn fitted_obstacle(id: &str, cloud: &[[f64; 2]]) -> Result<JsonObstacle, SimError> {
    let e = Ellipse::fit(cloud).ok_or_else(|| SimError::argument("cloud", "no finite ellipse fits"))?;
    Ok(JsonObstacle {
        spec: ObstacleSpec {
            id: id.into(),
            center: e.center.to_vec(),
            semi_axes: e.semi_axes.to_vec(),
            exponents: Some(vec![1.0, 1.0]),
            rotation: Some(e.rotation()),
            velocity: None,
            nested: None,
        },
        margin: ROBOT_RADIUS,
        ttl_s: 0.0,
    })
}

/// The two runs of an event move at once in the same perceived scene, one robot per potential (a robot executes one
/// stream at a time); they do not avoid each other (they are the same robot, twice).
fn spec(robot: &str, method: Method) -> v1::MotionSpec {
    v1::MotionSpec {
        robot_id: robot.into(),
        primitive: "corridor".into(),
        avoidance: Some(avoidance(method)),
        robot_avoidance: Some(avoidance(Method::None)),
        extra_obstacles: walls(ROBOT_RADIUS).iter().map(JsonObstacle::to_proto).collect(),
        ..Default::default()
    }
}

fn request(robot: &str, method: Method) -> v1::ExecuteRequest {
    v1::ExecuteRequest {
        motion: Some(spec(robot, method)),
        dt: DT,
        segment_s: 0.05,
        pacing: v1::Pacing::Realtime as i32,
        // The stream ends at the goal; room beyond 3 tau for a run slowed down around the box on a busy host.
        max_duration_s: 4.0 * TAU,
        ..Default::default()
    }
}

/// Sleeps until `origin + t` on the wall clock (Unix seconds).
async fn sleep_until_run_time(origin: f64, t: f64) {
    let now =
        std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0.0, |d| d.as_secs_f64());
    let wait = origin + t - now;
    if wait > 0.0 {
        tokio::time::sleep(Duration::from_secs_f64(wait)).await;
    }
}

/// The perception node of one run: waits for the run's origin, then publishes and removes the box at its times.
async fn perceive(
    publisher: &ObstaclePublisher,
    unknown: UnknownBox,
    mut origin: watch::Receiver<Option<f64>>,
) -> Result<(), SimError> {
    let origin = within("the run's start", origin.wait_for(Option::is_some))
        .await?
        .map_err(|_| SimError::closed("the robot".into()))?
        .unwrap_or_default();
    sleep_until_run_time(origin, unknown.add_at).await;
    let obstacle = fitted_obstacle(unknown.id, &point_cloud(unknown.center, BOX_HALF))?;
    within("zenoh put", publisher.put_obstacle(&obstacle)).await??;
    if let Some(t) = unknown.remove_at {
        sleep_until_run_time(origin, t).await;
        within("zenoh delete", publisher.delete(unknown.id)).await??;
    }
    Ok(())
}

/// Waits until the server's scene has no obstacle `id`.
async fn wait_absent(client: &DmpClient, id: &str) -> Result<(), SimError> {
    within("scene cleared", async {
        loop {
            let snap = client.list_obstacles().await?;
            if snap.obstacles.iter().all(|o| o.id != id) {
                return Ok::<_, SimError>(());
            }
            tokio::time::sleep(Duration::from_millis(5)).await;
        }
    })
    .await?
}

/// The perception node's Zenoh session: from `--zenoh-config` when given (a secured cell's perception config),
/// else a peer connecting to the server's endpoints.
async fn open_publisher(options: &SimOptions) -> Result<ObstaclePublisher, dmp_client::ClientError> {
    match &options.zenoh_config {
        Some(file) => ObstaclePublisher::open_from_file(&options.cell, file, &options.zenoh_connect).await,
        None => ObstaclePublisher::open(&options.cell, &options.zenoh_connect, &[]).await,
    }
}

/// Runs both scenarios, each with both potentials.
pub(crate) async fn run(client: &DmpClient, options: &SimOptions) -> Result<SimReport, SimError> {
    let (t, rows) = ramped_line(&START, &GOAL, TAU, RAMP_S, DT);
    let parameters = super::learn_parameters(STIFFNESS);
    let robots = ROBOT_IDS.map(server_robot);
    for robot in &robots {
        within("learn", client.learn(robot, "corridor", &t, &rows, parameters.clone())).await??;
        put_profile(client, robot, &PROFILE, Some(-1.0)).await?;
    }
    let as_robot = [options.robot_client(client, &robots[0])?, options.robot_client(client, &robots[1])?];
    let mut publisher = within("zenoh open", open_publisher(options)).await??;
    // A server that restarts or reconnects mid-run asks for the boxes it missed.
    within("zenoh queryable", publisher.serve_latest()).await??;
    within("zenoh subscriber", publisher.wait_for_subscriber(super::STEP_TIMEOUT)).await??;
    let mut report = SimReport::new("youbot-perception", true);
    report.notes.push("set-up: see client/sim/src/robots/perception.rs; always paced in real time".into());
    let methods = [
        ("static", Method::StaticVolumetric(StaticVolumetric { a: 10.0, eta: 2.0 })),
        ("dynamic", Method::DynamicVolumetric(DynamicVolumetric { lambda: 1.0, beta: 2.0, eta: 2.0 })),
    ];
    let result = async {
        for unknown in unknown_boxes() {
            let (tx, rx) = watch::channel(None);
            let robots = async {
                let (tx0, tx1) = (tx.clone(), tx.clone());
                let set = move |tx: &watch::Sender<Option<f64>>, o: Option<f64>| {
                    if o.is_some() && tx.borrow().is_none() {
                        tx.send_replace(o);
                    }
                };
                tokio::join!(
                    execute(&as_robot[0], request(&robots[0], methods[0].1), true, |c| set(
                        &tx0,
                        c.origin_unix()
                    )),
                    execute(&as_robot[1], request(&robots[1], methods[1].1), true, |c| set(
                        &tx1,
                        c.origin_unix()
                    )),
                )
            };
            let (robots, seen) = tokio::join!(robots, perceive(&publisher, unknown, rx));
            seen?;
            let runs: [(&str, Executed); 2] = [(methods[0].0, robots.0?), (methods[1].0, robots.1?)];
            // Leave the scene as it was.
            within("zenoh delete", publisher.delete(unknown.id)).await??;
            wait_absent(client, unknown.id).await?;
            for ((name, exec), (_, method)) in runs.iter().zip(methods) {
                record(client, options, unknown, name, method, exec, &mut report).await?;
            }
        }
        Ok::<_, SimError>(())
    }
    .await;
    within("zenoh close", publisher.close()).await??;
    result?;
    Ok(report)
}

async fn record(
    client: &DmpClient,
    options: &SimOptions,
    unknown: UnknownBox,
    name: &str,
    method: Method,
    exec: &Executed,
    report: &mut SimReport,
) -> Result<(), SimError> {
    let mut world: Vec<Body> = WALLS
        .iter()
        .map(|(id, c)| Body::new(*id, SolidShape::rectangle(WALL_HALF[0], WALL_HALF[1]), c))
        .collect();
    let until = unknown.remove_at.unwrap_or(f64::INFINITY);
    world.push(
        Body::new(unknown.id, SolidShape::rectangle(BOX_HALF, BOX_HALF), &unknown.center)
            .during(unknown.add_at, until),
    );
    let body = robot_body("youbot", SolidShape::rectangle(ROBOT_HALF[0], ROBOT_HALF[1]));
    let key = format!("youbot/{}-{name}", unknown.key);
    report.add(&key, measure(exec, DT, &GOAL, Some(&PROFILE), &body, &world, &[]));
    // How far the path left the straight line `y = 0`: over the whole run, and once past the box's centre.
    let traj = &exec.traj;
    let ys = (0..traj.len()).map(|k| (position(traj, k)[0], position(traj, k)[1].abs()));
    let (all, past) = ys.fold((0.0f64, 0.0f64), |(all, past), (x, y)| {
        (all.max(y), if x >= unknown.center[0] { past.max(y) } else { past })
    });
    report.metrics.insert(format!("{key}/max_abs_y_m"), all);
    report.metrics.insert(format!("{key}/max_abs_y_past_box_m"), past);
    let free = free_plan(client, &spec(&server_robot(ROBOT_IDS[0]), method), DT).await?;
    let mut planned: Vec<dmp::Obstacle> = walls(ROBOT_RADIUS)
        .iter()
        .map(JsonObstacle::to_engine)
        .collect::<Result<_, _>>()
        .map_err(|e| SimError::Plot(e.to_string()))?;
    // What the perception node saw and published (for the time the events say).
    let cloud = point_cloud(unknown.center, BOX_HALF);
    let o = fitted_obstacle(unknown.id, &cloud)?;
    planned.push(o.to_engine().map_err(|e| SimError::Plot(e.to_string()))?);
    let mut seen = dmp_plot::Solid::new(
        format!("{} (points seen)", unknown.id),
        dmp_plot::SolidShape::Points(cloud.iter().map(|p| p.to_vec()).collect()),
        vec![0.0, 0.0],
    );
    (seen.from, seen.until) = (unknown.add_at, unknown.remove_at.unwrap_or(f64::INFINITY));
    let title = format!("youBot: {} obstacle, {name} potential", unknown.key);
    let file = format!("{}-{name}.svg", unknown.key);
    let mut events = vec![dmp_plot::Event::new(unknown.add_at, format!("{} appears", unknown.id))];
    if let Some(t) = unknown.remove_at {
        events.push(dmp_plot::Event::new(t, format!("{} removed", unknown.id)));
    }
    let fig = Figure {
        title: &title,
        line: (&START, &GOAL),
        free: &free,
        adapted: &exec.traj,
        obstacles: &planned,
        robots: &[],
        time: 0.0,
        world: &world,
        seen: std::slice::from_ref(&seen),
        body: Some(&body),
        method: method.name(),
        events: &events,
        pose: None,
    };
    write_figure(&options.out, &file, &fig)?;
    report.plots.push(file);
    Ok(())
}
