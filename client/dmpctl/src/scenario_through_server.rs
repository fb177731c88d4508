//! `dmpctl scenario run FILE --server URL --out DIR`: the offline experiment, computed by the server.
//!
//! The scenario is validated and learned locally too ([`dmp::scenario::prepare`]): the local [`Prepared`] gives the
//! metrics their scene, and its primitive is compared with the server's. Then:
//!
//! - **one robot** (no `robots`): the demonstration is learned under robot `scenario.<name>` ([`robot_ids`]),
//!   name = the scenario's name sanitized; two `Plan`s with the scenario's `dt`, `duration`, start, goal and `tau`: one with
//!   the scenario's obstacles as `extra_obstacles` (`ignore_scene = true`, so the cell's own scene is left out) and
//!   its avoidance, one with method `none` and no obstacles (the obstacle-free twin). A plan is the engine's
//!   rollout, so the metrics are the offline run's.
//! - **several robots**: each robot's dimensions of the demonstration are learned as its own primitive (robot
//!   `scenario.<name>.<id>`), and the two runs are `ExecuteGroup` streams paced as fast as read, one member per robot,
//!   `max_duration_s` = the scenario's duration; the members' setpoints are put back together in the scenario's
//!   dimension order. Learning is per dimension, so each robot's primitive is the rows of the whole one, and the
//!   server's group run is the engine's joint rollout: the metrics are the offline run's
//!   (`tests/tests/server/matches_the_engine.rs` checks it on `youbots-three-dynamic.json`).
//!   Rows past the scenario's duration (streams end on segment boundaries) are cut; a shorter run is cut to the
//!   shorter length, and a note says so.
//!
//! Every motion asks for no limits and no safety distance (`NO_LIMITS`, a negative `margin`): a scenario has
//! neither, and the server's default profile would otherwise hold the run back from the paper's trajectory.
//!
//! The robots are the run's own (`scenario.` is no real robot's prefix): their primitives are deleted when the run
//! ends, also after an error, unless `keep` (`--keep`).
//!
//! Contacts are not needed by the metrics; stalls are: they are detected again here, with the engine's detector on
//! the server's trajectory, exactly as the rollout does.

use std::path::Path;
use std::time::Instant;

use dmp::scenario::{Prepared, Scenario};
use dmp::stall::{StallConfig, StallDetector};
use dmp::{Avoidance, Rollout, Trajectory};
use dmp_client::ClientError;
use dmp_client::grpc::{DmpClient, record_primitive};
use dmp_client::setpoints::Setpoints;
use dmp_proto::avoidance::avoidance_to_proto;
use dmp_proto::learning::learn_parameters_to_proto;
use dmp_proto::limits::NO_LIMITS;
use dmp_proto::obstacle_json::obstacle_to_proto;
use dmp_proto::shape::footprint_to_proto;
use dmp_proto::v1;
use tokio_stream::StreamExt;

use crate::error::DmpctlError;
use crate::offline::{RunSummary, write_outputs};
use crate::scenario_file::load_scenario;

/// The namespace of the robots of `scenario run --server`: `scenario.<name>` (`.` is allowed in robot ids).
pub(crate) const ROBOT_PREFIX: &str = "scenario.";

/// The robot a single-robot scenario named `name` is stored under: `scenario.<name>`, sanitized.
pub fn scenario_robot(name: &str) -> String {
    sanitize(&format!("{ROBOT_PREFIX}{}", sanitize(name)))
}

/// The robots the run of `s` stores primitives for: `scenario.<name>` for one robot, `scenario.<name>.<id>` for
/// each robot of a group.
pub fn robot_ids(s: &Scenario) -> Vec<String> {
    if s.robots.is_empty() {
        vec![scenario_robot(&s.name)]
    } else {
        s.robots.iter().map(|r| sanitize(&format!("{}.{}", scenario_robot(&s.name), r.id))).collect()
    }
}

