//! `dmpctl`'s commands against the real server (gRPC only), through the same entry point as the binary.

use std::path::Path;

use clap::Parser;
use dmp_tests::{TestServer, within};
use dmpctl::DmpctlError;
use dmpctl::cli::{Cli, run_async};

/// The summary of a run that completed with problems (exit code 3), one of which contains `problem`.
fn problems_summary(e: DmpctlError, problem: &str) -> String {
    assert_eq!(e.exit_code(), 3, "{e}");
    match e {
        DmpctlError::Problems { summary, problems } => {
            assert!(problems.iter().any(|p| p.contains(problem)), "{problems:?}");
            summary
        }
        e => panic!("{e}"),
    }
}

/// Runs `dmpctl --server URL ARGS...` (under the tests' timeout).
async fn run_at(url: &str, args: &[&str]) -> Result<String, DmpctlError> {
    let mut all = vec!["dmpctl", "--server", url];
    all.extend_from_slice(args);
    let cli = Cli::try_parse_from(&all).unwrap_or_else(|e| panic!("{all:?}: {e}"));
    within(&all.join(" "), run_async(cli)).await
}

#[tokio::test(flavor = "multi_thread")]
async fn server_commands_against_the_server() {
    let server = TestServer::grpc_only().await;
    let url = server.url();
    let dir = tempfile::tempdir().unwrap();
    let d = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let csv: String = std::iter::once("t,x1,x2".to_string())
        .chain((0..=100).map(|k| {
            let t = k as f64 / 100.0;
            format!("{t},{},{}", t * t, 1.0 - t)
        }))
        .collect::<Vec<_>>()
        .join("\n");
    std::fs::write(d("demo.csv"), csv).unwrap();

    let out =
        run_at(&url, &["learn", "--robot", "r", "--name", "p", "--csv", &d("demo.csv"), "--n-basis", "15"])
            .await
            .unwrap();
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(
        (v["version"].as_u64(), v["dim"].as_u64(), v["n_basis"].as_u64()),
        (Some(1), Some(2), Some(15))
    );
    let scenario = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/paper-one-obstacle/none.json");
    run_at(&url, &["learn", "--robot", "r", "--name", "paper", "--scenario", scenario.to_str().unwrap()])
        .await
        .unwrap();
    let listed = run_at(&url, &["list", "--robot", "r"]).await.unwrap();
    assert!(listed.starts_with("p\tv1\tdim 2\tN 15") && listed.contains("\npaper\tv1"), "{listed}");

    let shown: serde_json::Value =
        serde_json::from_str(&run_at(&url, &["show", "--robot", "r", "--name", "p"]).await.unwrap()).unwrap();
    let p: dmp::Primitive = serde_json::from_value(shown["primitive"].clone()).unwrap();
    assert_eq!(p.n_basis, 15);

    let said = run_at(
        &url,
        &[
            "plan",
            "--robot",
            "r",
            "--name",
            "p",
            "--goal",
            "2,-1",
            "--duration-s",
            "1.5",
            // The DMP's own timing, which the checks below are about.
            "--no-limits",
            "--out",
            &d("plan"),
        ],
    )
    .await
    .map_or_else(|e| problems_summary(e, "goal not reached: ended "), |ok| panic!("exit 0: {ok}"));
    // Not at the goal and at rest to within 1 mm at 1.5 s: out of time, exit 3, the outputs written all the same.
    assert!(said.contains("1501 points") && said.contains("verdict OUT_OF_TIME"), "{said}");
    let plan = std::fs::read_to_string(dir.path().join("plan/trajectory.csv")).unwrap();
    assert_eq!(plan.lines().next(), Some("t,x1,x2,xd1,xd2,a1,a2"));
    assert_eq!(plan.lines().count(), 1502);
    let last: Vec<f64> = plan.lines().last().unwrap().split(',').map(|c| c.parse().unwrap()).collect();
    assert!((last[1] - 2.0).abs() < 0.05 && (last[2] + 1.0).abs() < 0.05, "{last:?}");

    let said = run_at(
        &url,
        &[
            "stream",
            "--robot",
            "r",
            "--name",
            "p",
            "--goal",
            "2,-1",
            "--max-duration-s",
            "1.5",
            "--no-limits",
            "--out",
            &d("stream"),
        ],
    )
    .await
    .unwrap_err();
    // 1501 points in segments of 10, the last one the point at 1.5 s; the goal is not reached to within 1 mm
    // by then, so the run ends at its maximum duration: out of time, exit 3.
    assert_eq!(said.exit_code(), 3, "{said}");
    let said = said.to_string();
    assert!(
        said.contains("151 segments, 1501 setpoints in force up to t = 1.5 s, last status STOPPED")
            && said.contains("verdict OUT_OF_TIME")
            && said.contains("goal not reached: ended "),
        "{said}"
    );
    let streamed = std::fs::read_to_string(dir.path().join("stream/trajectory.csv")).unwrap();
    assert_eq!(streamed.lines().count(), plan.lines().count());
    // With a looser "at the goal and at rest", the same motion arrives, and says since when.
    let loose = [
        "stream",
        "--robot",
        "r",
        "--name",
        "p",
        "--goal",
        "2,-1",
        "--goal-tolerance",
        "0.05",
        "--goal-speed-tolerance",
        "0.5",
        "--max-duration-s",
        "5",
        "--no-limits",
        "--out",
        &d("loose"),
    ];
    let said = run_at(&url, &loose).await.unwrap();
    let since: f64 = said
        .split("at the goal and at rest since t = ")
        .nth(1)
        .and_then(|rest| rest.split(' ').next())
        .unwrap_or_else(|| panic!("{said}"))
        .parse()
        .unwrap();
    assert!(said.contains("last status GOAL_REACHED") && since > 0.5 && since < 1.5, "{said}");
    let mut bad = vec!["dmpctl", "--server", &url];
    bad.extend_from_slice(&loose);
    bad[11] = "0";
    let e = Cli::try_parse_from(&bad).unwrap_err().to_string();
    assert!(e.contains("--goal-tolerance") && e.contains("greater than zero"), "{e}");
    // Both write their figure too: the run and the obstacle-free plan of the same motion, under their title.
    for what in ["plan", "stream"] {
        let svg = std::fs::read_to_string(dir.path().join(what).join("plot.svg")).unwrap();
        let doc = roxmltree::Document::parse(&svg).unwrap();
        let title = format!("r/p: {what}");
        assert!(doc.descendants().any(|n| n.has_tag_name("text") && n.text().map(str::trim) == Some(&title)));
        for class in ["path-free", "path-adapted", "speed", "clearance"] {
            let g = doc.descendants().find(|n| n.attribute("class") == Some(class));
            assert!(
                g.is_some_and(|g| g.descendants().any(|n| n.has_tag_name("polyline"))),
                "{what}: {class}"
            );
        }
    }

    // The paper's run without avoidance collides, as it is meant to: exit 3 unless allowed.
    let e = run_at(&url, &["scenario", "run", scenario.to_str().unwrap(), "--out", &d("scenario")])
        .await
        .unwrap_err();
    assert_eq!(e.exit_code(), 3, "{e}");
    assert!(e.to_string().contains("collision: true") && e.to_string().contains("--allow-collision"), "{e}");
    let run = run_at(
        &url,
        &["scenario", "run", scenario.to_str().unwrap(), "--out", &d("scenario"), "--allow-collision"],
    )
    .await
    .unwrap();
    assert!(run.contains("through http://"), "{run}");
    assert!(dir.path().join("scenario/metrics.json").exists());

    assert_eq!(
        run_at(&url, &["delete", "--robot", "r", "--name", "p"]).await.unwrap(),
        "deleted 1 version of r/p"
    );
    let e = run_at(&url, &["show", "--robot", "r", "--name", "p"]).await.unwrap_err();
    assert!(e.is_bad_input() && e.to_string().contains("NotFound"), "{e}");
    let e = run_at(&url, &["plan", "--robot", "r", "--name", "nothing", "--out", &d("x")]).await.unwrap_err();
    assert!(e.is_bad_input(), "{e}");
    let e = run_at(&url, &["learn", "--robot", "r", "--name", "p", "--csv", &d("missing.csv")])
        .await
        .unwrap_err();
    assert!(!e.is_bad_input() && e.to_string().contains("missing.csv"), "{e}");
    server.stop().await;
}

