//! Tests of the command line: parsing, refusals naming the flag. The commands against the real server are
//! end-to-end tests (`tests/tests/client/dmpctl.rs`).

use clap::Parser;
use dmp_client::ClientError;

use super::*;
use crate::args::{Vector, Via};
use crate::place::usable_locators;

fn parse(args: &[&str]) -> Cli {
    Cli::try_parse_from(std::iter::once("dmpctl").chain(args.iter().copied()))
        .unwrap_or_else(|e| panic!("{args:?}: {e}"))
}

fn refused(args: &[&str]) -> String {
    match Cli::try_parse_from(std::iter::once("dmpctl").chain(args.iter().copied())) {
        Ok(c) => panic!("{args:?} parsed: {c:?}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn scenario_commands_stay_offline_without_server() {
    let c = parse(&["scenario", "run", "s.json", "--out", "o"]);
    assert!(c.server.is_none());
    assert!(matches!(c.command, Command::Scenario(ScenarioCommand::Run { .. })));
    let c = parse(&["scenario", "run", "s.json", "--server", "http://127.0.0.1:9", "--out", "o"]);
    assert_eq!(c.server.as_deref(), Some("http://127.0.0.1:9"));
    let c = parse(&["scenario", "bench", "s.json", "--repeat", "3"]);
    assert!(matches!(c.command, Command::Scenario(ScenarioCommand::Bench { repeat: 3, .. })));
}

#[test]
fn global_options_go_anywhere() {
    let c = parse(&["--server", "http://h:1", "--cell", "c1", "list", "--robot", "r"]);
    assert_eq!((c.server.as_deref(), c.cell.as_deref()), (Some("http://h:1"), Some("c1")));
    let c = parse(&["list", "--robot", "r", "--zenoh-connect", "tcp/a:1", "--zenoh-connect", "tcp/b:2"]);
    assert_eq!(c.zenoh_connect, vec!["tcp/a:1", "tcp/b:2"]);
    assert_eq!(c.cell, None, "the server's own cell (GetInfo for the Zenoh commands)");
}

#[test]
fn learn_takes_exactly_one_source() {
    let c = parse(&[
        "learn",
        "--robot",
        "r",
        "--name",
        "p",
        "--csv",
        "d.csv",
        "--k",
        "100,200",
        "--n-basis",
        "20",
    ]);
    let Command::Learn(a) = c.command else { panic!() };
    assert_eq!(a.source.csv.as_deref(), Some(Path::new("d.csv")));
    assert_eq!(a.k, Some(Vector(vec![100.0, 200.0])));
    assert_eq!(a.n_basis, Some(20));
    let c = parse(&["learn", "--robot", "r", "--name", "p", "--scenario", "s.json"]);
    let Command::Learn(a) = c.command else { panic!() };
    assert!(a.source.scenario.is_some() && a.source.csv.is_none());
    refused(&["learn", "--robot", "r", "--name", "p"]);
    refused(&["learn", "--robot", "r", "--name", "p", "--csv", "a", "--scenario", "b"]);
    assert!(refused(&["learn", "--name", "p", "--csv", "a"]).contains("--robot"));
    assert!(
        refused(&["learn", "--robot", "r", "--name", "p", "--csv", "a", "--alpha", "-1"]).contains("--alpha")
    );
}

#[test]
fn load_takes_its_flags_and_the_global_server() {
    let c = parse(&[
        "--server",
        "http://h:1",
        "load",
        "--robots",
        "20",
        "--rate",
        "500",
        "--segment-s",
        "0.02",
        "--duration-s",
        "3",
        "--scene-updates",
        "5",
        "--zenoh-connect",
        "tcp/h:2",
        "--dim",
        "2",
        "--out",
        "r",
    ]);
    assert_eq!(
        (c.server.as_deref(), c.zenoh_connect.as_slice()),
        (Some("http://h:1"), &["tcp/h:2".into()][..])
    );
    let Command::Load(a) = c.command else { panic!() };
    let expected = dmp_sim::load::LoadArgs {
        robots: 20,
        rate: 500.0,
        segment_s: 0.02,
        duration: 3.0,
        scene_updates: 5.0,
        dim: 2,
        out: Some(PathBuf::from("r")),
        ..Default::default()
    };
    assert_eq!(a, expected);
    let Command::Load(a) = parse(&["load"]).command else { panic!() };
    assert_eq!(a, dmp_sim::load::LoadArgs::default());
    let Command::Load(a) = parse(&["load", "--via-zenoh-discovery", "--cells", "a,b,c"]).command else {
        panic!()
    };
    assert!(a.via_zenoh_discovery);
    assert_eq!(a.cell_names, ["a", "b", "c"]);
    // The server's adaptive step (at most 30 ms, tolerance 3e-6) unless told otherwise; a zero tolerance asks
    // for a fixed RK4 step, and a zero step for the server's default.
    assert_eq!((a.integration_step_s, a.integration_tolerance), (0.03, 3e-6));
    let Command::Load(a) =
        parse(&["load", "--integration-step-s", "0.005", "--integration-tolerance", "0"]).command
    else {
        panic!()
    };
    assert_eq!((a.integration_step_s, a.integration_tolerance), (0.005, 0.0));
    assert!(a.validate().is_ok());
    let Command::Load(a) = parse(&["load", "--integration-step-ms", "0"]).command else { panic!() };
    assert_eq!(a.validate().unwrap().args.integration_step_s, 0.0);
    // The old spellings in milliseconds still work, hidden, and mean the same seconds.
    let Command::Load(a) = parse(&["load", "--segment-ms", "20", "--duration", "3"]).command else {
        panic!()
    };
    let p = a.validate().unwrap();
    assert_eq!((p.args.segment_s, p.args.segment_ms, p.args.duration), (0.02, None, 3.0));
    assert!(refused(&["load", "--segment-ms", "20", "--segment-s", "0.02"]).contains("--segment"));
    let mut cmd = <Cli as clap::CommandFactory>::command();
    let help = cmd.find_subcommand_mut("load").unwrap().render_long_help().to_string();
    assert!(
        help.contains("--segment-s") && !help.contains("--segment-ms") && !help.contains("-ms"),
        "{help}"
    );
    let Command::Load(a) = parse(&["load", "--integration-tolerance", "0.5"]).command else { panic!() };
    assert!(a.validate().unwrap_err().to_string().contains("--integration-tolerance"));
    assert!(refused(&["load", "--robots", "many"]).contains("--robots"));
    // Numbers clap accepts are checked by the load itself, naming the flag.
    let Command::Load(a) = parse(&["load", "--rate", "-1"]).command else { panic!() };
    assert!(a.validate().unwrap_err().to_string().starts_with("--rate"));
}

#[test]
fn list_show_delete() {
    assert!(matches!(parse(&["list", "--robot", "r"]).command, Command::List { .. }));
    let Command::Show { version, .. } = parse(&["show", "--robot", "r", "--name", "p"]).command else {
        panic!()
    };
    assert_eq!(version, 0);
    let Command::Show { version, .. } =
        parse(&["show", "--robot", "r", "--name", "p", "--version", "3"]).command
    else {
        panic!()
    };
    assert_eq!(version, 3);
    assert!(matches!(parse(&["delete", "--robot", "r", "--name", "p"]).command, Command::Delete { .. }));
    assert!(refused(&["delete", "--robot", "r"]).contains("--name"));
    assert!(refused(&["show", "--robot", "r", "--name", "p", "--version", "x"]).contains("--version"));
}

#[test]
fn plan_parses_vectors_with_negative_entries_and_avoidance() {
    let c = parse(&[
        "plan",
        "--robot",
        "r",
        "--name",
        "p",
        "--goal",
        "-1,0.5",
        "--start",
        "0,0",
        "--tau",
        "2",
        "--duration",
        "3",
        "--dt",
        "0.002",
        "--out",
        "o",
        "--avoidance",
        "none",
        "--ignore-scene",
    ]);
    let Command::Plan(a) = c.command else { panic!() };
    assert_eq!(a.motion.goal, Some(Vector(vec![-1.0, 0.5])));
    assert_eq!(a.motion.start, Some(Vector(vec![0.0, 0.0])));
    assert_eq!((a.motion.tau, a.duration, a.dt), (Some(2.0), Some(3.0), Some(0.002)));
    assert_eq!(a.motion.avoidance, Some(dmp::Avoidance::NONE));
    assert!(a.motion.ignore_scene);
    let spec = a.motion.spec();
    assert_eq!((spec.goal, spec.tau), (vec![-1.0, 0.5], 2.0));
    assert!(spec.avoidance.is_some());

    let c = parse(&[
        "plan",
        "--robot",
        "r",
        "--name",
        "p",
        "--out",
        "o",
        "--avoidance",
        r#"{"method": "static_volumetric", "A": 10, "eta": 1}"#,
    ]);
    let Command::Plan(a) = c.command else { panic!() };
    assert_eq!(a.motion.avoidance.unwrap().method.name(), "static_volumetric");
    let spec = a.motion.spec();
    assert!(spec.goal.is_empty() && spec.start.is_empty() && spec.tau == 0.0);
    assert!(spec.goal_orientation.is_empty() && spec.start_orientation.is_empty());

    // A pose primitive's orientations go to the server as given (it checks them, naming the field).
    let c = parse(&[
        "plan",
        "--robot",
        "r",
        "--name",
        "p",
        "--out",
        "o",
        "--goal-orientation",
        "0,0,-0.6,0.8",
        "--start-orientation",
        "0,0,0,1",
    ]);
    let Command::Plan(a) = c.command else { panic!() };
    let spec = a.motion.spec();
    assert_eq!(spec.goal_orientation, vec![0.0, 0.0, -0.6, 0.8]);
    assert_eq!(spec.start_orientation, vec![0.0, 0.0, 0.0, 1.0]);

    let e = refused(&["plan", "--robot", "r", "--name", "p", "--goal", "1,x", "--out", "o"]);
    assert!(e.contains("--goal") && e.contains("entry 2"), "{e}");
    assert!(
        refused(&["plan", "--robot", "r", "--name", "p", "--goal", "1,NaN", "--out", "o"]).contains("--goal")
    );
    assert!(refused(&["plan", "--robot", "r", "--name", "p", "--tau", "0", "--out", "o"]).contains("--tau"));
    assert!(refused(&["plan", "--robot", "r", "--name", "p"]).contains("--out"));
    let e = refused(&["plan", "--robot", "r", "--name", "p", "--out", "o", "--avoidance", "magic"]);
    assert!(e.contains("--avoidance") && e.contains("magic"), "{e}");
}

#[test]
fn stream_options() {
    let c = parse(&[
        "stream",
        "--robot",
        "r",
        "--name",
        "p",
        "--realtime",
        "--goal",
        "1,1",
        "--tau",
        "0.5",
        "--segment",
        "0.02",
        "--lookahead",
        "0.1",
        "--max-duration",
        "4",
        "--out",
        "o",
    ]);
    let Command::Stream(a) = c.command else { panic!() };
    assert!(a.realtime);
    assert_eq!((a.segment, a.lookahead, a.max_duration), (Some(0.02), Some(0.1), Some(4.0)));
    let Command::Stream(a) = parse(&["stream", "--robot", "r", "--name", "p", "--out", "o"]).command else {
        panic!()
    };
    assert!(!a.realtime && a.motion.goal.is_none() && !a.quiet);
    let Command::Stream(a) =
        parse(&["stream", "--robot", "r", "--name", "p", "--out", "o", "--quiet"]).command
    else {
        panic!()
    };
    assert!(a.quiet);
}

#[test]
fn scene_commands() {
    let Command::Scene(SceneCommand::Put { via, ttl, .. }) = parse(&["scene", "put", "o.json"]).command
    else {
        panic!()
    };
    assert_eq!((via, ttl), (Via::Grpc, None));
    let c =
        parse(&["scene", "put", "o.json", "--via", "zenoh", "--ttl", "2.5", "--zenoh-connect", "tcp/h:7447"]);
    let Command::Scene(SceneCommand::Put { via, ttl, .. }) = c.command else { panic!() };
    assert_eq!((via, ttl), (Via::Zenoh, Some(2.5)));
    assert_eq!(c.zenoh_connect, vec!["tcp/h:7447"]);
    let Command::Scene(SceneCommand::Put { ttl, .. }) =
        parse(&["scene", "put", "o.json", "--ttl-s", "1.5"]).command
    else {
        panic!()
    };
    assert_eq!(ttl, Some(1.5));
    let Command::Scene(SceneCommand::Delete { id, via }) =
        parse(&["scene", "delete", "box1", "--via", "zenoh"]).command
    else {
        panic!()
    };
    assert_eq!((id.as_str(), via), ("box1", Via::Zenoh));
    assert!(matches!(parse(&["scene", "list"]).command, Command::Scene(SceneCommand::List)));
    assert!(refused(&["scene", "put", "o.json", "--via", "carrier-pigeon"]).contains("--via"));
    assert!(refused(&["scene", "put", "o.json", "--ttl", "-1"]).contains("--ttl"));
}

#[test]
fn a_closed_port_is_a_connection_failure_not_bad_input() {
    // Port 1 on loopback: nothing listens.
    let e = run(parse(&["--server", "http://127.0.0.1:1", "list", "--robot", "r"])).unwrap_err();
    assert!(matches!(e, DmpctlError::Client(ClientError::Connect { .. })), "{e}");
    assert!(!e.is_bad_input());
    assert!(e.to_string().contains("127.0.0.1:1"), "{e}");
    let e = run(parse(&["--server", "http://bad host:1", "list", "--robot", "r"])).unwrap_err();
    assert!(e.is_bad_input(), "{e}");
}

#[test]
fn only_the_loopback_locators_of_a_server_on_this_host_are_used() {
    let reported = ["tcp/127.0.0.1:7447", "tcp/10.0.0.5:7447", "tls/[::1]:7448", "tcp/172.17.0.1:7447"]
        .map(String::from)
        .to_vec();
    for local in ["http://127.0.0.1:50051", "https://localhost:50051", "http://[::1]:50051/"] {
        assert_eq!(
            usable_locators(local, &reported),
            vec!["tcp/127.0.0.1:7447", "tls/[::1]:7448"],
            "{local}"
        );
    }
    // A remote server's listen addresses say nothing reliable about how to reach it: none, so scouting or
    // --zenoh-connect.
    assert!(usable_locators("https://robot-host:50051", &reported).is_empty());
    assert!(usable_locators("http://10.0.0.5:50051", &reported).is_empty());
}

#[test]
fn a_zenoh_command_that_cannot_ask_the_server_goes_on_with_the_default_cell() {
    // Nothing listens on port 1 (gRPC) nor on the Zenoh endpoint: the command warns that it cannot ask the server,
    // goes on to Zenoh (no gRPC needed for a Zenoh delete), and fails there, not at the gRPC connection.
    let c = parse(&[
        "--server",
        "http://127.0.0.1:1",
        "--zenoh-connect",
        "tcp/127.0.0.1:1",
        "scene",
        "delete",
        "x",
        "--via",
        "zenoh",
    ]);
    let e = run(c).unwrap_err();
    assert!(matches!(e, DmpctlError::Client(ClientError::Zenoh(_))), "{e:?}");
}

#[test]
fn summary_lines_count_in_the_singular_and_the_plural() {
    assert_eq!(plural(1, "robot"), "1 robot");
    assert_eq!(plural(3, "run"), "3 runs");
    assert_eq!(plural(0, "run"), "0 runs");
}

#[test]
fn durations_are_in_seconds_with_the_old_spellings_hidden() {
    let new =
        ["stream", "--robot", "r", "--name", "p", "--dt-s", "0.002", "--segment-s", "0.02", "--out", "o"];
    let old = ["stream", "--robot", "r", "--name", "p", "--dt", "0.002", "--segment", "0.02", "--out", "o"];
    for args in [&new[..], &old[..]] {
        let Command::Stream(a) = parse(args).command else { panic!() };
        assert_eq!((a.dt, a.segment), (Some(0.002), Some(0.02)), "{args:?}");
    }
    let mut cmd = <Cli as clap::CommandFactory>::command();
    let help = cmd.find_subcommand_mut("stream").unwrap().render_long_help().to_string();
    for flag in ["--dt-s", "--segment-s", "--lookahead-s", "--max-duration-s"] {
        assert!(help.contains(flag), "{flag} missing from\n{help}");
    }
    assert!(!help.contains("--segment ") && !help.contains("--max-duration "), "{help}");
    let Command::Plan(a) =
        parse(&["plan", "--robot", "r", "--name", "p", "--duration-s", "2", "--out", "o"]).command
    else {
        panic!()
    };
    assert_eq!(a.duration, Some(2.0));
}
