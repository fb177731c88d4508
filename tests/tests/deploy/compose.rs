//! deploy/compose.yaml and deploy/prometheus.yml.

use std::collections::BTreeMap;

use serde_json::Value;

use crate::dockerfile::Dockerfile;
use crate::zenohd::{check_router_args, router_listen_port};
use crate::{
    SET_DIR, as_str, deploy, dmp_server_args, dmpctl_args, flag_values, port_of, read, set_files,
    set_paths_in, strings, yaml_documents,
};

/// The container side of each `HOST:CONTAINER` port mapping of a service.
fn container_ports(service: &Value) -> Vec<u16> {
    service["ports"]
        .as_array()
        .map(|ports| ports.iter().map(|p| port_of(p.as_str().expect("a port mapping as a string"))).collect())
        .unwrap_or_default()
}

/// The `SOURCE:TARGET[:ro]` volume mounts of a service, by target.
fn mounts(service: &Value) -> BTreeMap<String, String> {
    service["volumes"]
        .as_array()
        .map(|v| {
            v.iter()
                .map(|m| {
                    let parts: Vec<&str> = m.as_str().unwrap().split(':').collect();
                    (parts[1].to_owned(), parts[0].to_owned())
                })
                .collect()
        })
        .unwrap_or_default()
}

#[test]
fn compose_parses_and_its_commands_ports_and_paths_agree_with_the_image() {
    let docker = Dockerfile::load();
    let (grpc_port, metrics_port) = docker.grpc_and_metrics_ports();
    let compose = yaml_documents(&deploy().join("compose.yaml")).remove(0);
    let services = compose["services"].as_object().expect("services");
    let volumes = compose["volumes"].as_object().expect("named volumes");

    // The set, as access-init makes it.
    let init = &services["access-init"];
    let init_args = strings(&init["command"], "access-init");
    let init_parsed = dmp_server_args(&init_args, "access-init");
    let Some(dmp_server::config::command_line::Command::Access(
        dmp_server::config::command_line::AccessCommand::Init { dir, cells, robots, hosts, .. },
    )) = init_parsed.command
    else {
        panic!("access-init does not run `access init`: {init_args:?}")
    };
    assert_eq!(dir, std::path::Path::new(SET_DIR), "the set is written where every container mounts it");
    assert_eq!(mounts(init).get(SET_DIR).map(String::as_str), Some("dmp-set"));
    let set = set_files(&as_str(&cells), &as_str(&robots), &as_str(&hosts));

    // The router: the official image of the zenoh crate's version, the set's configuration, the storage.
    let zenohd = &services["zenohd"];
    assert_eq!(zenohd["image"].as_str(), Some(format!("eclipse/zenoh:{}", crate::zenoh_version()).as_str()));
    let router_args = strings(&zenohd["command"], "zenohd");
    check_router_args(&router_args, &set, "compose zenohd");
    let router_port = router_listen_port(&as_str(&cells));
    assert_eq!(container_ports(zenohd), [router_port]);
    assert_eq!(mounts(zenohd).get(SET_DIR).map(String::as_str), Some("dmp-set"));
    assert_eq!(
        hosts.first().map(String::as_str),
        Some("zenohd"),
        "zenoh-perception.json5 connects to the first --host"
    );

    // `docker compose build` builds the image once, from deploy/Dockerfile, in a service of no profile (services
    // of an inactive profile are not built).
    let builders: Vec<_> = services.iter().filter(|(_, s)| !s["build"].is_null()).collect();
    assert_eq!(builders.len(), 1, "one service builds dmp-server:latest");
    let (_, builder) = builders[0];
    assert!(builder["profiles"].is_null() && builder["image"] == "dmp-server:latest");
    assert_eq!(builder["build"]["dockerfile"], "deploy/Dockerfile");
    assert!(deploy().join(builder["build"]["context"].as_str().unwrap()).join("deploy/Dockerfile").exists());

    // Two servers, each its own cell, on the image's ports and volume, connected to the router.
    let mut served = Vec::new();
    for (name, s) in services.iter().filter(|(_, s)| s["entrypoint"].is_null() && s["profiles"].is_null()) {
        if s["image"].as_str() != Some("dmp-server:latest") {
            continue;
        }
        let args = strings(&s["command"], name);
        let parsed = dmp_server_args(&args, name);
        assert!(parsed.command.is_none(), "{name} serves");
        let cell = parsed.cell.clone().expect("each server names its cell");
        assert!(cells.contains(&cell), "{name}: cell {cell} is not a cell of the set");
        assert!(hosts.contains(name), "{name} is not a --host of the set: its certificate would not name it");
        served.push(cell);
        assert_eq!(parsed.grpc_addr.map(|a| a.port()), Some(grpc_port), "{name}");
        assert_eq!(parsed.metrics_addr.map(|a| a.port()), Some(metrics_port), "{name}");
        let mut published = container_ports(s);
        published.sort();
        let mut exposed: Vec<u16> = docker.exposed.iter().copied().collect();
        exposed.sort();
        assert_eq!(published, exposed, "{name} publishes the image's ports");
        let data = parsed.data_dir.clone().expect("--data-dir");
        assert_eq!(data.to_str(), Some(docker.volume.as_str()), "{name}: --data-dir is the image's VOLUME");
        let m = mounts(s);
        assert!(volumes.contains_key(&m[&docker.volume]), "{name}: its store is on a named volume");
        assert_eq!(m.get(SET_DIR).map(String::as_str), Some("dmp-set"), "{name}");
        assert_eq!(set_paths_in(&args, &set, name).len(), 4, "{name}: access file, certificate, key, CA");
        assert_eq!(parsed.zenoh_mode.as_deref(), Some("client"), "{name}: a client of the router");
        assert_eq!(parsed.zenoh_connect, [format!("tls/zenohd:{router_port}")], "{name}");
        // The lease file, mounted from deploy/.
        let lease = parsed.zenoh_config.clone().expect("--zenoh-config: the lease");
        let lease = lease.to_str().unwrap();
        assert_eq!(
            m.get(lease).map(String::as_str),
            Some("./zenoh-lease.json5"),
            "{name}: {lease} is mounted"
        );
    }
    served.sort();
    served.dedup();
    assert_eq!(served.len(), 2, "two servers, each serving its own cell: {served:?}");
    let data_volumes: Vec<_> = volumes.keys().filter(|v| v.starts_with("data")).collect();
    assert_eq!(data_volumes.len(), 2, "a store per server");

    // The perception node: dmpctl, the perception identity's Zenoh configuration, an obstacle file it mounts.
    let p = &services["perception"];
    assert_eq!(strings(&p["entrypoint"], "perception"), ["/usr/local/bin/dmpctl"]);
    assert!(docker.binaries.contains("dmpctl"));
    let args = strings(&p["command"], "perception");
    let _ = dmpctl_args(&args, "perception");
    assert_eq!(
        set_paths_in(&args, &set, "perception").into_iter().collect::<Vec<_>>(),
        ["zenoh-perception.json5"]
    );
    assert!(cells.contains(&flag_values(&args, "--cell")[0].to_owned()));
    let file = &args[args.iter().position(|a| a == "put").expect("scene put") + 1];
    let source = &mounts(p)[file];
    let bytes = std::fs::read(deploy().join(source)).unwrap();
    dmp_proto::obstacle_json::obstacle_from_json_bytes(&bytes, "")
        .expect("the perception example is an obstacle");

    // Prometheus scrapes the servers' metrics ports.
    let prometheus = yaml_documents(&deploy().join("prometheus.yml")).remove(0);
    let targets = strings(&prometheus["scrape_configs"][0]["static_configs"][0]["targets"], "targets");
    assert_eq!(targets.len(), 2);
    for t in &targets {
        let (host, port) = t.split_once(':').unwrap();
        let s = &services[host];
        let args = strings(&s["command"], host);
        assert_eq!(dmp_server_args(&args, host).metrics_addr.map(|a| a.port()), Some(port.parse().unwrap()));
    }
    let _ = read(&deploy().join("perception-box.json"));
}