/// Deletes every primitive of `robots` (the run's own); returns how many versions were deleted.
pub(crate) async fn clean_up(client: &DmpClient, robots: &[String]) -> Result<u64, ClientError> {
    let mut deleted = 0;
    for robot in robots {
        deleted += client.delete_robot_primitives(robot).await?;
    }
    Ok(deleted)
}

/// A robot id or primitive name the server accepts: 1 to 128 characters of `[A-Za-z0-9_.-]`, others replaced by
/// `_`; empty gives `scenario`.
pub(crate) fn sanitize(name: &str) -> String {
    let s: String = name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.') { c } else { '_' })
        .take(128)
        .collect();
    if s.is_empty() { "scenario".into() } else { s }
}

/// Runs the scenario at `path` through the server and writes the three files of the offline run into `out`.
/// The primitives it stored are deleted at the end (also after an error) unless `keep`.
pub async fn run_scenario_through_server(
    client: &DmpClient,
    path: &Path,
    out: &Path,
    keep: bool,
) -> Result<RunSummary, DmpctlError> {
    let started = Instant::now();
    let scenario = load_scenario(path)?;
    let p = dmp::scenario::prepare(&scenario)
        .map_err(|source| DmpctlError::Invalid { path: path.to_path_buf(), source })?;
    if p.pose.is_some() {
        return Err(DmpctlError::Invalid {
            path: path.to_path_buf(),
            source: dmp::InvalidInput::new(
                "demonstration.q",
                "a pose scenario (orientations, a held tool) runs offline only: run it without --server",
            )
            .into(),
        });
    }
    let mut notes = Vec::new();
    let ran = if scenario.robots.is_empty() {
        plan_one_robot(client, &scenario, &p, &mut notes).await
    } else {
        run_robot_group(client, &scenario, &p, &mut notes).await
    };
    if !keep && let Err(e) = clean_up(client, &robot_ids(&scenario)).await {
        notes.push(format!(
            "clean-up: the primitives of {} may be left: {e}",
            robot_ids(&scenario).join(", ")
        ));
    }
    let (free, adapted) = ran?;
    let stalls = detect_stalls(&p, &adapted)?;
    let free =
        Rollout { trajectory: free, contacts: vec![], stalls: vec![], orientations: Default::default() };
    let adapted = Rollout { trajectory: adapted, contacts: vec![], stalls, orientations: Default::default() };
    let mut metrics = dmp::metrics::metrics(&p, &free, &adapted)
        .map_err(|source| DmpctlError::Invalid { path: path.to_path_buf(), source })?;
    metrics.compute_seconds = started.elapsed().as_secs_f64();
    write_outputs(&p, &free, &adapted, &metrics, out)?;
    Ok(RunSummary { metrics, notes })
}

/// The stalls the rollout would report: one detector per robot, fed every row.
fn detect_stalls(p: &Prepared, traj: &Trajectory) -> Result<Vec<(usize, dmp::stall::Stall)>, ClientError> {
    let field = p.field().map_err(|e| ClientError::Protocol(e.to_string()))?;
    let mut detectors: Vec<StallDetector> =
        field.agents().iter().map(|a| StallDetector::new(StallConfig::default(), a.dims.clone())).collect();
    let mut stalls = Vec::new();
    for k in 0..traj.len() {
        for (i, d) in detectors.iter_mut().enumerate() {
            if let Some(s) = d.update(traj.t[k], traj.position(k), traj.velocity(k), &p.motion.goal) {
                stalls.push((i, s));
            }
        }
    }
    Ok(stalls)
}

/// Notes a primitive of the server that differs from the engine's.
fn compare_primitive(
    record: &v1::PrimitiveRecord,
    expected: &dmp::Primitive,
    what: &str,
    notes: &mut Vec<String>,
) -> Result<(), ClientError> {
    let got = record_primitive(record)?;
    if &got != expected {
        let dw = got
            .weights
            .iter()
            .flatten()
            .zip(expected.weights.iter().flatten())
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        notes.push(format!(
            "the server's primitive for {what} differs from the engine's (largest weight difference {dw:e})"
        ));
    }
    Ok(())
}

