//! The `dmpctl` binary, offline: outputs of `scenario run` and `scenario bench`, and a clear error with the field at
//! fault, exit code 2 and no panic for every kind of bad scenario.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde_json::Value;

fn scenarios() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios")
}

fn dmpctl(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_dmpctl")).args(args).output().expect("dmpctl runs")
}

fn paper(method: &str) -> Value {
    let path = scenarios().join(format!("paper-one-obstacle/{method}.json"));
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn scenario_run_writes_the_three_files() {
    let out = tempfile::tempdir().unwrap();
    let file = scenarios().join("paper-one-obstacle/dynamic_volumetric.json");
    let o = dmpctl(&["scenario", "run", file.to_str().unwrap(), "--out", out.path().to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = std::fs::read_to_string(out.path().join("trajectory.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("t,x1,x2,xd1,xd2,a1,a2"));
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), 1001);
    assert!(rows[0].starts_with("0,0,0,0,0,"));
    assert!(rows[1000].starts_with("1,"));
    let metrics: Value =
        serde_json::from_str(&std::fs::read_to_string(out.path().join("metrics.json")).unwrap()).unwrap();
    assert_eq!(metrics["steps"], 1000);
    assert_eq!(metrics["finite"], true);
    assert!(metrics["compute_seconds"].as_f64().unwrap() > 0.0);
    let svg = std::fs::read_to_string(out.path().join("plot.svg")).unwrap();
    assert!(svg.contains("<svg") && svg.contains("</svg>") && !svg.contains("NaN"));
}

#[test]
fn a_run_with_problems_exits_3_with_its_summary_unless_the_collision_is_allowed() {
    let out = tempfile::tempdir().unwrap();
    let o = out.path().to_str().unwrap();
    let file = scenarios().join("paper-one-obstacle/none.json");
    let run = dmpctl(&["scenario", "run", file.to_str().unwrap(), "--out", o]);
    let (stdout, stderr) = (String::from_utf8_lossy(&run.stdout), String::from_utf8_lossy(&run.stderr));
    assert_eq!(run.status.code(), Some(3), "{stderr}");
    assert!(stdout.contains("collision: true"), "{stdout}");
    assert!(stderr.contains("the run completed with problems: collision"), "{stderr}");
    assert!(out.path().join("metrics.json").exists(), "the outputs are written all the same");
    let allowed = dmpctl(&["scenario", "run", file.to_str().unwrap(), "--out", o, "--allow-collision"]);
    assert!(allowed.status.success(), "{}", String::from_utf8_lossy(&allowed.stderr));
    // A run that ends short of its goal fails too: the 3-D bench scenario stops 7.6 cm away.
    let bench = scenarios().join("bench-3d-ten-dynamic-volumetric.json");
    let short = dmpctl(&["scenario", "run", bench.to_str().unwrap(), "--out", o]);
    assert_eq!(short.status.code(), Some(3));
    assert!(String::from_utf8_lossy(&short.stderr).contains("goal not reached"));
}

#[test]
fn scenario_bench_prints_one_json_object() {
    let file = scenarios().join("paper-one-obstacle/static_volumetric.json");
    let o = dmpctl(&["scenario", "bench", file.to_str().unwrap(), "--repeat", "3"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: Value = serde_json::from_str(String::from_utf8(o.stdout).unwrap().trim()).unwrap();
    assert_eq!(v["steps"], 1000);
    assert_eq!(v["repeats"], 3);
    assert!(v["steps_per_second"].as_f64().unwrap() > 1000.0);
}

/// Writes `text` to a file, runs `scenario run` on it, and checks exit code 2, no panic, and that the message names
/// `field` and says `rule`.
fn assert_refused(text: &str, field: &str, rule: &str) {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("bad.json");
    std::fs::write(&file, text).unwrap();
    let o = dmpctl(&[
        "scenario",
        "run",
        file.to_str().unwrap(),
        "--out",
        dir.path().join("out").to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "expected exit 2 for {field}, stderr: {err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(err.contains(field), "message does not name `{field}`: {err}");
    assert!(err.contains(rule), "message does not say `{rule}`: {err}");
    assert!(!dir.path().join("out/trajectory.csv").exists());
}

fn refused_after(edit: impl FnOnce(&mut Value), field: &str, rule: &str) {
    let mut v = paper("dynamic_volumetric");
    edit(&mut v);
    assert_refused(&serde_json::to_string(&v).unwrap(), field, rule);
}

#[test]
fn bad_scenarios_name_the_field_and_exit_2() {
    refused_after(|v| drop(v.as_object_mut().unwrap().remove("dmp")), "dmp", "missing field");
    refused_after(
        |v| drop(v["rollout"].as_object_mut().unwrap().remove("dt")),
        "rollout",
        "missing field `dt`",
    );
    refused_after(
        |v| v["demonstration"]["t"][5] = v["demonstration"]["t"][4].clone(),
        "demonstration.t[5]",
        "increasing",
    );
    refused_after(
        |v| v["demonstration"]["x"][7] = serde_json::json!([0, 0, 0]),
        "demonstration.x[7]",
        "coordinates",
    );
    refused_after(
        |v| v["obstacles"][0]["center"] = serde_json::json!([0, 0, 0]),
        "obstacles[0].center",
        "2 entries",
    );
    refused_after(
        |v| v["obstacles"][0]["semi_axes"][0] = (-0.3).into(),
        "obstacles[0].semi_axes[0]",
        "greater than zero",
    );
    refused_after(|v| v["obstacles"][0]["exponents"][1] = 0.5.into(), "obstacles[0].exponents[1]", ">= 1");
    refused_after(
        |v| v["obstacles"][0]["rotation"] = serde_json::json!([[1.0, 0.2], [0.0, 1.0]]),
        "obstacles[0].rotation",
        "orthonormal",
    );
    refused_after(|v| v["avoidance"]["method"] = "magic".into(), "avoidance", "unknown variant `magic`");
    refused_after(
        |v| drop(v["avoidance"].as_object_mut().unwrap().remove("lambda")),
        "avoidance",
        "missing field `lambda`",
    );
    refused_after(|v| v["avoidance"]["beta"] = 0.5.into(), "avoidance.beta", "between 1 and 100");
    refused_after(|v| v["rollout"]["dt"] = 0.0.into(), "rollout.dt", "greater than zero");
    refused_after(|v| v["rollout"]["dt"] = (-0.001).into(), "rollout.dt", "greater than zero");
    refused_after(|v| v["rollout"]["duration"] = 1e9.into(), "rollout.duration", "limit");
    refused_after(|v| v["rollout"]["goal"] = serde_json::json!([1, 2, 3]), "rollout.goal", "2 entries");
    refused_after(|v| v["dmp"]["N"] = 0.into(), "dmp.N", "at least 1");
    refused_after(|v| v["dmp"]["K"] = serde_json::json!([1050.0, -1.0]), "dmp.K[1]", "greater than zero");
    refused_after(
        |v| {
            v["avoidance"] =
                serde_json::json!({"method": "steering_angle", "gamma": 20.0, "beta": 3.0, "bogus": 1})
        },
        "avoidance",
        "unknown field `bogus`",
    );
    refused_after(
        |v| {
            v["robots"] = serde_json::json!([
                {"id": "a", "dims": [0, 1], "footprint": {"semi_axes": [0.1, 0.1]}},
                {"id": "b", "dims": [1, 0], "footprint": {"semi_axes": [0.1, 0.1]}}
            ])
        },
        "robots[1].dims",
        "already owned",
    );
}

#[test]
fn nan_and_malformed_text_are_refused_at_the_field() {
    let mut v = paper("static_point");
    v["demonstration"]["x"][3][1] = 12345.678.into();
    let text = serde_json::to_string(&v).unwrap().replace("12345.678", "NaN");
    assert_refused(&text, "demonstration.x[3][1]", "finite");
    let text = serde_json::to_string(&v).unwrap().replace("12345.678", "Infinity");
    assert_refused(&text, "demonstration.x[3][1]", "finite");
    assert_refused("{\"name\": ", "name", "EOF");
    assert_refused("[1, 2]", "(document)", "expected opening brace");
}

#[test]
fn a_missing_file_is_an_io_error_not_bad_input() {
    let o = dmpctl(&["scenario", "run", "/nonexistent/scenario.json", "--out", "/tmp/never"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("/nonexistent/scenario.json"));
}

#[test]
fn server_commands_exit_1_when_the_server_is_unreachable_and_2_on_bad_arguments() {
    // Port 1 on loopback: nothing listens.
    let o = dmpctl(&["--server", "http://127.0.0.1:1", "list", "--robot", "r"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("cannot connect to the server at http://127.0.0.1:1"), "{err}");

    let o = dmpctl(&["plan", "--robot", "r", "--name", "p", "--goal", "1,x", "--out", "/tmp/never"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("--goal") && err.contains("entry 2"), "{err}");

    // A bad obstacle file is refused before anything is sent, naming the field.
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("o.json");
    std::fs::write(&file, r#"{"id": "a", "center": [0, 0], "semi_axes": [0.1, -1]}"#).unwrap();
    for via in ["grpc", "zenoh"] {
        let o =
            dmpctl(&["scene", "put", file.to_str().unwrap(), "--via", via, "--server", "http://127.0.0.1:1"]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains("semi_axes[1]"), "{err}");
    }
}

/// A command that runs for more than the 2 s after which progress appears on a terminal, with stderr piped (as
/// here): nothing of the progress is written, stderr stays empty and stdout has only the result.
#[test]
fn progress_stays_off_a_pipe() {
    let file = scenarios().join("bench-3d-ten-dynamic-volumetric.json");
    // Long enough to pass the 2 s after which a terminal would see progress: more repeats until it is, however
    // fast the machine (600 took about 2-6 s here).
    let mut repeat = 600;
    let o = loop {
        let started = std::time::Instant::now();
        let o = dmpctl(&["scenario", "bench", file.to_str().unwrap(), "--repeat", &repeat.to_string()]);
        let took = started.elapsed();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        if took > std::time::Duration::from_millis(2500) {
            break o;
        }
        assert!(repeat < 600 * 16, "took {took:?} with {repeat} repeats: too short to show progress anyway");
        repeat *= 4;
    };
    assert_eq!(String::from_utf8_lossy(&o.stderr), "");
    let stdout = String::from_utf8(o.stdout).unwrap();
    assert_eq!(stdout.lines().count(), 1, "{stdout}");
    assert!(!stdout.contains('\r') && !stdout.contains('\u{1b}'), "{stdout:?}");
}

/// The same broken obstacle, in a scenario given to `scenario run` and to `scene put`: the same error line,
/// `FILE:LINE:COLUMN: FIELD: REASON`, and exit code 2 (`scene put` refuses its file before asking the server).
#[test]
fn one_error_style_for_the_same_bad_obstacle_in_scenario_run_and_scene_put() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    for (bad, field, reason) in [
        (Value::from("wide"), "obstacles[0].semi_axes[1]", "invalid type: string \"wide\", expected f64"),
        (Value::from(-1.0), "obstacles[0].semi_axes[1]", "must be a finite number greater than zero"),
    ] {
        let mut v = paper("dynamic_volumetric");
        v["obstacles"][0]["semi_axes"][1] = bad;
        let file = dir.path().join("bad.json");
        std::fs::write(&file, serde_json::to_string_pretty(&v).unwrap()).unwrap();
        let f = file.to_str().unwrap();
        let run = dmpctl(&["scenario", "run", f, "--out", out.to_str().unwrap()]);
        let put = dmpctl(&["--server", "http://127.0.0.1:1", "--cell", "c", "scene", "put", f]);
        let (run_err, put_err) = (String::from_utf8_lossy(&run.stderr), String::from_utf8_lossy(&put.stderr));
        assert_eq!((run.status.code(), put.status.code()), (Some(2), Some(2)), "{run_err}\n{put_err}");
        assert_eq!(run_err, put_err);
        // The line and column of the value: in the pretty-printed file, the second entry of `semi_axes`.
        let text = std::fs::read_to_string(&file).unwrap();
        let (line, text_line) =
            text.lines().enumerate().skip_while(|(_, l)| !l.contains("\"semi_axes\"")).nth(2).unwrap();
        let column = text_line.len() - text_line.trim_start().len() + 1;
        assert_eq!(run_err.trim_end(), format!("dmpctl: {f}:{}:{column}: {field}: {reason}", line + 1));
    }
}
