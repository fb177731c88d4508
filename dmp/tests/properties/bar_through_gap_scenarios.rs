//! The bar-through-gap experiment as scenario files (`scenarios/bar-through-gap/`, written by
//! `scenarios/generate.py`): the [`DOWN`] layout of [`super::bar_through_gap`], run through the scenario format
//! (`dmp::scenario`, what `dmpctl scenario run` runs), with the bar as a held tool (`tool`) or as a point robot
//! among pegs inflated by its half-length.
//!
//! `expected-metrics.json` holds the metrics this implementation measured when the files were written (there is no
//! independent implementation of a held tool to compare with): a regression check. What the experiment shows is
//! asserted on its own: the tool-aware run with the static volumetric potential passes, turning the bar, and the
//! parry3d clearance of the true bar (a 0.6 x 0.02 x 0.02 m box) to the true pegs (cylinders) stays positive at
//! every 1 ms step; the point robot never passes. The tool-aware run with the dynamic potential passes too, but
//! spins the bar (166° from the free run, over 60 rad/s at its peak): recorded, not a result to copy.

use std::path::{Path, PathBuf};

use dmp::scenario::{Scenario, prepare, run};
use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use serde_json::Value;

use super::bar_through_gap::{DOWN, clearance};

fn dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/bar-through-gap")
}

fn load(file: &str) -> Scenario {
    let text = std::fs::read_to_string(dir().join(file)).unwrap();
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{file}: {e}"))
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

#[test]
fn the_bar_scenarios_match_their_expected_metrics() {
    let expected: Value =
        serde_json::from_str(&std::fs::read_to_string(dir().join("expected-metrics.json")).unwrap()).unwrap();
    let expected = expected.as_object().unwrap();
    assert_eq!(expected.len(), 4);
    for (file, want) in expected {
        let p = prepare(&load(file)).unwrap();
        let got = serde_json::to_value(run(&p).unwrap().metrics).unwrap();
        let ctx = |k: &str| format!("{file} {k}: got {} want {}", got[k], want[k]);
        for k in ["collision", "finite", "steps"] {
            assert_eq!(got[k], want[k], "{}", ctx(k));
        }
        assert_eq!(got["time_to_goal"].is_null(), want["time_to_goal"].is_null(), "{}", ctx("time_to_goal"));
        assert_eq!(
            got["stalls"].as_array().unwrap().len(),
            want["stalls"].as_array().unwrap().len(),
            "{file}"
        );
        let (gg, wg) = (f(&got["final_goal_distance"]), f(&want["final_goal_distance"]));
        assert!((gg - wg).abs() <= 2e-3, "{}", ctx("final_goal_distance"));
        let (ge, we) = (f(&got["eps_max"]), f(&want["eps_max"]));
        assert!((ge - we).abs() <= (0.01 * we).max(1e-3), "{}", ctx("eps_max"));
        let turn = |m: &Value| f(&m["pose"]["max_turn_from_free_deg"]);
        assert!((turn(&got) - turn(want)).abs() <= 1.0, "{file}: turn {} want {}", turn(&got), turn(want));
        assert_eq!(got["pose"]["tool_contact_rows"], want["pose"]["tool_contact_rows"], "{file}");
        for (id, wd) in want["pose"]["tool_min_distance"].as_object().into_iter().flatten() {
            let gd = f(&got["pose"]["tool_min_distance"][id]);
            assert!((gd - f(wd)).abs() <= 1e-3, "{file} {id} tool_min_distance: got {gd} want {wd}");
            assert!(gd > 0.0, "{file}: the tool's surface keeps clear of {id}");
        }
        for (id, wo) in want["obstacles"].as_object().unwrap() {
            let (gd, wd) = (f(&got["obstacles"][id]["min_distance"]), f(&wo["min_distance"]));
            assert!((gd - wd).abs() <= 1e-3, "{file} {id} min_distance: got {gd} want {wd}");
        }
    }
}

/// The bar's middle and orientation at every row of the scenario's adapted run.
fn poses(file: &str) -> Vec<(Vector3<f64>, UnitQuaternion<f64>)> {
    let p = prepare(&load(file)).unwrap();
    let out = run(&p).unwrap();
    let (traj, q) = (&out.adapted.trajectory, &out.adapted.orientations.q);
    assert_eq!(q.len(), 4 * traj.len(), "an orientation per row");
    (0..traj.len())
        .map(|k| {
            let x = Vector3::from_column_slice(&traj.position(k)[..3]);
            let q = UnitQuaternion::new_normalize(Quaternion::new(
                q[4 * k + 3],
                q[4 * k],
                q[4 * k + 1],
                q[4 * k + 2],
            ));
            (x, q)
        })
        .collect()
}

#[test]
fn the_held_bar_turns_and_passes_the_pegs_without_touching_them() {
    let run = poses("tool-static-volumetric.json");
    let worst = run.iter().map(|(x, q)| clearance(&DOWN, x, q)).fold(f64::INFINITY, f64::min);
    assert!(worst > 0.0, "the true bar touches a true peg");
    assert!(run.iter().any(|(x, _)| DOWN.passed(x)), "the whole bar gets past the pegs");
    // Held as it starts (100° from the x axis), the bar's line passes 3.5 cm from each peg's axis (0.2 m from its
    // middle): it gets by only once turned to at most 72.5° or at least 107.5°, where the line misses the axes by
    // the peg's radius and the bar's half-thickness (6 cm).
    let start = run[0].1;
    let turn = run.iter().map(|(_, q)| q.angle_to(&start).to_degrees()).fold(0.0, f64::max);
    assert!(turn > 7.5, "it passes by turning: {turn}°");
    // A point robot among the pegs inflated by the bar's half-length is held above them, with either potential.
    for file in ["point-static-volumetric.json", "point-dynamic-volumetric.json"] {
        let run = poses(file);
        assert!(run.iter().all(|(x, _)| DOWN.held_before(x, 0.0)), "{file}: it never reaches the pegs");
    }
}
