//! Setting up the world of the load on the server: each cell's fixed obstacles and each robot's primitive (both
//! over gRPC, at most `SETUP_CONCURRENCY` calls at once), and the session start of each robot.

use std::sync::Arc;
use std::time::Duration;

use dmp_client::ClientError;
use dmp_client::grpc::DmpClient;
use dmp_proto::v1;
use tokio::sync::Semaphore;
use tokio::task::JoinSet;

use super::layout::{self, FIXED_OBSTACLES, PRIMITIVE, RobotPlan};
use super::{MAX_DURATION_SLACK_S, Params};
use crate::error::SimError;

/// Setup calls (puts of obstacles and primitives) in flight at once.
pub(crate) const SETUP_CONCURRENCY: usize = 32;
/// Longest wait for one setup call.
pub(crate) const SETUP_TIMEOUT: Duration = Duration::from_secs(30);

/// `f` under [`SETUP_TIMEOUT`], its error as a message.
async fn setup_call<T>(what: &str, f: impl Future<Output = Result<T, ClientError>>) -> Result<T, String> {
    match tokio::time::timeout(SETUP_TIMEOUT, f).await {
        Ok(Ok(v)) => Ok(v),
        Ok(Err(e)) => Err(format!("setup: {what}: {e}")),
        Err(_) => Err(format!("setup: {what}: no answer within {SETUP_TIMEOUT:?}")),
    }
}

/// Puts every cell's fixed obstacles (a failure fails the run: a cell without them is not the load asked for) and
/// every robot's primitive; returns, per robot, why it could not be set up (all failing fails the run).
pub(crate) async fn set_up(
    p: &Params,
    clients: &[DmpClient],
    cells: &[String],
    robots: &[RobotPlan],
) -> Result<Vec<Option<String>>, SimError> {
    let permits = Arc::new(Semaphore::new(SETUP_CONCURRENCY));
    let mut obstacles = JoinSet::new();
    for (c, cell) in cells.iter().enumerate() {
        for k in 0..FIXED_OBSTACLES {
            let client = clients[c % clients.len()].clone().with_cell(cell.clone());
            let (permits, dim) = (permits.clone(), p.args.dim);
            obstacles.spawn(async move {
                let _permit = permits.acquire_owned().await;
                let o = layout::fixed_obstacle(dim, k, 0.0);
                setup_call("putting the fixed obstacles", client.put_obstacle(o)).await
            });
        }
    }
    let mut primitives = JoinSet::new();
    for (i, r) in robots.iter().enumerate() {
        let client = clients[r.cell % clients.len()].clone();
        let (permits, r, tau, pose) = (permits.clone(), r.clone(), p.args.tau, p.args.pose);
        primitives.spawn(async move {
            let _permit = permits.acquire_owned().await;
            let primitive = if pose { super::pose::primitive(&r, tau) } else { layout::primitive(&r, tau) };
            let put = match primitive {
                Ok(primitive) => {
                    setup_call("putting the primitive", client.put_primitive(&r.id, PRIMITIVE, &primitive))
                        .await
                }
                Err(e) => Err(format!("setup: {e}")),
            };
            (i, put.err())
        });
    }
    // A cell without its obstacles cannot be measured as asked: the run fails.
    while let Some(done) = obstacles.join_next().await {
        match done {
            Ok(Ok(_)) => {}
            Ok(Err(e)) => return Err(SimError::protocol(e)),
            Err(e) => return Err(SimError::protocol(format!("setup task: {e}"))),
        }
    }
    let mut failed: Vec<Option<String>> = vec![Some("setup: the task failed".into()); robots.len()];
    while let Some(done) = primitives.join_next().await {
        if let Ok((i, error)) = done {
            failed[i] = error;
        }
    }
    if failed.iter().all(Option::is_some) {
        let e = failed[0].clone().unwrap_or_default();
        return Err(SimError::protocol(format!("no robot could be set up: {e}")));
    }
    Ok(failed)
}

/// The session start of a robot (a pose robot's with its orientations and limits, `--pose`).
pub fn start_request(p: &Params, r: &RobotPlan, cell: &str) -> v1::ExecuteRequest {
    let mut motion = v1::MotionSpec {
        robot_id: r.id.clone(),
        primitive: PRIMITIVE.into(),
        tau: p.args.tau,
        footprint: Some(layout::footprint(p.args.dim)),
        cell: cell.into(),
        ..Default::default()
    };
    if p.args.pose {
        super::pose::pose_start(&mut motion, r);
    }
    v1::ExecuteRequest {
        motion: Some(motion),
        dt: p.dt,
        segment_s: p.args.segment_s,
        pacing: v1::Pacing::Realtime as i32,
        lookahead_s: 0.0,
        max_duration_s: p.args.duration + MAX_DURATION_SLACK_S,
        integration_step_s: p.args.integration_step_s,
        integration_tolerance: p.args.integration_tolerance,
        take_over: false,
    }
}

/// Deletes each robot's primitive and each cell's fixed obstacles, at most [`SETUP_CONCURRENCY`] calls at once; a
/// robot or obstacle that is not there (never set up, or deleted already) is no error.
pub(crate) async fn clean_up(
    client: &DmpClient,
    cells: &[String],
    robots: &[RobotPlan],
) -> Result<(), SimError> {
    let permits = Arc::new(Semaphore::new(SETUP_CONCURRENCY));
    let mut calls = JoinSet::new();
    for r in robots {
        let (client, permits, id) = (client.clone(), permits.clone(), r.id.clone());
        calls.spawn(async move {
            let _permit = permits.acquire_owned().await;
            let deleted = client.delete(&id, PRIMITIVE).await;
            // A robot that was never set up has nothing to delete.
            let deleted = match deleted {
                Err(e) if e.is_not_found() => Ok(0),
                other => other,
            };
            setup_call("deleting a primitive", std::future::ready(deleted)).await.map(drop)
        });
    }
    for cell in cells {
        let client = client.clone().with_cell(cell.clone());
        let scene = setup_call("listing a cell's obstacles", client.list_obstacles()).await;
        let scene = scene.map_err(SimError::protocol)?;
        for k in 0..FIXED_OBSTACLES {
            let id = layout::obstacle_id(k);
            if scene.obstacles.iter().any(|o| o.id == id) {
                let (client, permits) = (client.clone(), permits.clone());
                calls.spawn(async move {
                    let _permit = permits.acquire_owned().await;
                    setup_call("deleting a fixed obstacle", client.delete_obstacle(&id)).await.map(drop)
                });
            }
        }
    }
    let mut first_error = None;
    while let Some(done) = calls.join_next().await {
        let e = match done {
            Ok(Ok(())) => continue,
            Ok(Err(e)) => e,
            Err(e) => format!("a clean-up task: {e}"),
        };
        first_error.get_or_insert(e.replacen("setup: ", "", 1));
    }
    first_error.map_or(Ok(()), |e| Err(SimError::protocol(e)))
}
