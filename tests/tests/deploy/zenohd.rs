//! The router's storage of obstacles: deploy/zenohd-obstacles.json5, and the same storage on the command line of
//! the secured routers (compose, k8s).

use std::collections::{BTreeMap, BTreeSet};

use serde_json::Value;
use zenoh::key_expr::KeyExpr;

use crate::{deploy, json5, port_of, read, set_paths_in};

/// Checks that a storage configuration keeps every obstacle key the server subscribes to and queries, in memory.
fn check_storage(storage: &Value, what: &str) {
    let key = storage["key_expr"].as_str().unwrap_or_else(|| panic!("{what}: no key_expr"));
    let stored = KeyExpr::try_from(key).unwrap_or_else(|e| panic!("{what}: {key}: {e}"));
    let subscribed = dmp_proto::keys::obstacles_of(dmp_proto::keys::EVERY_CELL);
    assert!(
        stored.includes(&KeyExpr::try_from(subscribed.as_str()).unwrap()),
        "{what}: {key} misses {subscribed}"
    );
    assert_eq!(key, "dmp/*/obstacles/**", "{what}: what the server's catch-up query asks");
    let volume = &storage["volume"];
    assert!(volume == "memory" || volume["id"] == "memory", "{what}: memory backend: {volume}");
}

/// Checks a router's command line: `-c` the set's zenoh-router.json5, and `--cfg=` the obstacle storage.
pub fn check_router_args(args: &[String], set: &BTreeSet<String>, what: &str) {
    let config = args.windows(2).find(|w| w[0] == "-c").map(|w| w[1].clone()).expect("-c FILE");
    assert!(config.ends_with("/zenoh-router.json5"), "{what}: {config}");
    assert_eq!(set_paths_in(args, set, what).len(), 1, "{what}");
    let cfg = args.iter().find_map(|a| a.strip_prefix("--cfg=")).expect("--cfg=KEY:VALUE");
    assert!(!cfg.contains(' '), "{what}: the image's entrypoint splits its arguments at spaces");
    let (key, value) = cfg.split_once(':').unwrap();
    assert_eq!(key, "plugins/storage_manager/storages/dmp_obstacles", "{what}");
    check_storage(&json5(value, what), what);
    check_router_lease(args, what);
}

/// The lease of deploy/zenoh-lease.json5 (`transport.link.tx`), for a node that fails over.
pub fn lease() -> (u64, u64) {
    let lease = json5(&read(&deploy().join("zenoh-lease.json5")), "zenoh-lease.json5");
    let tx = &lease["transport"]["link"]["tx"];
    (tx["lease"].as_u64().expect("tx.lease"), tx["keep_alive"].as_u64().expect("tx.keep_alive"))
}

/// Checks that a router's command line sets the lease of deploy/zenoh-lease.json5, with keys stock Zenoh takes.
fn check_router_lease(args: &[String], what: &str) {
    let cfgs: BTreeMap<&str, &str> =
        args.iter().filter_map(|a| a.strip_prefix("--cfg=")).filter_map(|c| c.split_once(':')).collect();
    let (lease, keep_alive) = lease();
    for (key, value) in [("transport/link/tx/lease", lease), ("transport/link/tx/keep_alive", keep_alive)] {
        assert_eq!(cfgs.get(key).copied(), Some(value.to_string().as_str()), "{what}: --cfg={key}:{value}");
        let mut config = zenoh::Config::default();
        config.insert_json5(key, cfgs[key]).unwrap_or_else(|e| panic!("{what}: {key}: {e}"));
    }
}

/// The port the router of a set (`zenoh-router.json5` as `access init` writes it) listens on.
pub fn router_listen_port(cells: &[&str]) -> u16 {
    let dir = tempfile::tempdir().unwrap();
    let options = dmp_server::access::init::InitOptions {
        cells: cells.iter().map(|c| c.to_string()).collect(),
        ..Default::default()
    };
    dmp_server::access::init::init(dir.path(), &options).unwrap();
    let router = json5(&read(&dir.path().join("zenoh-router.json5")), "zenoh-router.json5");
    let endpoints = router["listen"]["endpoints"].as_array().unwrap();
    assert_eq!(endpoints.len(), 1);
    port_of(endpoints[0].as_str().unwrap())
}

#[test]
fn the_storage_example_keeps_every_obstacle_in_memory() {
    let config = json5(&read(&deploy().join("zenohd-obstacles.json5")), "zenohd-obstacles.json5");
    assert_eq!(config["mode"], "router");
    let storages = config["plugins"]["storage_manager"]["storages"].as_object().unwrap();
    assert_eq!(storages.len(), 1);
    for (name, storage) in storages {
        check_storage(storage, name);
    }
    // Stock Zenoh reads it (the plugins' part is zenohd's to check).
    zenoh::Config::from_file(deploy().join("zenohd-obstacles.json5")).expect("a Zenoh configuration");
}
