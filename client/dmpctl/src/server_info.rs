//! What the server says about itself and its replies: `info`, `stats` and `health`, and the warnings the server
//! adds to a reply, printed on stderr.

use std::time::Duration;

use dmp_client::grpc::DmpClient;
use dmp_proto::v1;

use crate::error::DmpctlError;

/// `info`: the server's set-up and the caller's identity, as JSON.
pub(crate) fn info_json(info: &v1::ServerInfo) -> serde_json::Value {
    serde_json::json!({
        "version": info.version,
        "cell": info.cell,
        "tls": info.tls,
        "mutual_tls": info.mutual_tls,
        "access_control": info.access_control,
        "insecure": info.insecure,
        "insecure_reasons": info.insecure_reasons,
        "identity": info.identity,
        "role": info.role,
        "zenoh_locators": info.zenoh_locators,
        "limits": info.limits.as_ref().map(|l| serde_json::json!({
            "max_message_bytes": l.max_message_bytes,
            "max_samples": l.max_samples,
            "max_dim": l.max_dim,
            "max_obstacles": l.max_obstacles,
            "max_streams_per_client": l.max_streams_per_client,
            "max_steps": l.max_steps,
            "workspace_m": l.workspace_m,
            "max_request_work": l.max_request_work,
        })),
    })
}

/// The line a warning of the server is printed as (on stderr, `dmpctl: warning: ...`).
pub(crate) fn warning_line(w: &v1::Warning) -> String {
    let kind = v1::warning::Kind::try_from(w.kind).map_or("UNKNOWN", |k| k.as_str_name());
    let mut line = format!("warning: {kind}");
    if !w.obstacle_id.is_empty() {
        line.push_str(&format!(" (obstacle `{}`)", w.obstacle_id));
    }
    if !w.field.is_empty() {
        line.push_str(&format!(" {}:", w.field));
    }
    line.push(' ');
    line.push_str(&w.reason);
    line
}

/// Prints the warnings of a reply on stderr, and a scene that went stale or fresh again (`stale` holds the last
/// state seen: the change is printed once).
pub(crate) fn print_warnings(warnings: &[v1::Warning], scene_stale: bool, stale: &mut bool) {
    for w in warnings {
        eprintln!("dmpctl: {}", warning_line(w));
    }
    if scene_stale != *stale {
        *stale = scene_stale;
        if scene_stale {
            eprintln!(
                "dmpctl: warning: computed with a stale scene (its obstacles' sources have gone quiet)"
            );
        } else {
            eprintln!("dmpctl: the scene is fresh again");
        }
    }
}

/// `stats`: the server's statistics as JSON.
pub(crate) fn stats_json(s: &v1::ServerStats) -> serde_json::Value {
    serde_json::json!({
        "uptime_s": s.uptime_s,
        "cpu_seconds": s.cpu_seconds,
        "rss_bytes": s.rss_bytes,
        "open_streams": s.open_streams,
        "segments_sent": s.segments_sent,
        "cells": s.cells,
        "robots": s.robots,
        "robot_states_dropped": s.robot_states_dropped,
        "realtime_work_reserved": s.realtime_work_reserved,
        "realtime_work_budget": s.realtime_work_budget,
        "batch_work_reserved": s.batch_work_reserved,
        "batch_work_budget": s.batch_work_budget,
        "realtime_jobs_running": s.realtime_jobs_running,
        "batch_jobs_running": s.batch_jobs_running,
        "jobs_abandoned": s.jobs_abandoned,
        "jobs_failed": s.jobs_failed,
    })
}

/// The services `health` checks: the server as a whole, then each of its services.
pub(crate) const HEALTH_SERVICES: [&str; 6] = [
    "",
    "dmp.v1.PrimitiveService",
    "dmp.v1.RobotService",
    "dmp.v1.SceneService",
    "dmp.v1.MotionService",
    "dmp.v1.ServerService",
];

/// How long `health` waits for each answer.
const HEALTH_TIMEOUT: Duration = Duration::from_secs(5);

/// `health`: one line per service with its status; an error naming those not serving.
pub(crate) async fn health(client: &DmpClient) -> Result<String, DmpctlError> {
    let mut lines = Vec::new();
    let mut down = Vec::new();
    for service in HEALTH_SERVICES {
        // A wedged server must not hang a probe.
        let status = match tokio::time::timeout(HEALTH_TIMEOUT, client.health(service)).await {
            Ok(status) => status?,
            Err(_) => "NO_ANSWER",
        };
        let name = if service.is_empty() { "(server)" } else { service };
        if status != "SERVING" {
            down.push(format!("{name} {status}"));
        }
        lines.push(format!("{name}\t{status}"));
    }
    if down.is_empty() {
        Ok(lines.join("\n"))
    } else {
        Err(DmpctlError::Unhealthy(format!("{}\nnot serving: {}", lines.join("\n"), down.join(", "))))
    }
}
