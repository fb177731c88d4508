//! Catching up with the obstacles published before the server (re)started or while it was cut off: a Zenoh
//! querier on `dmp/*/obstacles/**` (every cell, as the subscriber) asks every matching queryable (perception
//! nodes serving their latest obstacles, `dmp_client::zenoh_pub::ObstaclePublisher::serve_latest`, or a zenohd
//! storage) and applies each reply as a published sample.
//!
//! When: on start if a queryable is already known, every time the querier's matching status goes from "no
//! queryable" to "some queryable" (a perception node or a router with a storage appeared, or came back after the
//! connection to it was lost and Zenoh reconnected), and whenever a peer or router connects to the session: the
//! matching status does not change for a queryable that comes while others answer, and in peer mode it did not
//! change for one declared after its node connected (measured with zenoh 1.10.2: a lone node's queryable on
//! `dmp/default/obstacles/**` was never asked). A new connection's declarations arrive just after it opens, so it is
//! asked at once and again [`AFTER_CONNECT`] later. Each time, every cell's expression is asked, then each served
//! cell's own (`dmp/<cell>/obstacles/**`), so that a node declaring only its cell's obstacles is reached too.
//! Replies are applied as puts: asking twice changes versions, not the scene.
//!
//! Tested end to end (`tests/tests/server/catch_up.rs`): the server connecting to a perception node, a node
//! connecting to the server across a server restart, and a server joining a router (as its client) after the node.
//! The client library's node also puts its obstacles again when the server's subscriber appears, a second way for
//! the cases this query would miss.

use std::collections::BTreeSet;
use std::time::Duration;

use tokio::time::Instant;

use dmp_proto::keys::{EVERY_CELL, obstacles_of};
use tokio::task::JoinHandle;
use tokio_util::sync::CancellationToken;
use tracing::{debug, info, warn};
use zenoh::Session;
use zenoh::query::{ConsolidationMode, Querier, QueryTarget};
use zenoh::sample::SampleKind;

use super::SceneUpdater;
use crate::error::ServerError;

/// How long a catch-up query waits for replies.
pub(crate) const QUERY_TIMEOUT: Duration = Duration::from_secs(5);
/// When a connection is asked again after it opened: its declarations have arrived by then.
pub(crate) const AFTER_CONNECT: [Duration; 2] = [Duration::from_millis(100), Duration::from_secs(1)];

/// Declares the querier and spawns the task that queries on start and on every return of a queryable, until
/// `stop`.
pub(super) async fn spawn(
    session: &Session,
    updater: SceneUpdater,
    stop: CancellationToken,
) -> Result<JoinHandle<()>, ServerError> {
    let zenoh_err =
        |e: zenoh::Error| ServerError::Internal(format!("zenoh: cannot declare the querier: {e}"));
    let querier = session
        .declare_querier(format!("{}/**", obstacles_of(EVERY_CELL)))
        .target(QueryTarget::All)
        .consolidation(ConsolidationMode::None)
        .timeout(QUERY_TIMEOUT)
        .await
        .map_err(zenoh_err)?;
    let listener = querier.matching_listener().await.map_err(zenoh_err)?;
    let connections = session.info().transport_events_listener().await.map_err(zenoh_err)?;
    let mut matching = querier.matching_status().await.map_err(zenoh_err)?.matching();
    let session = session.clone();
    if matching {
        ask(&session, &querier, &updater, "start").await;
    }
    Ok(tokio::spawn(async move {
        // The times the connections that opened are asked again.
        let mut again: BTreeSet<Instant> = BTreeSet::new();
        loop {
            let next = again.first().copied();
            let due = async move {
                match next {
                    Some(at) => tokio::time::sleep_until(at).await,
                    None => std::future::pending().await,
                }
            };
            tokio::select! {
                _ = stop.cancelled() => break,
                status = listener.recv_async() => match status {
                    Ok(s) if s.matching() && !matching => {
                        matching = true;
                        ask(&session, &querier, &updater, "a queryable appeared").await;
                    }
                    Ok(s) => matching = s.matching(),
                    Err(_) => break,
                },
                event = connections.recv_async() => match event {
                    Ok(e) if e.kind() == SampleKind::Put => {
                        ask(&session, &querier, &updater, "a peer or router connected").await;
                        let now = Instant::now();
                        again.extend(AFTER_CONNECT.iter().map(|d| now + *d));
                    }
                    Ok(_) => {}
                    Err(_) => break,
                },
                () = due => {
                    // Several connections due together are asked once.
                    let now = Instant::now();
                    again.retain(|at| *at > now);
                    ask(&session, &querier, &updater, "a connection's declarations arrived").await;
                }
            }
        }
        // The matching listener first: undeclared after its querier, zenoh logs an ERROR that it cannot find it.
        drop(listener);
        if let Err(e) = querier.undeclare().await {
            debug!(error = %e, "zenoh querier undeclare failed (session closed?)");
        }
    }))
}

/// Asks every cell's obstacles, then each served cell's own.
async fn ask(session: &Session, querier: &Querier<'_>, updater: &SceneUpdater, why: &'static str) {
    query(querier, updater, why).await;
    for cell in updater.cells.served().unwrap_or_else(|| vec![updater.cells.default_cell().to_owned()]) {
        let key = format!("{}/**", obstacles_of(&cell));
        let on_reply = updater.clone();
        let sent = session
            .get(&key)
            .target(QueryTarget::All)
            .consolidation(ConsolidationMode::None)
            .timeout(QUERY_TIMEOUT)
            .callback(move |reply| match reply.result() {
                Ok(sample) => on_reply.obstacle(sample),
                Err(e) => debug!(error = ?e.payload().try_to_string(), "catch-up query: error reply"),
            })
            .await;
        if let Err(e) = sent {
            warn!(key, error = %e, "catch-up query failed");
        }
    }
}

/// Sends one query; its replies are applied as they arrive (in Zenoh's callbacks).
async fn query(querier: &Querier<'_>, updater: &SceneUpdater, why: &'static str) {
    let on_reply = updater.clone();
    let sent = querier
        .get()
        .callback(move |reply| match reply.result() {
            Ok(sample) => on_reply.obstacle(sample),
            Err(e) => debug!(error = ?e.payload().try_to_string(), "catch-up query: error reply"),
        })
        .await;
    match sent {
        Ok(()) => info!(key = %querier.key_expr(), why, "obstacles queried"),
        Err(e) => warn!(key = %querier.key_expr(), error = %e, "catch-up query failed"),
    }
}
