//! deploy/grafana/dmp-cell.json: every metric it queries is one the server serves (in a real scrape).

use std::collections::BTreeSet;

use dmp_server::server::start;
use dmp_tests::scrape::get;
use dmp_tests::{config, within};
use serde_json::Value;

use crate::{deploy, read};

/// Every `expr` of the dashboard's panels.
fn expressions(dashboard: &Value) -> Vec<String> {
    dashboard["panels"]
        .as_array()
        .expect("panels")
        .iter()
        .flat_map(|p| p["targets"].as_array().expect("targets").iter())
        .map(|t| t["expr"].as_str().expect("a PromQL expression").to_owned())
        .collect()
}

#[tokio::test(flavor = "multi_thread")]
async fn every_metric_of_the_dashboard_is_served() {
    let dashboard: Value =
        serde_json::from_str(&read(&deploy().join("grafana/dmp-cell.json"))).expect("JSON");
    let queried: BTreeSet<String> = expressions(&dashboard)
        .iter()
        .flat_map(|e| {
            e.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == ':'))
                .filter(|w| w.starts_with("dmp_"))
                .map(str::to_owned)
                .collect::<Vec<_>>()
        })
        .collect();
    assert!(queried.len() >= 10, "{queried:?}");

    let dir = tempfile::tempdir().unwrap();
    let mut c = config(dir.path());
    c.metrics_addr = Some("127.0.0.1:0".parse().unwrap());
    let handle = within("server start", start(c)).await.expect("server starts");
    let reply = get(handle.metrics_addr.unwrap(), "/metrics").await;
    assert_eq!(reply.status, 200);
    let served: BTreeSet<&str> = reply
        .body
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| l.split(['{', ' ']).next().unwrap())
        .collect();
    for name in &queried {
        assert!(
            served.contains(name.as_str()),
            "the dashboard queries {name}, which the server does not serve"
        );
    }
    // The `le` label the lateness panel counts as on time.
    assert!(reply.body.contains("dmp_segment_lateness_seconds_bucket{le=\"0.0\"}"));
    within("shutdown", handle.shutdown()).await.unwrap();
}
