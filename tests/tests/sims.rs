//! The simulated robots (`dmp_sim::robots`) against the real server, in-process on 127.0.0.1:0 with Zenoh on
//! loopback (multicast off). Each asserts what the issue asks of every simulation: goals reached, no contact with
//! any true shape or other robot, nothing non-finite, continuous setpoints. Every await is under a timeout.

use dmp_sim::robots::{SimName, SimOptions, SimReport, run, run_with};
use dmp_tests::{TestServer, within};

/// Starts a server, runs `name` against it (simulated clock), shuts the server down; returns the report and
/// checks that the report, the figures and the page were written.
async fn simulate(name: SimName) -> SimReport {
    simulate_then(name, |_| {}).await
}

/// The classes every figure of a simulation has: both shapes of the obstacles, both runs, the time strip.
const FIGURE_CLASSES: [&str; 7] =
    ["obstacle-true", "isopotential", "path-free", "path-adapted", "speed", "acceleration", "clearance"];

/// [`simulate`], then `inspect` on the output folder before it is removed.
async fn simulate_then(name: SimName, inspect: impl FnOnce(&std::path::Path)) -> SimReport {
    let server = TestServer::start().await;
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let options = SimOptions {
        realtime: false,
        out: out.clone(),
        zenoh_connect: server.handle().zenoh_locators.clone(),
        cell: "default".into(),
        zenoh_config: None,
        tokens: None,
        keep: false,
    };
    let report = within("simulation", run(&server.url(), name, &options)).await.expect("the simulation runs");
    // The simulation's robots are its own (`sim.<name>`), and it deleted their primitives when it ended.
    let client = server.client().await;
    for robot in name.robot_ids() {
        assert!(robot.starts_with("sim."), "{robot}");
        assert!(
            within("list", client.list(&robot)).await.unwrap().is_empty(),
            "{robot}'s primitives are left"
        );
    }
    server.stop().await;
    let written: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(written["collision"], serde_json::Value::Bool(report.collision));
    for plot in &report.plots {
        let svg = std::fs::read_to_string(out.join(plot)).unwrap();
        let doc = roxmltree::Document::parse(&svg).unwrap_or_else(|e| panic!("{plot} is not XML: {e}"));
        assert!(doc.root_element().has_tag_name("svg"), "{plot} is not an SVG");
        for class in FIGURE_CLASSES {
            let drawn =
                doc.descendants().filter(|n| n.attribute("class") == Some(class)).any(|g| g.has_children());
            assert!(drawn, "{plot}: nothing of class {class}");
        }
    }
    // One page with every figure inline, a verdict per check, and nothing to fetch.
    let page = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert_eq!(page.matches("<svg").count(), report.plots.len());
    let cells = page.matches("<td class=\"pass\">").count() + page.matches("<td class=\"fail\">").count();
    assert!(cells >= 5 * report.robots.len(), "{cells} verdicts for {} robots", report.robots.len());
    assert_eq!(page.replace("xmlns=\"http://www.w3.org/2000/svg\"", "").matches("http").count(), 0, "a URL");
    inspect(&out);
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
        // A robot that runs with a limit profile (in its robot record) has no setpoint over it.
        assert_eq!(r.limit_violations, 0, "{id}: setpoints over the profile {:?}", r.profile);
        assert!(r.finite_difference_peaks.peak_speed > 0.0, "{id}");
        assert!(r.peak_acceleration.is_finite(), "{id}");
        for (o, d) in &r.min_clearance_m {
            assert!(d.is_finite() && *d > 0.0, "{id}: clearance to {o} is {d}");
        }
    }
}

