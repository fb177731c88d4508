//! The deploy files (`deploy/`) kept true: they parse, every command line they give dmp-server and dmpctl parses
//! with the binaries' own clap commands, and every port and path agrees with `deploy/Dockerfile`, with the set that
//! `dmp-server access init` writes, and with the server's configuration. Docker and Kubernetes can't run here:
//! this is what can be checked without them.

mod compose;
mod dockerfile;
mod grafana;
mod k8s;
mod zenohd;

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use clap::Parser;
use serde_json::Value;

use dockerfile::Dockerfile;

/// The repository's `deploy/` folder.
fn deploy() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../deploy")
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Every document of a YAML file, as JSON values.
fn yaml_documents(path: &Path) -> Vec<Value> {
    serde_saphyr::from_multiple::<Value>(&read(path))
        .unwrap_or_else(|e| panic!("{} is not valid YAML: {e}", path.display()))
}

/// A JSON5 file or text.
fn json5(text: &str, what: &str) -> Value {
    json5::from_str(text).unwrap_or_else(|e| panic!("{what} is not valid JSON5: {e}"))
}

/// Where the deploy files mount the set of `dmp-server access init`.
const SET_DIR: &str = "/etc/dmp-server/set";

/// The files of a set that `dmp-server access init` writes (for the cells, robots and hosts given).
fn set_files(cells: &[&str], robots: &[&str], hosts: &[&str]) -> BTreeSet<String> {
    let dir = tempfile::tempdir().unwrap();
    let strings = |v: &[&str]| v.iter().map(|s| s.to_string()).collect();
    let options = dmp_server::access::init::InitOptions {
        cells: strings(cells),
        robots: strings(robots),
        hosts: strings(hosts),
    };
    dmp_server::access::init::init(dir.path(), &options).expect("access init");
    std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect()
}

/// Checks that every argument naming a file of the set (`/etc/dmp-server/set/NAME`, alone or after `=`) names one
/// `access init` writes, and returns those names.
fn set_paths_in(args: &[String], set: &BTreeSet<String>, what: &str) -> BTreeSet<String> {
    let mut used = BTreeSet::new();
    for a in args {
        let path = a.rsplit('=').next().unwrap();
        if let Some(name) = path.strip_prefix(&format!("{SET_DIR}/")) {
            assert!(set.contains(name), "{what}: {a} is not a file of the set ({set:?})");
            used.insert(name.to_owned());
        }
    }
    used
}

/// The arguments after `--flag` (each occurrence).
fn flag_values<'a>(args: &'a [String], flag: &str) -> Vec<&'a str> {
    args.windows(2).filter(|w| w[0] == flag).map(|w| w[1].as_str()).collect()
}

/// A YAML/JSON list of strings.
fn strings(v: &Value, what: &str) -> Vec<String> {
    v.as_array()
        .unwrap_or_else(|| panic!("{what}: not a list: {v}"))
        .iter()
        .map(|s| s.as_str().unwrap_or_else(|| panic!("{what}: not a string: {s}")).to_owned())
        .collect()
}

/// dmp-server's own parse of `args` (as the binary parses its command line).
fn dmp_server_args(args: &[String], what: &str) -> dmp_server::config::command_line::Args {
    dmp_server::config::command_line::Args::try_parse_from(
        std::iter::once("dmp-server".to_owned()).chain(args.iter().cloned()),
    )
    .unwrap_or_else(|e| panic!("{what}: dmp-server does not take {args:?}:\n{e}"))
}

/// dmpctl's own parse of `args`.
fn dmpctl_args(args: &[String], what: &str) -> dmpctl::cli::Cli {
    dmpctl::cli::Cli::try_parse_from(std::iter::once("dmpctl".to_owned()).chain(args.iter().cloned()))
        .unwrap_or_else(|e| panic!("{what}: dmpctl does not take {args:?}:\n{e}"))
}

/// The version of the zenoh crate in Cargo.lock: the router's image must be the same.
fn zenoh_version() -> String {
    let lock: toml::Value =
        toml::from_str(&read(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../Cargo.lock"))).unwrap();
    let packages = lock["package"].as_array().unwrap();
    let zenoh = packages.iter().find(|p| p["name"].as_str() == Some("zenoh")).expect("zenoh in Cargo.lock");
    zenoh["version"].as_str().unwrap().to_owned()
}

/// The strings of `v` as `&str`.
fn as_str(v: &[String]) -> Vec<&str> {
    v.iter().map(String::as_str).collect()
}

/// The port of a `HOST:PORT` address or endpoint.
fn port_of(addr: &str) -> u16 {
    addr.rsplit(':').next().unwrap().parse().unwrap_or_else(|e| panic!("no port in {addr}: {e}"))
}

#[test]
fn the_readme_points_at_the_deploy_files() {
    let readme = read(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../README.md"));
    for file in [
        "deploy/compose.yaml",
        "deploy/k8s/",
        "deploy/grafana/dmp-cell.json",
        "deploy/zenohd-obstacles.json5",
        "--metrics-addr",
    ] {
        assert!(readme.contains(file), "README.md does not mention {file}");
    }
    let _ = Dockerfile::load();
}
