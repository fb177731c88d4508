//! The file formats: scenario files (dmpctl's JSON5 reader, then the engine's validation and, when small, the
//! offline run) and demonstration CSV files (`dmpctl learn --csv`). None may panic; what they accept is finite.

use std::path::Path;

use proptest::collection::vec;
use proptest::prelude::*;
use proptest::test_runner::TestCaseResult;
use serde_json::{Value, json};

use dmpctl::demo_csv::parse_demonstration_csv;
use dmpctl::scenario_file::parse_scenario;

use crate::mutate::{Mutated, mutated};
use crate::runner::fuzz;
use crate::values::{extreme, num, pos, wildness};
use crate::wire::all_finite;

/// The largest scenario run in full by a case (steps, samples, basis functions, boundary samples).
const RUN_LIMITS: (usize, usize, usize, usize) = (3000, 2000, 100, 200);

/// The checks of one scenario text: parsing, validation and (when small) the run never panic, and a run that
/// succeeds is finite.
pub fn check_scenario(text: &str) -> TestCaseResult {
    let Ok(s) = parse_scenario(text, Path::new("fuzz.json")) else { return Ok(()) };
    let (max_steps, max_samples, max_basis, max_points) = RUN_LIMITS;
    if s.demonstration.t.len() > max_samples || s.dmp.n > max_basis || s.point_samples > max_points {
        return Ok(());
    }
    let Ok(prepared) = dmp::scenario::prepare(&s) else { return Ok(()) };
    all_finite("primitive.goal", &prepared.primitive.goal)?;
    for w in &prepared.primitive.weights {
        all_finite("primitive.weights", w)?;
    }
    if prepared.steps > max_steps {
        return Ok(());
    }
    let Ok(outcome) = dmp::scenario::run(&prepared) else { return Ok(()) };
    for (what, r) in [("free", &outcome.free), ("adapted", &outcome.adapted)] {
        let tr = &r.trajectory;
        for (field, v) in [("t", &tr.t), ("x", &tr.x), ("xd", &tr.xd), ("xdd", &tr.xdd)] {
            all_finite(&format!("{what}.{field}"), v)?;
        }
    }
    Ok(())
}

/// A small valid scenario: the seed of the mutations and of the structured cases.
fn small_scenario() -> Value {
    let t: Vec<f64> = (0..=20).map(|i| i as f64 * 0.05).collect();
    let x: Vec<Vec<f64>> = t.iter().map(|t| vec![*t, t * t]).collect();
    json!({
        "name": "fuzz",
        "demonstration": {"t": t, "x": x},
        "dmp": {"N": 10, "K": 1050.0, "D": null, "alpha": 4.0},
        "rollout": {"dt": 0.01, "duration": 1.2, "start": null, "goal": null, "tau": null},
        "obstacles": [{"id": "o", "center": [0.5, 0.3], "semi_axes": [0.1, 0.05], "exponents": [1, 2]}],
        "point_samples": 20,
        "avoidance": {"method": "dynamic_volumetric", "lambda": 10, "beta": 2, "eta": 0.5},
        "robots": [],
        "robot_avoidance": null
    })
}

fn number(v: f64) -> Value {
    serde_json::Number::from_f64(v).map_or(Value::Null, Value::Number)
}

fn numbers(v: Vec<f64>) -> Value {
    Value::Array(v.into_iter().map(number).collect())
}

/// A scenario built field by field from the small one, numbers of any wildness.
fn structured_scenario() -> impl Strategy<Value = String> {
    (wildness(), 1..=3usize, 0..30usize).prop_flat_map(|(w, d, samples)| {
        let method = prop_oneof![
            Just(json!({"method": "none"})),
            (pos(w), pos(w)).prop_map(|(a, b)| json!({"method": "static_point", "eta": number(a), "p0": number(b)})),
            (pos(w), pos(w))
                .prop_map(|(a, b)| json!({"method": "dynamic_point", "lambda": number(a), "beta": number(b)})),
            (pos(w), pos(w))
                .prop_map(|(a, b)| json!({"method": "steering_angle", "gamma": number(a), "beta": number(b)})),
            (pos(w), pos(w))
                .prop_map(|(a, b)| json!({"method": "static_volumetric", "A": number(a), "eta": number(b)})),
            (pos(w), pos(w), pos(w), any::<bool>()).prop_map(|(a, b, c, rel)| {
                json!({"method": "dynamic_volumetric", "lambda": number(a), "beta": number(b), "eta": number(c),
                       "relative_velocity": rel})
            }),
        ];
        let obstacle = (vec(num(w), d), vec(pos(w), d), vec(pos(w), d), vec(num(w), d)).prop_map(|(c, a, e, v)| {
            json!({"id": "o", "center": numbers(c), "semi_axes": numbers(a), "exponents": numbers(e),
                   "velocity": numbers(v)})
        });
        (
            (0.05..2.0f64).prop_map(move |end| (0..samples).map(|i| end * i as f64 / samples as f64).collect::<Vec<f64>>()),
            vec(vec(num(w), d), samples),
            (prop_oneof![1..30usize, Just(0usize)], pos(w), prop_oneof![Just(None), pos(w).prop_map(Some)], pos(w)),
            (prop_oneof![Just(0.01), pos(w)], prop_oneof![Just(1.0), pos(w)]),
            vec(obstacle, 0..3),
            method,
            prop_oneof![Just(10usize), 0..300usize],
        )
            .prop_map(|(t, x, (n, k, dd, alpha), (dt, duration), obstacles, avoidance, points)| {
                let mut s = small_scenario();
                s["demonstration"] = json!({"t": numbers(t), "x": x.into_iter().map(numbers).collect::<Vec<_>>()});
                s["dmp"] = json!({"N": n, "K": number(k), "D": dd.map(number), "alpha": number(alpha)});
                s["rollout"]["dt"] = number(dt);
                s["rollout"]["duration"] = number(duration);
                s["obstacles"] = Value::Array(obstacles);
                s["avoidance"] = avoidance;
                s["point_samples"] = json!(points);
                s.to_string()
            })
    })
}

