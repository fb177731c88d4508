//! The paper's experiments from the scenario files, through the same library `dmpctl scenario run` uses.
//!
//! The first experiment (`scenarios/paper-one-obstacle`, six runs) must match the metrics an independent
//! implementation measured (`expected-metrics.json`); the other scenarios are checked for what they demonstrate.

use std::path::{Path, PathBuf};

use dmpctl::offline::run_scenario;
use serde_json::Value;

fn scenarios() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios")
}

fn run(file: &Path) -> Value {
    let out = tempfile::tempdir().unwrap();
    let summary = run_scenario(file, out.path()).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
    for f in ["trajectory.csv", "metrics.json", "plot.svg"] {
        assert!(out.path().join(f).exists(), "{f} missing");
    }
    serde_json::to_value(&summary.metrics).unwrap()
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

#[test]
fn first_experiment_matches_the_expected_metrics() {
    let dir = scenarios().join("paper-one-obstacle");
    let expected: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("expected-metrics.json")).unwrap()).unwrap();
    let expected = expected.as_object().unwrap();
    assert_eq!(expected.len(), 6);
    for (file, want) in expected {
        let got = run(&dir.join(file));
        let ctx = |k: &str| format!("{file} {k}: got {} want {}", got[k], want[k]);
        assert_eq!(got["collision"], want["collision"], "{}", ctx("collision"));
        assert_eq!(got["steps"], want["steps"], "{}", ctx("steps"));
        assert_eq!(got["finite"], true);
        let (ge, we) = (f(&got["eps_max"]), f(&want["eps_max"]));
        assert!((ge - we).abs() <= (0.01 * we).max(1e-3), "{}", ctx("eps_max"));
        let (ga, wa) = (f(&got["acc_max_after_10pct"]), f(&want["acc_max_after_10pct"]));
        assert!((ga - wa).abs() <= 0.05 * wa, "{}", ctx("acc_max_after_10pct"));
        let (gg, wg) = (f(&got["final_goal_distance"]), f(&want["final_goal_distance"]));
        assert!((gg - wg).abs() <= 2e-3, "{}", ctx("final_goal_distance"));
        for (id, wo) in want["obstacles"].as_object().unwrap() {
            let go = &got["obstacles"][id];
            assert_eq!(go["collision"], wo["collision"], "{file} {id}");
            let (gd, wd) = (f(&go["min_distance"]), f(&wo["min_distance"]));
            assert!((gd - wd).abs() <= 1e-3, "{file} {id} min_distance: got {gd} want {wd}");
        }
    }
}

#[test]
fn the_volumetric_methods_clear_two_obstacles() {
    for method in ["static-volumetric", "dynamic-volumetric"] {
        let m = run(&scenarios().join(format!("paper-two-obstacles-{method}.json")));
        assert_eq!(m["collision"], false, "{method}");
        assert!(f(&m["final_goal_distance"]) < 2e-3, "{method}");
        for id in ["ellipse", "circle"] {
            assert!(f(&m["obstacles"][id]["min_distance"]) > 0.0, "{method} {id}");
        }
    }
}

#[test]
fn a_moving_obstacle_is_avoided_with_relative_velocity() {
    let m = run(&scenarios().join("moving-obstacle-dynamic-volumetric.json"));
    assert_eq!(m["collision"], false);
    assert!(f(&m["eps_max"]) > 1e-3, "the obstacle must actually deflect the path");
    // Without avoidance the same walker is hit: the test can fail.
    let mut v: Value = serde_json::from_str(
        &std::fs::read_to_string(scenarios().join("moving-obstacle-dynamic-volumetric.json")).unwrap(),
    )
    .unwrap();
    v["avoidance"] = serde_json::json!({"method": "none"});
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("none.json");
    std::fs::write(&file, serde_json::to_string(&v).unwrap()).unwrap();
    assert_eq!(run(&file)["collision"], true);
}

#[test]
fn ten_rotated_moving_superquadrics_in_3d() {
    let m = run(&scenarios().join("bench-3d-ten-dynamic-volumetric.json"));
    assert_eq!(m["collision"], false);
    assert_eq!(m["finite"], true);
    assert_eq!(m["obstacles"].as_object().unwrap().len(), 10);
}

#[test]
fn three_youbots_on_one_phase_do_not_collide() {
    let m = run(&scenarios().join("youbots-three-dynamic.json"));
    assert_eq!(m["collision"], false);
    let robots = m["robots"].as_object().unwrap();
    assert_eq!(robots.len(), 3);
    for (id, r) in robots {
        assert!(f(&r["final_goal_distance"]) < 0.15, "{id}: {r}");
    }
    assert_eq!(m["robot_pairs"].as_object().unwrap().len(), 3);
    for (pair, p) in m["robot_pairs"].as_object().unwrap() {
        assert_eq!(p["collision"], false, "{pair}");
        assert!(f(&p["min_center_distance"]) > 0.3, "{pair}: {p}");
    }
}

#[test]
fn the_held_bar_scenario_writes_its_orientations_and_the_tools_outline() {
    let out = tempfile::tempdir().unwrap();
    let file = scenarios().join("bar-through-gap/tool-static-volumetric.json");
    let summary = run_scenario(&file, out.path()).unwrap();
    let m = serde_json::to_value(&summary.metrics).unwrap();
    assert_eq!(m["collision"], false);
    assert!(f(&m["pose"]["max_turn_from_free_deg"]) > 7.5, "the bar turns to pass: {m}");
    assert!(f(&m["pose"]["tool_min_distance"]["peg0"]) > 0.0);
    let csv = std::fs::read_to_string(out.path().join("trajectory.csv")).unwrap();
    let header = csv.lines().next().unwrap();
    assert_eq!(header, "t,x1,x2,x3,xd1,xd2,xd3,a1,a2,a3,qx,qy,qz,qw,wx,wy,wz,wdx,wdy,wdz");
    let last: Vec<f64> = csv.lines().last().unwrap().split(',').map(|v| v.parse().unwrap()).collect();
    let q = &last[10..14];
    assert!((q.iter().map(|v| v * v).sum::<f64>() - 1.0).abs() < 1e-12, "a unit quaternion: {q:?}");
    let svg = std::fs::read_to_string(out.path().join("plot.svg")).unwrap();
    assert!(
        svg.contains("tool at t (s)") && svg.contains("strip-orientation"),
        "the tool and its rotation drawn"
    );
}