/// One cell per command, for the scene and the motions alike: `--cell`, checked against the naming rule, else the
/// server's own default cell (GetInfo).
#[tokio::test(flavor = "multi_thread")]
async fn every_command_acts_in_its_one_cell() {
    let server = TestServer::start_with(|c| {
        c.zenoh.disabled = true;
        c.cell = "bar".into();
    })
    .await;
    let url = server.url();
    let dir = tempfile::tempdir().unwrap();
    let box_file = dir.path().join("box.json");
    std::fs::write(&box_file, r#"{"id": "crate", "center": [0.5, 0.12], "semi_axes": [0.1, 0.1]}"#).unwrap();
    let file = box_file.to_str().unwrap();

    let info: serde_json::Value = serde_json::from_str(&run_at(&url, &["info"]).await.unwrap()).unwrap();
    assert_eq!(info["cell"], "bar");
    let limits = &server.handle().config().limits;
    assert_eq!(info["limits"]["max_obstacles"], limits.max_obstacles as u64);
    assert_eq!(info["zenoh_locators"], serde_json::json!([]), "no Zenoh here");
    let stats: serde_json::Value = serde_json::from_str(&run_at(&url, &["stats"]).await.unwrap()).unwrap();
    assert!(
        stats["uptime_s"].as_f64().unwrap() > 0.0 && stats["realtime_work_budget"].as_f64().unwrap() > 0.0
    );
    let health = run_at(&url, &["health"]).await.unwrap();
    assert_eq!(health.lines().count(), 6, "{health}");
    assert!(health.lines().all(|l| l.ends_with("\tSERVING")), "{health}");

    run_at(&url, &["--cell", "lab2", "scene", "put", file]).await.unwrap();
    let lab2 = run_at(&url, &["--cell", "lab2", "scene", "list"]).await.unwrap();
    assert!(lab2.contains("crate"), "{lab2}");
    // Without --cell, the server's default cell (bar), which is empty.
    let default = run_at(&url, &["scene", "list"]).await.unwrap();
    assert!(!default.contains("crate"), "{default}");
    let bar = server.handle().cells().find("bar").unwrap().unwrap();
    assert!(bar.snapshot().obstacles.is_empty());

    // A bad name is refused before anything is sent, with the rule.
    let e = run_at(&url, &["--cell", "bad cell!", "scene", "put", file]).await.unwrap_err();
    assert!(e.is_bad_input(), "{e}");
    assert!(e.to_string().contains("--cell") && e.to_string().contains("only letters, digits"), "{e}");
    assert!(!matches!(server.handle().cells().find("bad cell!"), Ok(Some(_))));

    // Motions go to the command's cell: the box in lab2 bends a plan there, not one in the default cell.
    let csv: String = std::iter::once("t,x1,x2".to_string())
        .chain((0..=100).map(|k| format!("{},{},0", k as f64 / 100.0, k as f64 / 100.0)))
        .collect::<Vec<_>>()
        .join("\n");
    std::fs::write(dir.path().join("line.csv"), csv).unwrap();
    let line_csv = dir.path().join("line.csv");
    run_at(&url, &["learn", "--robot", "r", "--name", "line", "--csv", line_csv.to_str().unwrap()])
        .await
        .unwrap();
    let deviation = |out: &str| {
        let plan = std::fs::read_to_string(dir.path().join(out).join("trajectory.csv")).unwrap();
        plan.lines()
            .skip(1)
            .map(|l| l.split(',').nth(2).unwrap().parse::<f64>().unwrap().abs())
            .fold(0.0, f64::max)
    };
    // A typo in the cell is refused (exit 2), naming the known cells, not planned in a new, empty scene.
    let typo_dir = dir.path().join("plan-typo");
    let typo = ["--cell", "lba2", "plan", "--robot", "r", "--name", "line", "--duration", "2", "--out"];
    let e = run_at(&url, &[&typo[..], &[typo_dir.to_str().unwrap()]].concat()).await.unwrap_err();
    assert_eq!(e.exit_code(), 2, "{e}");
    assert!(e.to_string().contains("unknown cell `lba2`: known cells are `bar`, `lab2` ("), "{e}");
    assert!(
        server.handle().cells().find("lba2").unwrap().is_none() && !typo_dir.join("trajectory.csv").exists()
    );
    for (cell, out) in [(None, "plan-default"), (Some("lab2"), "plan-lab2")] {
        let mut args = Vec::new();
        if let Some(c) = cell {
            args.extend(["--cell", c]);
        }
        let out_dir = dir.path().join(out);
        args.extend([
            "plan",
            "--robot",
            "r",
            "--name",
            "line",
            "--duration",
            "2",
            // The DMP's own line, which the deviations below compare.
            "--no-limits",
            // At 2 s the line is 2 mm short of its goal: within this tolerance, the plan reaches it (exit 0).
            "--goal-tolerance",
            "0.01",
            "--goal-speed-tolerance",
            "0.1",
            "--out",
            out_dir.to_str().unwrap(),
        ]);
        run_at(&url, &args).await.unwrap();
    }
    assert!(deviation("plan-default") < 1e-9, "the default cell has no obstacle");
    let bent = deviation("plan-lab2");
    assert!(bent > 1e-3, "the plan in lab2 did not go round its box: {bent}");
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread")]
async fn robots_lists_every_robot_that_has_primitives() {
    let server = TestServer::grpc_only().await;
    let url = server.url();
    assert_eq!(
        run_at(&url, &["robots"]).await.unwrap(),
        "no robot has primitives (that this client may read)"
    );
    let scenario = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/paper-one-obstacle/none.json");
    let scenario = scenario.to_str().unwrap();
    for (robot, name) in [("panda", "reach"), ("panda", "place"), ("panda", "place"), ("sim.youbot1", "line")]
    {
        run_at(&url, &["learn", "--robot", robot, "--name", name, "--scenario", scenario]).await.unwrap();
    }
    let said = run_at(&url, &["robots"]).await.unwrap();
    let lines: Vec<&str> = said.lines().collect();
    assert_eq!(lines.len(), 2, "{said}");
    // One line per robot, sorted, with its number of primitives (names, not versions) and a readable time.
    assert!(lines[0].starts_with("panda ") && lines[0].contains(" 2 primitives  updated 20"), "{said}");
    assert!(lines[1].starts_with("sim.youbot1 ") && lines[1].contains(" 1 primitive  updated 20"), "{said}");
    assert!(lines.iter().all(|l| l.ends_with('Z')), "{said}");
    server.stop().await;
}