#[tokio::test(flavor = "multi_thread")]
async fn panda_picks_and_places_past_the_red_peg() {
    use dmp_sim::robots::pose::angle_deg;
    use dmp_sim::robots::{panda, panda_bar};
    let report = simulate_then(SimName::Panda, |out| {
        // The page opens from the disk in a browser: not blank, no console message.
        let shot = dmp_tests::browser::open(&out.join("report.html"), (1400, 4000));
        assert!(shot.console.is_empty(), "console: {:#?}", shot.console);
        assert_eq!(shot.size, (1400, 4000));
        assert!(shot.luminance_variance > 100.0 && shot.ink > 0.02, "blank page? {shot:?}");
    })
    .await;
    assert_clean(&report);
    assert_eq!(report.robots.len(), 4);
    assert_eq!(report.plots.len(), 4);
    for (id, r) in &report.robots {
        assert_eq!(r.late_setpoints, 0, "{id}");
        assert_pose_within_panda(id, r);
        assert!(r.setpoints >= 1000, "{id}: {} setpoints at 1 kHz", r.setpoints);
        // What a real Panda would accept: it runs with the PANDA profile in its robot record.
        assert_eq!(r.profile, Some(dmp::Limits::PANDA), "{id}");
        assert!(r.peak_speed <= panda::MAX_SPEED, "{id}: peak speed {} m/s", r.peak_speed);
        assert!(r.peak_acceleration <= panda::MAX_ACCELERATION, "{id}: {} m/s^2", r.peak_acceleration);
        assert!(r.peak_jerk <= panda::MAX_JERK, "{id}: peak jerk {} m/s^3", r.peak_jerk);
    }
    // Both carries go past the red peg without touching it with the ring's true disc, turned as it is carried.
    for key in ["panda/carry-static", "panda/carry-dynamic"] {
        let d = report.robots[key].min_clearance_m["red-peg"];
        assert!(d > 0.0 && d < 0.1, "{key}: clearance to the red peg {d}");
        let pose = report.robots[key].pose.as_ref().unwrap();
        assert!(pose.body.contains("ring"), "{key}: {}", pose.body);
        // From upright on its stand to flat over the green peg, turned 30° about z: 93.8° between them.
        let turn = angle_deg(&panda::Q_GRASP, &panda::Q_PLACE);
        assert!((pose.max_turn_from_start_deg - turn).abs() < 1.0, "{key}: turned {pose:?}");
    }
    let reach = report.robots["panda/move-to-ring"].pose.as_ref().unwrap();
    assert!((reach.max_turn_from_start_deg - 90.0).abs() < 1.0, "{reach:?}");
    // The bar passes the gap only turned: its true box stays clear of both true rails, and it turns past the angle
    // where its axis clears the rails' nearest edges (`a sin(phi) - b cos(phi) = t`, a = the gap's half-width, b
    // a rail's half-height, t the bar's half-thickness: 17.5°; held as it starts, 10° off across, it would cut
    // them).
    let bar = &report.robots["panda/carry-bar"];
    let pose = bar.pose.as_ref().unwrap();
    assert!(pose.body.contains("bar"), "{}", pose.body);
    for rail in ["rail-left", "rail-right"] {
        let d = bar.min_clearance_m[rail];
        assert!(d > 0.0 && d < 0.2, "the bar's clearance to {rail} is {d}");
    }
    let (a, b, t) = (panda_bar::GAP / 2.0, panda_bar::RAIL_HALF[2], panda_bar::BAR_HALF_THICKNESS);
    let clears = (b.atan2(a) + (t / a.hypot(b)).asin()).to_degrees();
    assert!((17.0..18.0).contains(&clears), "{clears}");
    assert!(
        pose.max_turn_from_start_deg > clears - 10.0,
        "the bar turned {pose:?}, needs {}°",
        clears - 10.0
    );
}

/// A pose run of the Panda: it ends at its goal orientation and its angular setpoints stay within the Panda's
/// angular limits (finite differences at 1 kHz, as the linear ones), counted in its limit violations.
fn assert_pose_within_panda(id: &str, r: &dmp_sim::robots::RobotReport) {
    let limits = dmp::Limits::PANDA;
    let pose = r.pose.as_ref().unwrap_or_else(|| panic!("{id}: not a pose run"));
    assert!(pose.final_orientation_error_deg <= 0.1, "{id}: {pose:?}");
    assert_eq!(pose.angular_limit_violations, 0, "{id}: {pose:?}");
    assert!(pose.peak_angular_speed > 0.0, "{id}: it turns");
    assert!(pose.peak_angular_speed <= limits.max_angular_speed * (1.0 + 1e-6), "{id}: {pose:?}");
    assert!(
        pose.peak_angular_acceleration <= limits.max_angular_acceleration * (1.0 + 1e-6),
        "{id}: {pose:?}"
    );
    assert!(pose.peak_angular_jerk <= limits.max_angular_jerk * (1.0 + 1e-6), "{id}: {pose:?}");
    // The streamed angular velocities agree with the orientations' finite differences.
    assert!((pose.streamed_peak_angular_speed - pose.peak_angular_speed).abs() < 0.01, "{id}: {pose:?}");
    assert!(pose.min_body_clearance_m > 0.0 && pose.min_body_clearance_m.is_finite(), "{id}: {pose:?}");
}