/// One scenario case.
#[derive(Debug, Clone)]
pub enum ScenarioText {
    /// A seed, mutated.
    Mutated(Mutated),
    /// A scenario built field by field.
    Structured(String),
    /// Any text.
    Raw(String),
}

#[test]
fn fuzz_scenario_files() {
    let small = small_scenario();
    let seeds: Vec<Vec<u8>> = vec![
        small.to_string().into_bytes(),
        serde_json::to_string_pretty(&small).expect("JSON").into_bytes(),
        include_bytes!("../../../scenarios/paper-one-obstacle/static_point.json").to_vec(),
    ];
    let strategy = prop_oneof![
        4 => mutated(seeds.len()).prop_map(ScenarioText::Mutated),
        4 => structured_scenario().prop_map(ScenarioText::Structured),
        1 => "\\PC{0,60}".prop_map(ScenarioText::Raw),
    ];
    fuzz("scenario_files", 300, 50, strategy, |case| match case {
        ScenarioText::Mutated(m) => check_scenario(&String::from_utf8_lossy(&m.bytes(&seeds))),
        ScenarioText::Structured(s) | ScenarioText::Raw(s) => check_scenario(&s),
    });
}

/// The checks of one CSV text: an accepted demonstration is finite, rectangular and has two samples or more.
pub fn check_csv(text: &str) -> TestCaseResult {
    let Ok(d) = parse_demonstration_csv(text, Path::new("fuzz.csv")) else { return Ok(()) };
    prop_assert!(d.t.len() >= 2 && d.t.len() == d.x.len());
    all_finite("t", &d.t)?;
    let width = d.x[0].len();
    prop_assert!(width >= 1);
    for row in &d.x {
        prop_assert_eq!(row.len(), width);
        all_finite("x", row)?;
    }
    Ok(())
}

/// A CSV text built row by row: a header or not, numbers of any wildness, comments and blank lines.
fn structured_csv() -> impl Strategy<Value = String> {
    let header = prop_oneof![
        Just(String::new()),
        Just("t,x1,x2\n".to_owned()),
        Just("t,x2,x1,xd1\n".to_owned()),
        Just("time, a, b\n".to_owned()),
        Just("t\n".to_owned()),
        "[a-z0-9,x]{0,12}\n",
    ];
    let cell = prop_oneof![
        8 => num(5).prop_map(|v| v.to_string()),
        1 => extreme().prop_map(|v| format!("{v:e}")),
        1 => prop_oneof![Just("nan"), Just("inf"), Just("-inf"), Just(""), Just(" "), Just("1e999"), Just("0x1")]
            .prop_map(str::to_owned),
    ];
    let row = vec(cell, 1..=4).prop_map(|cells| cells.join(","));
    let line = prop_oneof![8 => row, 1 => Just("# comment".to_owned()), 1 => Just(String::new())];
    (header, vec(line, 0..12)).prop_map(|(h, lines)| format!("{h}{}", lines.join("\n")))
}

#[test]
fn fuzz_demonstration_csv() {
    let seeds: Vec<Vec<u8>> = vec![
        b"t,x1,x2\n0,0,1\n0.5,0.25,1.5\n1,1,2\n".to_vec(),
        b"# by hand\n\n0,5\n1,6\n".to_vec(),
        b"t,x1,x2,xd1,xd2,a1,a2\n0,0,0,0,0,9,9\n0.001,1e-6,2e-6,1,1,9,9\n".to_vec(),
    ];
    let strategy = prop_oneof![
        3 => mutated(seeds.len()).prop_map(|m| (Some(m), String::new())),
        3 => structured_csv().prop_map(|s| (None, s)),
        1 => "\\PC{0,40}".prop_map(|s| (None, s)),
    ];
    fuzz("demonstration_csv", 3000, 1000, strategy, |(m, text)| match m {
        Some(m) => check_csv(&String::from_utf8_lossy(&m.bytes(&seeds))),
        None => check_csv(&text),
    });
}
