//! The `dmp-server` binary's Zenoh threads: without `ZENOH_RUNTIME` it runs Zenoh with the server's layout (one
//! Zenoh thread) and keeps its own process name, an operator's layout is kept, and one Zenoh cannot read stops it.
#![cfg(target_os = "linux")]

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use dmp_server::zenoh_bridge::threads::{LAYOUT, ZENOH_RUNTIME};

/// Longest wait for the server to open its Zenoh session.
const STARTUP: Duration = Duration::from_secs(60);

/// The server on loopback ports chosen by the system, `ZENOH_RUNTIME` as given (None: unset).
fn server(zenoh_runtime: Option<&str>, data: &tempfile::TempDir) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_dmp-server"));
    c.args([
        "--grpc-addr",
        "127.0.0.1:0",
        "--zenoh-listen",
        "tcp/127.0.0.1:0",
        "--zenoh-no-multicast",
        "--data-dir",
    ])
    .arg(data.path())
    .env("RUST_LOG", "info")
    .stdin(Stdio::null())
    .stdout(Stdio::null())
    .stderr(Stdio::piped());
    match zenoh_runtime {
        Some(v) => c.env(ZENOH_RUNTIME, v),
        None => c.env_remove(ZENOH_RUNTIME),
    };
    c
}

/// A running server, killed when dropped.
struct Running(Child);

impl Drop for Running {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// What a started server shows of itself.
struct Started {
    /// The process's name (`/proc/<pid>/comm`).
    name: String,
    /// Its threads' names.
    threads: Vec<String>,
    /// The line of its log that gives the effective configuration (with the `ZENOH_RUNTIME` Zenoh reads).
    configuration: String,
}

/// Starts the server and waits until its Zenoh session is open and its Zenoh threads `expected` are running.
fn started(zenoh_runtime: Option<&str>, expected: &[&str]) -> Started {
    let data = tempfile::tempdir().unwrap();
    let mut child = Running(server(zenoh_runtime, &data).spawn().expect("the server starts"));
    let stderr = child.0.stderr.take().unwrap();
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            let open = line.contains("zenoh session open");
            if tx.send((open, line)).is_err() {
                break;
            }
        }
    });
    let deadline = Instant::now() + STARTUP;
    let mut log = Vec::new();
    loop {
        match rx.recv_timeout(deadline.saturating_duration_since(Instant::now())) {
            Ok((true, _)) => break,
            Ok((false, line)) => log.push(line),
            Err(e) => panic!("the server did not open its Zenoh session ({e}); its log:\n{}", log.join("\n")),
        }
    }
    let configuration = log
        .iter()
        .find(|line| line.contains("effective configuration"))
        .unwrap_or_else(|| panic!("no effective configuration in the log:\n{}", log.join("\n")))
        .clone();
    let pid = child.0.id();
    let comm = |path: std::path::PathBuf| std::fs::read_to_string(path).map(|name| name.trim().to_string());
    // A thread names itself once it runs: wait (briefly) for the ones expected.
    let threads = loop {
        let threads: Vec<String> = std::fs::read_dir(format!("/proc/{pid}/task"))
            .unwrap()
            .filter_map(|t| comm(t.ok()?.path().join("comm")).ok())
            .collect();
        if expected.iter().all(|e| threads.iter().any(|t| t == e)) || Instant::now() > deadline {
            break threads;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let name = comm(format!("/proc/{pid}/comm").into()).unwrap();
    Started { name, threads, configuration }
}

fn named(threads: &[String], name: &str) -> usize {
    threads.iter().filter(|t| t.as_str() == name).count()
}

#[test]
fn without_a_layout_the_server_keeps_its_name_and_runs_zenoh_on_one_thread() {
    // Zenoh starts a runtime's threads at its first use: once the session is open, `acc` and `net` have theirs
    // (see the next test) and `rx` and `tx` wait for a link.
    let s = started(None, &["app-0"]);
    assert_eq!(s.name, "dmp-server", "the process keeps its name");
    assert!(s.configuration.contains(LAYOUT), "the layout is set: {}", s.configuration);
    assert_eq!(named(&s.threads, "app-0"), 1, "{:?}", s.threads);
    for other in ["acc-0", "net-0", "rx-0", "tx-0"] {
        assert_eq!(named(&s.threads, other), 0, "{other} in {:?}", s.threads);
    }
}

#[test]
fn an_operators_layout_is_kept() {
    // Zenoh's own default: its `acc` and `net` threads run once the session is open.
    let s = started(Some("()"), &["acc-0", "net-0"]);
    assert_eq!(s.name, "dmp-server");
    assert!(!s.configuration.contains(LAYOUT), "{}", s.configuration);
    assert_eq!(named(&s.threads, "acc-0"), 1, "{:?}", s.threads);
    assert_eq!(named(&s.threads, "net-0"), 1, "{:?}", s.threads);
    // One runtime handed over, as asked; the other kept.
    let mine = "(acc: (handover: app))";
    let s = started(Some(mine), &["net-0"]);
    assert!(s.configuration.contains(mine), "{}", s.configuration);
    assert_eq!(named(&s.threads, "acc-0"), 0, "acc handed over, as asked: {:?}", s.threads);
    assert_eq!(named(&s.threads, "net-0"), 1, "net kept, as asked: {:?}", s.threads);
}

#[test]
fn a_layout_zenoh_cannot_read_stops_the_server_with_zenohs_reason() {
    let data = tempfile::tempdir().unwrap();
    let mut child =
        Running(server(Some("(rxx: (worker_threads: 1))"), &data).spawn().expect("the server starts"));
    let deadline = Instant::now() + STARTUP;
    let status = loop {
        if let Some(status) = child.0.try_wait().unwrap() {
            break status;
        }
        assert!(Instant::now() < deadline, "the server kept running with a layout Zenoh cannot read");
        std::thread::sleep(Duration::from_millis(20));
    };
    assert!(!status.success(), "{status}");
    let mut stderr = String::new();
    std::io::Read::read_to_string(&mut child.0.stderr.take().unwrap(), &mut stderr).unwrap();
    assert!(stderr.contains("rxx"), "Zenoh names the unknown runtime: {stderr}");
}