#[tokio::test(flavor = "multi_thread")]
async fn youbot_avoids_a_box_published_by_a_perception_node() {
    let report = simulate(SimName::YoubotPerception).await;
    assert_clean(&report);
    assert_eq!(report.robots.len(), 4);
    // Plausible for a youBot: accelerations of a few m/s^2, even going round the box.
    for (key, r) in &report.robots {
        assert!(r.peak_acceleration < 10.0, "{key}: peak acceleration {} m/s^2", r.peak_acceleration);
    }
    // The box that stays is avoided (it is in the robot's way).
    for key in ["youbot/added-static", "youbot/added-dynamic"] {
        let d = report.robots[key].min_clearance_m["box"];
        assert!(d > 0.0 && d < 0.5, "{key}: clearance to the box {d}");
    }
    let m = |k: &str| report.metrics[k];
    for method in ["static", "dynamic"] {
        // The permanent box bends the path; the temporary one, removed before the robot reaches it, bends it
        // less (within the youBot's limits, by a few hundredths of a millimetre: the robot responds to it only
        // while it is there), and past it the path is back near the straight line (exactly 0 without a box).
        let added = m(&format!("youbot/added-{method}/max_abs_y_m"));
        let temporary = m(&format!("youbot/temporary-{method}/max_abs_y_m"));
        let back = m(&format!("youbot/temporary-{method}/max_abs_y_past_box_m"));
        assert!(added > 0.2, "{method}: the box bent the path by only {added}");
        assert!(
            temporary > 1e-5 && temporary < added,
            "{method}: the temporary box bent the path by {temporary}"
        );
        assert!(back < 0.1 * temporary, "{method}: {back} from the line past the removed box");
    }
}

#[tokio::test(flavor = "multi_thread")]
async fn psm_arms_hand_the_ring_over_and_place_it_on_the_peg() {
    use dmp_sim::robots::pose::angle_deg;
    use dmp_sim::robots::{psm, psm_stage};
    let wall = std::time::Instant::now();
    let report = simulate(SimName::Psm).await;
    println!("psm: {:.2} s of wall clock", wall.elapsed().as_secs_f64());
    let m = |k: &str| *report.metrics.get(k).unwrap_or_else(|| panic!("no metric {k}"));
    assert_clean(&report);
    assert_eq!(report.robots.len(), 6);
    // A figure per stage, and one per arm of each stage where the jaws turn.
    assert_eq!(report.plots.len(), 7);
    for (id, r) in &report.robots {
        assert_eq!(r.late_setpoints, 0, "{id}");
        assert!(r.setpoints >= 1000, "{id}: {} setpoints at 1 kHz", r.setpoints);
        // Each arm is measured against the other one's jaws, and every peg.
        let other = if id.starts_with("psm1/") { "psm2" } else { "psm1" };
        for o in [other, "peg-1", "peg-2", "target-peg", "board"] {
            assert!(r.min_clearance_m.contains_key(o), "{id}: no clearance to {o}");
        }
    }
    // The handover: both tips a few mm from the centre when the ring changes hands (their goals are
    // HANDOVER_OFFSET from it, and the server's arrival tolerance is 1 mm).
    const { assert!(psm::HANDOVER_OFFSET <= 0.005) };
    for arm in ["psm1", "psm2"] {
        let d = m(&format!("handover/{arm}_to_centre_m"));
        assert!(d < psm::HANDOVER_OFFSET + 0.001, "{arm} is {d} m from the centre at the handover");
    }
    // The ring ends on the target peg: its hole over the peg's axis, just above the top, when it is released.
    let offset = m("ring/offset_from_peg_axis_m");
    assert!(offset < psm::RING_INNER_RADIUS - psm::PEG_RADIUS, "ring {offset} m off the peg's axis");
    let height = m("ring/height_above_peg_top_m");
    assert!(height > 0.0 && height < 0.015, "ring released {height} m above the peg");
    assert!(m("ring/released_at_s") > m("handover/time_s"));
    // Avoidance was needed: without it the carried ring hits a peg (and the path moved), and without the robot
    // term the jaws hit each other when the arms cross after the handover (with it they clear, assert_clean).
    for (key, peg) in [("psm1/transfer", "peg-1"), ("psm2/move-to-peg", "peg-2")] {
        let free = m(&format!("{key}/free_min_clearance_m/{peg}"));
        assert!(free <= 0.0, "{key}: the free plan clears {peg} by {free} m");
        let deviation = m(&format!("{key}/max_deviation_from_free_m"));
        assert!(deviation > 0.002, "{key}: avoidance moved the path by only {deviation} m");
    }
    for (key, other) in [("psm1/move-to-peg", "psm2"), ("psm2/move-to-peg", "psm1")] {
        let without = m(&format!("{key}/no_robot_term_min_clearance_m/{other}"));
        assert!(without <= 0.0, "{key}: without the robot term the jaws clear {other} by {without} m");
        assert!(report.robots[key].min_clearance_m[other] > 0.001, "{key}: too close to {other}");
    }
    // The simulated task takes a few seconds.
    assert!(m("ring/released_at_s") < 10.0);
    // The jaws turn towards the handover: pose runs (the server runs a pose primitive alone, so these stages are
    // two runs each) that end at their goal orientations within the PSM's angular limits; the crossing after the
    // handover stays on one phase, the jaws held.
    let limits = dmp::Limits::DVRK_PSM;
    let turns = [
        ("psm1/move-to-ring", psm_stage::Q_HOME, psm_stage::q_grasp()),
        ("psm2/move-to-ring", psm_stage::Q_HOME, psm_stage::q_standby()),
        ("psm1/transfer", psm_stage::q_grasp(), psm_stage::q_handover(0)),
        ("psm2/transfer", psm_stage::q_standby(), psm_stage::q_handover(1)),
    ];
    for (key, from, to) in turns {
        let p = report.robots[key].pose.as_ref().unwrap_or_else(|| panic!("{key}: not a pose run"));
        assert!(p.final_orientation_error_deg <= 0.1, "{key}: {p:?}");
        assert_eq!(p.goal_orientation, to, "{key}");
        let turn = angle_deg(&from, &to);
        assert!(
            turn > 40.0 && (p.max_turn_from_start_deg - turn).abs() < 1.0,
            "{key}: {turn}° planned, {p:?}"
        );
        assert_eq!(p.angular_limit_violations, 0, "{key}: {p:?}");
        assert!(p.peak_angular_speed <= limits.max_angular_speed * (1.0 + 1e-6), "{key}: {p:?}");
        assert!(
            p.peak_angular_acceleration <= limits.max_angular_acceleration * (1.0 + 1e-6),
            "{key}: {p:?}"
        );
        assert!(p.peak_angular_jerk <= limits.max_angular_jerk * (1.0 + 1e-6), "{key}: {p:?}");
        assert!(p.min_body_clearance_m > 0.0, "{key}: {p:?}");
    }
    assert!(
        report.robots["psm1/move-to-peg"].pose.is_none() && report.robots["psm2/move-to-peg"].pose.is_none()
    );
}

