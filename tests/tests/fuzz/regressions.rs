//! Inputs the fuzzer failed on, replayed through the same checks as the targets.

use crate::files::check_scenario;
use crate::wire::check_obstacle_payload;

/// The scenario of `scenario_files`' failure: `alpha = 5e-324` makes learning panic in `dmp/src/basis.rs:78`
/// (slice index `usize::MAX..`).
#[test]
fn a_vanishing_alpha_is_refused_not_a_panic() {
    let t: Vec<f64> = (0..13).map(|i| f64::from(i) / 260.0).collect();
    let demo = dmp::Demonstration::new(t, vec![vec![0.0; 3]; 13]).unwrap();
    let config = dmp::LearnConfig { n_basis: 1, k: vec![0.01], d: None, alpha: 5e-324 };
    assert!(dmp::learn(&demo, &config).is_err());
}

/// The same scenario through the file reader: refused or run, never a panic.
#[test]
fn the_vanishing_alpha_scenario_file_reads() {
    let text = r#"{"avoidance":{"beta":8.245673271132093,"lambda":0.46303556356560827,"method":"dynamic_point"},
        "demonstration":{"t":[0.0,0.0038461538461538464,0.007692307692307693],"x":[[0.0,0.0,0.0],[0.0,0.0,0.0],
        [0.0,0.0,0.0]]},"dmp":{"D":null,"K":0.01,"N":1,"alpha":5e-324},"name":"fuzz","obstacles":[],
        "point_samples":10,"robot_avoidance":null,"robots":[],
        "rollout":{"dt":0.01,"duration":1.0,"goal":null,"start":null,"tau":null}}"#;
    check_scenario(text).unwrap();
}

/// The obstacle of `obstacle_payloads`' failure: a semi-axis of 5e-324 is accepted, and its potential at its centre
/// is NaN.
#[test]
fn a_vanishing_semi_axis_is_refused() {
    let json = br#"{"id": "a", "center": [0.0, 0.0], "semi_axes": [0.01, 5e-324],
        "rotation": [[0.5289743876335489, -0.8486377891819996], [0.8486377891819996, 0.5289743876335489]],
        "velocity": [1e300, -0.5682802582874589], "ttl_s": 11.992873073914597}"#;
    let o = dmp_proto::payload::decode_obstacle("text/json", json, "a").unwrap();
    assert!(dmp_proto::obstacle::obstacle_to_engine(&o).is_err(), "accepted: {o:?}");
}

/// The same payload through the target's check.
#[test]
fn the_vanishing_semi_axis_payload_decodes() {
    let json = br#"{"center": [0.0, 0.0], "semi_axes": [0.01, 5e-324], "velocity": [1e300, 0]}"#;
    check_obstacle_payload("text/json", json, "a").unwrap();
}
