//! The simulated robots (`dmp_client::sim`) against the real server, in-process on 127.0.0.1:0 with Zenoh on
//! loopback (multicast off). Each asserts what the issue asks of every simulation: goals reached, no contact with
//! any true shape or other robot, nothing non-finite, continuous setpoints. Every await is under a timeout.

mod common;

use common::{config, within};
use dmp_client::sim::{SimName, SimOptions, SimReport, run};
use dmp_server::run::{ServerHandle, start};

/// Starts a server, runs `name` against it (simulated clock), shuts the server down; returns the report and
/// checks that the report and the figures were written.
async fn simulate(name: SimName) -> SimReport {
    let dir = tempfile::tempdir().unwrap();
    let handle: ServerHandle = within("server start", start(config(&dir.path().join("data")))).await.unwrap();
    let out = dir.path().join("out");
    let options = SimOptions {
        realtime: false,
        out: out.clone(),
        zenoh_connect: handle.zenoh_locators.clone(),
        cell: "default".into(),
    };
    let url = format!("http://{}", handle.grpc_addr);
    let report = within("simulation", run(&url, name, &options)).await.expect("the simulation runs");
    within("shutdown", handle.shutdown()).await.unwrap();
    let written: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(written["collision"], serde_json::Value::Bool(report.collision));
    for plot in &report.plots {
        let svg = std::fs::read_to_string(out.join(plot)).unwrap();
        assert!(svg.starts_with("<svg") || svg.starts_with("<?xml"), "{plot} is not an SVG");
    }
    // Shown with --nocapture (and on failure).
    println!("{}", serde_json::to_string_pretty(&report).unwrap());
    report
}

fn assert_clean(report: &SimReport) {
    let problems = report.problems();
    assert!(problems.is_empty(), "{problems:#?}\n{}", serde_json::to_string_pretty(report).unwrap());
    assert!(!report.collision);
    for (id, r) in &report.robots {
        assert!(r.reached_goal, "{id}");
        assert!(r.peak_acceleration.is_finite(), "{id}");
        for (o, d) in &r.min_clearance_m {
            assert!(d.is_finite() && *d > 0.0, "{id}: clearance to {o} is {d}");
        }
    }
}

#[tokio::test(flavor = "multi_thread")]
async fn panda_picks_and_places_past_the_red_peg() {
    let report = simulate(SimName::Panda).await;
    assert_clean(&report);
    assert_eq!(report.robots.len(), 3);
    assert_eq!(report.plots.len(), 3);
    for (id, r) in &report.robots {
        assert_eq!(r.late_setpoints, 0, "{id}");
        assert!(r.setpoints >= 1000, "{id}: {} setpoints at 1 kHz", r.setpoints);
    }
    // Both carries go past the red peg without touching it with the ring.
    for key in ["panda/carry-static", "panda/carry-dynamic"] {
        let d = report.robots[key].min_clearance_m["red-peg"];
        assert!(d > 0.0 && d < 0.1, "{key}: clearance to the red peg {d}");
    }
}

#[tokio::test(flavor = "multi_thread")]
async fn youbot_avoids_a_box_published_by_a_perception_node() {
    let report = simulate(SimName::YoubotPerception).await;
    assert_clean(&report);
    assert_eq!(report.robots.len(), 4);
    // The box that stays is avoided (it is in the robot's way).
    for key in ["youbot/added-static", "youbot/added-dynamic"] {
        let d = report.robots[key].min_clearance_m["box"];
        assert!(d > 0.0 && d < 0.5, "{key}: clearance to the box {d}");
    }
    let m = |k: &str| report.metrics[k];
    for method in ["static", "dynamic"] {
        // The permanent box bends the path; the temporary one, removed before the robot reaches it, bends it
        // less, and past it the path is back near the straight line.
        let added = m(&format!("youbot/added-{method}/max_abs_y_m"));
        let temporary = m(&format!("youbot/temporary-{method}/max_abs_y_m"));
        let back = m(&format!("youbot/temporary-{method}/max_abs_y_past_box_m"));
        assert!(added > 0.2, "{method}: the box bent the path by only {added}");
        assert!(
            temporary > 1e-4 && temporary < added,
            "{method}: the temporary box bent the path by {temporary}"
        );
        assert!(back < 0.1 * temporary, "{method}: {back} from the line past the removed box");
    }
}