#[tokio::test(flavor = "multi_thread")]
async fn youbots_avoid_each_other_and_the_cubes_on_one_phase() {
    let wall = std::time::Instant::now();
    let report = simulate(SimName::Youbots).await;
    println!("youbots: {:.2} s of wall clock", wall.elapsed().as_secs_f64());
    assert_clean(&report);
    // Two primitives (null weights, constant speed) x two potentials for the walls and cubes, three robots each.
    assert_eq!(report.robots.len(), 12);
    assert_eq!(report.plots.len(), 4);
    let m = |k: &str| *report.metrics.get(k).unwrap_or_else(|| panic!("no metric {k}"));
    let ids = ["youbot1", "youbot2", "youbot3"];
    let blocks = ["wall-south", "wall-north", "wall-west", "wall-east", "cube-a", "cube-b", "cube-c"];
    for (key, r) in &report.robots {
        let me = key.split('/').next().unwrap();
        assert_eq!(r.late_setpoints, 0, "{key}");
        // Measured against every wall and cube and both other robots.
        for o in blocks.iter().chain(&ids).filter(|o| **o != me) {
            let d = r.min_clearance_m.get(*o).unwrap_or_else(|| panic!("{key}: no clearance to {o}"));
            // The margins on top of the robot's size keep a few centimetres of air.
            assert!(*d > 0.02, "{key}: {d} m from {o}");
        }
        // Plausible for a youBot: within its top speed of 0.8 m/s, and accelerations of a few m/s^2.
        assert!(r.peak_acceleration < 10.0, "{key}: peak acceleration {} m/s^2", r.peak_acceleration);
        assert!(r.peak_speed < 0.8, "{key}: peak speed {} m/s", r.peak_speed);
    }
    for run in ["line-static", "line-dynamic", "constant-speed-static", "constant-speed-dynamic"] {
        // Avoiding was needed: on the free plans every robot touches a cube, and two robots (youbot1 and
        // youbot2, head-on) touch each other.
        for id in ids {
            let free = m(&format!("youbots/{run}/free_min_cube_clearance_m/{id}"));
            assert_eq!(free, 0.0, "{run}: {id}'s free plan clears the cubes by {free} m");
        }
        assert_eq!(m(&format!("youbots/{run}/free_min_robot_clearance_m")), 0.0, "{run}");
        // The simulated runs take under a minute.
        assert!(report.robots[&format!("youbot1/{run}")].duration_s < 60.0, "{run}");
    }
}

