//! What a reload of the access file (SIGHUP) changes on Zenoh: nothing that Zenoh enforces, so the server says
//! so on the audit log, naming every Zenoh peer the reload revoked.
//!
//! Zenoh 1.10.2 reads its access control once, when the session opens, and builds each peer's filter when the
//! peer connects: `TablesLock::update_config` would rebuild them but is crate-private (only Zenoh's own tests
//! call it), a config change through `Session::config()` or the admin space reaches only plugins, and no public
//! call closes a transport (`Runtime::manager` is crate-private). A sample carries no authenticated identity
//! either: its `source_info` is optional, set by the publisher, and never checked. So a revoked identity keeps,
//! until the server restarts, the Zenoh rights its certificate's common name had when the session opened, from its
//! open sessions and from new ones. Reopening the server's session would apply the new rules, but it carries the
//! plant's liveliness token: a reload would look like the server leaving, and its cells would fail over.
//!
//! What the server does know is authenticated: each link of its session carries the common name of the peer's
//! verified certificate (mutual TLS). At every reload it compares the Zenoh rights of each linked peer's
//! identity (its role and cells) with those the session opened with, and logs on the target `audit`, at warn,
//! each peer the reload revoked or narrowed (`zenoh session`, its identity, common name and Zenoh id). A peer of
//! such an identity that connects later is logged too, rate-limited ([`crate::access::audit`]).

use std::sync::Arc;

use tokio::sync::watch;
use tokio::task::JoinHandle;
use tokio_util::sync::CancellationToken;
use tracing::{debug, warn};
use zenoh::Session;
use zenoh::sample::SampleKind;
use zenoh::session::Link;

use crate::access::{Access, Role, audit};
use crate::error::ServerError;

/// Why a revoked identity's Zenoh session is still there.
const REASON: &str = "the reloaded access file no longer gives this identity these Zenoh rights, but Zenoh keeps \
                      those its session opened with until the server restarts";

/// The Zenoh rights of the identity of certificate common name `cn` under `access`: its name, role and cells
/// (none for a robot, which has no Zenoh rights, or an unknown name).
fn rights<'a>(access: Option<&'a Access>, cn: &str) -> Option<(&'a str, Role, &'a [String])> {
    let i = access?.by_common_name(cn)?;
    (i.role != Role::Robot).then_some((i.name.as_str(), i.role, i.scope.cells.as_slice()))
}

/// The identity's name under `opened` when a reload took Zenoh rights from common name `cn`: it had some when the
/// session opened, and `now` gives it none, another role, or not all of those cells.
fn revoked<'a>(opened: &'a Access, now: Option<&Access>, cn: &str) -> Option<&'a str> {
    let (name, role, cells) = rights(Some(opened), cn)?;
    match rights(now, cn) {
        Some((_, r, c)) if r == role && cells.iter().all(|cell| c.contains(cell)) => None,
        _ => Some(name),
    }
}

/// Audits every link of `session` whose peer `now` revoked; returns how many.
async fn audit_links(session: &Session, opened: &Access, now: Option<&Access>) -> usize {
    let mut n = 0;
    for link in session.info().links().await {
        if let Some(name) = link.auth_identifier().and_then(|cn| revoked(opened, now, cn)) {
            log_link(name, &link, "still connected");
            n += 1;
        }
    }
    n
}

fn log_link(identity: &str, link: &Link, what: &'static str) {
    warn!(target: "audit", identity, action = "zenoh session", common_name = link.auth_identifier(),
        zid = %link.zid(), peer = %link.dst(), reason = REASON, "revoked identity {what}");
}

/// Spawns the task that audits the peers revoked since `session` opened under `opened`, at every reload (from
/// `reloads`) and as they connect, until `stop`.
pub(crate) async fn spawn(
    session: &Session,
    opened: Arc<Access>,
    mut reloads: watch::Receiver<Option<Arc<Access>>>,
    stop: CancellationToken,
) -> Result<JoinHandle<()>, ServerError> {
    let links = session
        .info()
        .link_events_listener()
        .await
        .map_err(|e| ServerError::Internal(format!("zenoh: cannot listen to link events: {e}")))?;
    let session = session.clone();
    Ok(tokio::spawn(async move {
        loop {
            tokio::select! {
                _ = stop.cancelled() => break,
                changed = reloads.changed() => {
                    if changed.is_err() {
                        break;
                    }
                    let now = reloads.borrow_and_update().clone();
                    let n = audit_links(&session, &opened, now.as_deref()).await;
                    debug!(revoked_links = n, "zenoh links checked against the reloaded access file");
                }
                event = links.recv_async() => {
                    let Ok(event) = event else { break };
                    if event.kind() != SampleKind::Put {
                        continue;
                    }
                    let link = event.link();
                    let now = reloads.borrow().clone();
                    if let Some(name) = link.auth_identifier().and_then(|cn| revoked(&opened, now.as_deref(), cn)) {
                        audit::refused(name, "zenoh session", &format_args!(
                            "{REASON}: a new session connected (common name `{}`, zid {}, from {})",
                            link.auth_identifier().unwrap_or_default(), link.zid(), link.dst()
                        ));
                    }
                }
            }
        }
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_peer_is_revoked_when_its_identity_goes_or_loses_rights() {
        let file = |role: &str, cells: &str| {
            let robots = if role == "robot" { "robots = [\"eyes\"]\n" } else { "" };
            Access::parse(&format!(
                "[[identity]]\nname = \"eyes\"\nrole = \"{role}\"\ncells = [{cells}]\n{robots}cert_common_name = \"eyes-cn\"\n"
            ))
            .unwrap()
        };
        let opened = file("perception", "\"a\", \"b\"");
        assert_eq!(revoked(&opened, None, "eyes-cn"), Some("eyes"));
        assert_eq!(revoked(&opened, Some(&file("perception", "\"a\"")), "eyes-cn"), Some("eyes"), "narrowed");
        assert_eq!(revoked(&opened, Some(&file("perception", "\"a\", \"b\", \"c\"")), "eyes-cn"), None);
        assert_eq!(revoked(&opened, Some(&file("perception", "\"c\"")), "eyes-cn"), Some("eyes"));
        assert_eq!(revoked(&opened, Some(&file("observer", "\"a\"")), "eyes-cn"), Some("eyes"));
        assert_eq!(revoked(&opened, Some(&file("robot", "\"a\"")), "eyes-cn"), Some("eyes"));
        assert_eq!(revoked(&opened, Some(&opened), "eyes-cn"), None);
        assert_eq!(revoked(&opened, None, "stranger"), None, "never had rights");
    }
}
