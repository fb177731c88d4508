//! The real server, in-process on 127.0.0.1:0 with Zenoh on loopback (multicast off), driven through the client
//! library exactly as robots and perception nodes drive it. Every await is under a timeout.

mod access;
mod arrival;
mod audit_log;
mod bad_input;
mod catch_up;
mod catch_up_cells;
mod cell_claims;
mod default_limits;
mod forged_sender;
mod forged_versions;
mod hostile_compute;
mod hostile_sessions;
mod hostile_values;
mod limits;
mod load;
mod matches_the_engine;
mod metrics;
mod motion_limits;
mod plant;
mod plant_joiner;
mod poses;
mod primitives;
mod python_clients;
mod refusals;
mod revocation;
mod robot_records;
mod robots;
mod ros2_bridge;
mod ros2_budget;
mod ros2_golden;
mod ros2_trajectories;
mod scene_over_zenoh;
mod sessions_and_groups;
mod stale_scene;
mod tls;
mod unknown_cells;
mod verdicts;
mod zenoh_access;

use std::path::Path;
use std::time::Duration;

use dmp::Primitive;
use dmp_client::grpc::DmpClient;
use dmp_proto::v1;
use dmp_server::server::{ServerHandle, start};
use dmp_tests::{config, within};

async fn serve(dir: &Path) -> (ServerHandle, DmpClient) {
    let handle = within("server start", start(config(dir))).await.expect("server starts");
    let client = within("connect", DmpClient::connect(format!("http://{}", handle.grpc_addr)))
        .await
        .expect("connects");
    (handle, client)
}

/// A server of cell `cell-a`, secured by a fresh `access init` set in `set` for `robots` (TLS, the access file,
/// Zenoh on a `tls/` loopback endpoint), its data in `data`: the server, its `tls/` Zenoh locator and the set's
/// tokens (identity, token).
async fn secured_cell_a(
    set: &Path,
    data: &Path,
    robots: &[&str],
) -> (ServerHandle, String, Vec<(String, String)>) {
    let robots = robots.iter().map(|r| r.to_string()).collect();
    let options =
        dmp_server::access::init::InitOptions { cells: vec!["cell-a".into()], robots, ..Default::default() };
    let tokens = dmp_server::access::init::init(set, &options).unwrap().tokens;
    let mut c = config(data);
    c.cell = "cell-a".into();
    dmp_tests::secure(&mut c, set);
    let h = within("server start", start(c)).await.expect("server starts");
    let locator = h.zenoh_locators.iter().find(|l| l.starts_with("tls/")).expect("a tls/ locator").clone();
    (h, locator, tokens)
}

/// Waits (polling a condition, not a fixed sleep) until `cond` holds.
async fn until(what: &str, mut cond: impl FnMut() -> bool) {
    within(what, async {
        while !cond() {
            tokio::time::sleep(Duration::from_millis(5)).await;
        }
    })
    .await
}

fn paper_curve() -> (Vec<f64>, Vec<Vec<f64>>) {
    let t: Vec<f64> = (0..=1000).map(|i| i as f64 * 1e-3).collect();
    let x = t
        .iter()
        .map(|t| vec![t * (std::f64::consts::PI * t).cos(), t * (std::f64::consts::PI * t).sin()])
        .collect();
    (t, x)
}

fn line(start: Vec<f64>, goal: Vec<f64>, tau: f64) -> Primitive {
    let d = start.len();
    Primitive::straight_line(50, 4.0, vec![3050.0; d], None, tau, start, goal).unwrap()
}

fn spec(robot: &str, name: &str) -> v1::MotionSpec {
    v1::MotionSpec { robot_id: robot.into(), primitive: name.into(), ..Default::default() }
}

fn ellipse(id: &str, center: Vec<f64>, axes: Vec<f64>) -> v1::Obstacle {
    v1::Obstacle {
        id: id.into(),
        shape: Some(v1::obstacle::Shape::Superquadric(v1::Superquadric {
            semi_axes: axes,
            exponents: vec![],
        })),
        center,
        ..Default::default()
    }
}

fn dynamic_volumetric(lambda: f64, beta: f64, eta: f64) -> v1::Avoidance {
    v1::Avoidance {
        method: Some(v1::avoidance::Method::DynamicVolumetric(v1::avoidance::DynamicVolumetric {
            lambda,
            beta,
            eta,
        })),
        ..Default::default()
    }
}

fn rows(seg: &v1::Segment, v: &[f64]) -> Vec<Vec<f64>> {
    v.chunks(seg.dim as usize).map(<[f64]>::to_vec).collect()
}