/// Checks a plan's trajectory against the scenario's shape.
fn check_rows(traj: &Trajectory, p: &Prepared, what: &str) -> Result<(), ClientError> {
    if traj.dim() != p.primitive.dim || traj.len() != p.steps + 1 {
        return Err(ClientError::Protocol(format!(
            "the {what} plan has {} rows of dimension {}; the scenario needs {} rows (duration / dt + 1) of dimension {}",
            traj.len(),
            traj.dim(),
            p.steps + 1,
            p.primitive.dim
        )));
    }
    Ok(())
}

fn plan_trajectory(r: v1::PlanResponse) -> Result<Trajectory, ClientError> {
    let seg = r.trajectory.ok_or_else(|| ClientError::Protocol("the plan has no trajectory".into()))?;
    let mut s = Setpoints::new();
    s.push(&seg)?;
    Ok(s.into_trajectory())
}

/// One robot: learns its primitive, then plans the adapted and the obstacle-free run.
async fn plan_one_robot(
    client: &DmpClient,
    s: &Scenario,
    p: &Prepared,
    notes: &mut Vec<String>,
) -> Result<(Trajectory, Trajectory), ClientError> {
    let name = sanitize(&s.name);
    let robot = scenario_robot(&s.name);
    let record = client
        .learn(&robot, &name, &s.demonstration.t, &s.demonstration.x, learn_parameters_to_proto(&s.dmp))
        .await?;
    compare_primitive(&record, &p.primitive, &format!("{robot}/{name}"), notes)?;
    let motion = |avoidance: &Avoidance, obstacles: Vec<v1::Obstacle>| v1::MotionSpec {
        robot_id: robot.clone(),
        primitive: name.clone(),
        version: record.version,
        start: p.motion.start.clone(),
        goal: p.motion.goal.clone(),
        tau: p.motion.tau,
        avoidance: Some(avoidance_to_proto(avoidance, s.point_samples)),
        extra_obstacles: obstacles,
        ignore_scene: true,
        limits: Some(NO_LIMITS),
        margin: -1.0,
        ..Default::default()
    };
    let obstacles: Vec<v1::Obstacle> = s.obstacles.iter().map(|o| obstacle_to_proto(o, 0.0, 0.0)).collect();
    let plan = |m: v1::MotionSpec| v1::PlanRequest { motion: Some(m), dt: p.dt, duration: p.duration };
    let (adapted, free) = tokio::join!(
        client.plan(plan(motion(&s.avoidance, obstacles))),
        client.plan(plan(motion(&Avoidance::NONE, Vec::new()))),
    );
    let (adapted, free) = (plan_trajectory(adapted?)?, plan_trajectory(free?)?);
    check_rows(&adapted, p, "adapted")?;
    check_rows(&free, p, "obstacle-free")?;
    Ok((free, adapted))
}

/// The entries of a per-dimension parameter (one value, or one per dimension) for the dimensions `dims`.
fn entries_for_dims(v: Vec<f64>, dims: &[usize]) -> Vec<f64> {
    if v.len() <= 1 { v } else { dims.iter().map(|&i| v[i]).collect() }
}