/// A secured cell (`access init`: TLS, an access file, mutual TLS on Zenoh): the set-up runs as the planner, each
/// robot streams with its own token, and the perception node publishes with the cell's perception config.
#[tokio::test(flavor = "multi_thread")]
async fn sims_run_against_a_secured_server_each_robot_with_its_own_token() {
    use dmp_client::connect::{ConnectOptions, TlsOptions};
    use dmp_server::access::init::{InitOptions, init};
    let set = tempfile::tempdir().unwrap();
    let s = set.path();
    // The access file names the simulations' robots as the server knows them.
    let robots = ["sim.panda", "sim.youbot-static", "sim.youbot-dynamic"].map(String::from).to_vec();
    let tokens =
        init(s, &InitOptions { cells: vec!["default".into()], robots, ..Default::default() }).unwrap().tokens;
    let server = TestServer::start_with(|c| {
        dmp_tests::secure(c, s);
    })
    .await;
    let url = format!("https://{}", server.handle().grpc_addr);
    let planner = tokens.iter().find(|(n, _)| n == "planner").unwrap().1.clone();
    let tls = TlsOptions::from_files(&s.join("ca.pem"), None, None).unwrap();
    let connect = ConnectOptions { tls: Some(tls), token: Some(planner), ..Default::default() };
    let locators: Vec<String> =
        server.handle().zenoh_locators.iter().filter(|l| l.starts_with("tls/")).cloned().collect();
    let dir = tempfile::tempdir().unwrap();
    let options = |tokens: &std::path::Path| SimOptions {
        realtime: false,
        out: dir.path().join("out"),
        zenoh_connect: locators.clone(),
        cell: "default".into(),
        zenoh_config: Some(s.join("zenoh-perception.json5")),
        tokens: Some(tokens.to_owned()),
        keep: false,
    };

    // With another robot's token, the Panda's stream is refused: each robot streams as itself.
    let swapped = tempfile::tempdir().unwrap();
    std::fs::copy(s.join("sim.youbot-static.token"), swapped.path().join("sim.panda.token")).unwrap();
    let refused = within("simulation", run_with(&url, &connect, SimName::Panda, &options(swapped.path())))
        .await
        .expect_err("streamed with another robot's token");
    assert!(refused.to_string().contains("(robot) may not execute robot `sim.panda`"), "{refused}");

    let report = within("simulation", run_with(&url, &connect, SimName::YoubotPerception, &options(s)))
        .await
        .expect("the simulation runs");
    assert_clean(&report);
    assert_eq!(report.robots.len(), 4);
    for key in ["youbot/added-static", "youbot/added-dynamic"] {
        let d = report.robots[key].min_clearance_m["box"];
        assert!(d > 0.0 && d < 0.5, "{key}: clearance to the box {d}");
    }
    server.stop().await;
}

/// `dmpctl sim` given neither `--cell` nor `--zenoh-connect` asks the server (GetInfo): its robots stream in the
/// server's default cell and its perception node publishes there, through the server's own Zenoh locators.
#[tokio::test(flavor = "multi_thread")]
async fn dmpctl_sim_acts_in_the_servers_cell_without_flags() {
    use clap::Parser;
    let server = TestServer::start_with(|c| c.cell = "bar".into()).await;
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let url = server.url();
    let args = ["dmpctl", "--server", &url, "sim", "youbot-perception", "--out", out.to_str().unwrap()];
    let cli = dmpctl::cli::Cli::try_parse_from(args).unwrap();
    // This simulation runs in real time: on a loaded machine some setpoints may be late, which dmpctl reports as
    // a problem (exit 3). Anything else is a failure.
    let said = match within("dmpctl sim", dmpctl::cli::run_async(cli)).await {
        Ok(said) => said,
        Err(dmpctl::DmpctlError::Problems { summary, problems })
            if problems.iter().all(|p| p.ends_with("late setpoints")) =>
        {
            summary
        }
        Err(e) => panic!("{e}"),
    };
    assert!(said.contains("collision: false"), "{said}");
    // One youBot, several runs: the summary counts them apart.
    assert!(said.starts_with("youbot-perception: 1 robot, ") && !said.contains(" 1 run,"), "{said}");
    let bar = server.handle().cells().find("bar").unwrap().expect("cell bar");
    assert!(bar.snapshot().version > 0, "the perception node's boxes went elsewhere");
    server.stop().await;
}
