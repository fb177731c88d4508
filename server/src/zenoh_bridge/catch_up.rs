//! Catching up with the obstacles published before the server (re)started or while it was cut off: a Zenoh
//! querier on `dmp/*/obstacles/**` (every cell, as the subscriber) asks every matching queryable (perception
//! nodes serving their latest obstacles, `dmp_client::zenoh_pub::ObstaclePublisher::serve_latest`, or a zenohd
//! storage) and applies each reply as a published sample.
//!
//! When: on start if a queryable is already known, and every time the querier's matching status goes from "no
//! queryable" to "some queryable" (a perception node or a router with a storage appeared, or came back after the
//! connection to it was lost and Zenoh reconnected). The matching status changes only once the queryable's
//! declaration has arrived, so the query reaches it. A perception node that answers while others already do is
//! not asked again: it sends its obstacles anyway when it (re)starts.
//!
//! Tested end to end (`tests/tests/server/catch_up.rs`): the server connecting to a perception node, a node
//! connecting to the server across a server restart, and a server joining a router (as its client) after the node.
//! The client library's node also puts its obstacles again when the server's subscriber appears, a second way for
//! the cases this query would miss.

use std::time::Duration;

use dmp_proto::keys::{EVERY_CELL, obstacles_of};
use tokio::task::JoinHandle;
use tokio_util::sync::CancellationToken;
use tracing::{debug, info, warn};
use zenoh::Session;
use zenoh::query::{ConsolidationMode, Querier, QueryTarget};

use super::SceneUpdater;
use crate::error::ServerError;

/// How long a catch-up query waits for replies.
pub(crate) const QUERY_TIMEOUT: Duration = Duration::from_secs(5);

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
    let mut matching = querier.matching_status().await.map_err(zenoh_err)?.matching();
    if matching {
        query(&querier, &updater, "start").await;
    }
    Ok(tokio::spawn(async move {
        loop {
            tokio::select! {
                _ = stop.cancelled() => break,
                status = listener.recv_async() => match status {
                    Ok(s) if s.matching() && !matching => {
                        matching = true;
                        query(&querier, &updater, "a queryable appeared").await;
                    }
                    Ok(s) => matching = s.matching(),
                    Err(_) => break,
                },
            }
        }
        if let Err(e) = querier.undeclare().await {
            debug!(error = %e, "zenoh querier undeclare failed (session closed?)");
        }
    }))
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