/// Several robots: learns each robot's primitive, then streams the adapted and the obstacle-free group runs.
async fn run_robot_group(
    client: &DmpClient,
    s: &Scenario,
    p: &Prepared,
    notes: &mut Vec<String>,
) -> Result<(Trajectory, Trajectory), ClientError> {
    let name = sanitize(&s.name);
    let whole = learn_parameters_to_proto(&s.dmp);
    let mut members = Vec::with_capacity(s.robots.len());
    for (r, robot) in s.robots.iter().zip(robot_ids(s)) {
        let x: Vec<Vec<f64>> =
            s.demonstration.x.iter().map(|row| r.dims.iter().map(|&i| row[i]).collect()).collect();
        let params = v1::LearnParameters {
            k: entries_for_dims(whole.k.clone(), &r.dims),
            d: entries_for_dims(whole.d.clone(), &r.dims),
            ..whole.clone()
        };
        let record = client.learn(&robot, &name, &s.demonstration.t, &x, params).await?;
        let mut expected = p.primitive.clone();
        let sub = |v: &[f64]| r.dims.iter().map(|&i| v[i]).collect::<Vec<f64>>();
        expected.dim = r.dims.len();
        expected.k = sub(&p.primitive.k);
        expected.d = sub(&p.primitive.d);
        expected.start = sub(&p.primitive.start);
        expected.goal = sub(&p.primitive.goal);
        expected.weights = r.dims.iter().map(|&i| p.primitive.weights[i].clone()).collect();
        compare_primitive(&record, &expected, &format!("{robot}/{name}"), notes)?;
        members.push((robot, record.version, r));
    }
    let obstacles: Vec<v1::Obstacle> = s.obstacles.iter().map(|o| obstacle_to_proto(o, 0.0, 0.0)).collect();
    let request = |free: bool| v1::ExecuteGroupRequest {
        members: members
            .iter()
            .map(|(robot, version, r)| {
                let sub = |v: &[f64]| r.dims.iter().map(|&i| v[i]).collect::<Vec<f64>>();
                let none = Avoidance::NONE;
                let (avoidance, robot_avoidance) =
                    if free { (none, none) } else { (s.avoidance, s.robot_avoidance.unwrap_or(none)) };
                v1::GroupMember {
                    motion: Some(v1::MotionSpec {
                        robot_id: robot.clone(),
                        primitive: name.clone(),
                        version: *version,
                        start: sub(&p.motion.start),
                        goal: sub(&p.motion.goal),
                        tau: p.motion.tau,
                        avoidance: Some(avoidance_to_proto(&avoidance, s.point_samples)),
                        robot_avoidance: Some(avoidance_to_proto(&robot_avoidance, s.point_samples)),
                        footprint: Some(footprint_to_proto(&r.footprint)),
                        extra_obstacles: if free { Vec::new() } else { obstacles.clone() },
                        ignore_scene: true,
                        cell: String::new(),
                        goal_tolerance: None,
                        limits: Some(NO_LIMITS),
                        margin: -1.0,
                        ..Default::default()
                    }),
                }
            })
            .collect(),
        dt: p.dt,
        segment_s: 0.0,
        pacing: v1::Pacing::AsFastAsRead as i32,
        lookahead_s: 0.0,
        max_duration_s: p.duration,
        tau: p.motion.tau,
        // RK4 at the output rate, as offline (the server's default interpolates between coarser steps).
        integration_step_s: p.dt,
        integration_tolerance: 0.0,
        take_over: false,
    };
    let dims: Vec<&[usize]> = s.robots.iter().map(|r| r.dims.as_slice()).collect();
    // One after the other: the two runs move the same robots, and a robot executes one stream at a time.
    let mut adapted = execute_group_joined(client, request(false), &dims, p).await?;
    let mut free = execute_group_joined(client, request(true), &dims, p).await?;
    // Streams stop on segment boundaries: rows past the scenario's duration are cut, so that the metrics are over
    // the same span as offline (`final_goal_distance` at T). A shorter stream is noted.
    let rows = adapted.len().min(free.len()).min(p.steps + 1);
    if rows == 0 {
        return Err(ClientError::Protocol("a group stream carried no points".into()));
    }
    if rows < p.steps + 1 {
        notes.push(format!(
            "the group streams have {} (adapted) and {} (obstacle-free) rows, the offline run {}: metrics are over \
             the first {rows}",
            adapted.len(),
            free.len(),
            p.steps + 1
        ));
    }
    truncate(&mut adapted, rows);
    truncate(&mut free, rows);
    Ok((free, adapted))
}

fn truncate(t: &mut Trajectory, rows: usize) {
    let d = t.dim();
    t.t.truncate(rows);
    t.x.truncate(rows * d);
    t.xd.truncate(rows * d);
    t.xdd.truncate(rows * d);
}

/// Reads a group stream to its end and puts the members' setpoints back into the scenario's dimensions.
async fn execute_group_joined(
    client: &DmpClient,
    request: v1::ExecuteGroupRequest,
    dims: &[&[usize]],
    p: &Prepared,
) -> Result<Trajectory, ClientError> {
    let mut stream = client.execute_group(request).await?;
    let mut members: Vec<Setpoints> = dims.iter().map(|_| Setpoints::new()).collect();
    while let Some(step) = stream.next().await {
        let step = step?;
        if step.segments.len() != members.len() {
            return Err(ClientError::Protocol(format!(
                "group step {} has {} segments for {} members",
                step.sequence,
                step.segments.len(),
                members.len()
            )));
        }
        for (m, seg) in members.iter_mut().zip(&step.segments) {
            m.push(seg)?;
        }
    }
    let parts: Vec<Trajectory> = members.into_iter().map(Setpoints::into_trajectory).collect();
    let rows = parts.iter().map(Trajectory::len).min().unwrap_or(0);
    let d = p.primitive.dim;
    let mut out = Trajectory::with_capacity(d, rows);
    let (mut x, mut xd, mut xdd) = (vec![0.0; d], vec![0.0; d], vec![0.0; d]);
    for k in 0..rows {
        for (part, owned) in parts.iter().zip(dims) {
            if part.dim() != owned.len() {
                return Err(ClientError::Protocol(format!(
                    "a member's segments have dimension {}, its robot owns {}",
                    part.dim(),
                    owned.len()
                )));
            }
            for (j, &i) in owned.iter().enumerate() {
                x[i] = part.position(k)[j];
                xd[i] = part.velocity(k)[j];
                xdd[i] = part.acceleration(k)[j];
            }
        }
        // Segment times are `start_time + j dt`; on the scenario's grid `k dt` they are written as the offline run
        // writes them.
        let (t, grid) = (parts[0].t[k], k as f64 * p.dt);
        out.push(if (t - grid).abs() <= 1e-6 * p.dt { grid } else { t }, &x, &xd, &xdd);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_sanitized_for_the_server() {
        assert_eq!(sanitize("paper one/obstacle: dynamic"), "paper_one_obstacle__dynamic");
        assert_eq!(sanitize("youbots-three_dynamic.v1"), "youbots-three_dynamic.v1");
        assert_eq!(sanitize(""), "scenario");
        assert_eq!(sanitize(&"x".repeat(300)).len(), 128);
    }

    #[test]
    fn stalls_are_found_again_on_a_trajectory() {
        let file = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../scenarios/paper-one-obstacle/dynamic_volumetric.json");
        let p = dmp::scenario::prepare(&load_scenario(&file).unwrap()).unwrap();
        let out = dmp::scenario::run(&p).unwrap();
        let stalls = detect_stalls(&p, &out.adapted.trajectory).unwrap();
        assert_eq!(stalls, out.adapted.stalls);
        // Rebuilding the rollout from its trajectory alone gives the offline metrics.
        let again = dmp::metrics::metrics(
            &p,
            &Rollout {
                trajectory: out.free.trajectory.clone(),
                contacts: vec![],
                stalls: vec![],
                orientations: Default::default(),
            },
            &Rollout {
                trajectory: out.adapted.trajectory.clone(),
                contacts: vec![],
                stalls,
                orientations: Default::default(),
            },
        )
        .unwrap();
        assert_eq!(again, out.metrics);
    }
}
