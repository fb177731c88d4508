//! Discovery: this server's liveliness token and queryable on `dmp/@servers/<server-id>`, a queryable per cell it
//! serves on `dmp/@cells/<cell>`, all answering its `dmp.v1.PlantServer` (protobuf); and the [`Directory`] of the
//! plant's live servers, kept from their tokens (with history: those declared before this server started count
//! too) and the answers of their queryables.

use std::time::Duration;

use dmp_proto::keys::{cell_server_key, every_server, parse_server_key, server_key};
use dmp_proto::{codec, v1};
use tokio::task::JoinHandle;
use tokio_util::sync::CancellationToken;
use tracing::{debug, info, warn};
use zenoh::bytes::Encoding;
use zenoh::liveliness::LivelinessToken;
use zenoh::pubsub::Subscriber;
use zenoh::query::Queryable;
use zenoh::sample::SampleKind;
use zenoh::{Session, Wait};

use crate::cells::directory::Directory;
use crate::error::ServerError;

/// How long the directory waits for a server's answer.
const ASK_TIMEOUT: Duration = Duration::from_secs(5);

/// The token, the queryables and the directory's subscriber of one server.
#[derive(Debug)]
pub(crate) struct Discovery {
    token: LivelinessToken,
    queryables: Vec<Queryable<()>>,
    servers: Subscriber<()>,
    directory_task: JoinHandle<()>,
}

impl Discovery {
    /// Declares the queryables, then the token (so that whoever sees the token can ask), and starts the directory.
    pub(super) async fn start(
        session: &Session,
        server: &v1::PlantServer,
        directory: Directory,
        shutdown: CancellationToken,
    ) -> Result<Self, ServerError> {
        let zenoh_err = |e: zenoh::Error| ServerError::Internal(format!("zenoh: plant discovery: {e}"));
        let answer = codec::encode(server);
        let own_key = server_key(&server.server_id);
        let keys = std::iter::once(own_key.clone()).chain(server.cells.iter().map(|c| cell_server_key(c)));
        let mut queryables = Vec::new();
        for key in keys {
            let payload = answer.clone();
            let reply_key = key.clone();
            // The server's own key also names the cells whose server is gone, with their homes (read at each
            // query): a server joining meanwhile learns them, whoever serves them now.
            let homes_away = (key == own_key).then(|| (server.clone(), directory.clone()));
            let q = session
                .declare_queryable(&key)
                .callback(move |query| {
                    let away = homes_away.as_ref().map(|(me, d)| (me, d.homes_away()));
                    let payload = match away {
                        Some((me, mut away)) => {
                            // Never its own cells (its directory may not list itself).
                            away.retain(|_, home| *home != me.server_id);
                            if away.is_empty() {
                                payload.clone()
                            } else {
                                let mut me = me.clone();
                                me.homes_away = away;
                                codec::encode(&me)
                            }
                        }
                        _ => payload.clone(),
                    };
                    let sent =
                        query.reply(&reply_key, payload).encoding(Encoding::APPLICATION_PROTOBUF).wait();
                    if let Err(e) = sent {
                        debug!(key = %reply_key, error = %e, "plant: discovery answer not sent");
                    }
                })
                .await
                .map_err(zenoh_err)?;
            queryables.push(q);
        }
        let token =
            session.liveliness().declare_token(server_key(&server.server_id)).await.map_err(zenoh_err)?;
        let (tx, mut rx) = tokio::sync::mpsc::unbounded_channel();
        let servers = session
            .liveliness()
            .declare_subscriber(every_server())
            .history(true)
            .callback(move |sample| {
                if let Some(id) = parse_server_key(sample.key_expr().as_str()) {
                    let _ = tx.send((id.to_owned(), sample.kind()));
                }
            })
            .await
            .map_err(zenoh_err)?;
        let session = session.clone();
        let directory_task = tokio::spawn(async move {
            loop {
                let (id, kind) = tokio::select! {
                    _ = shutdown.cancelled() => break,
                    next = rx.recv() => match next { Some(n) => n, None => break },
                };
                match kind {
                    SampleKind::Put => ask(&session, &directory, &id).await,
                    SampleKind::Delete => {
                        directory.remove(&id);
                        info!(server = %id, "plant: server gone");
                    }
                }
            }
        });
        Ok(Self { token, queryables, servers, directory_task })
    }

    /// Undeclares the token (the others forget this server), the queryables and the subscriber.
    pub(super) async fn close(self) {
        let Self { token, queryables, servers, directory_task } = self;
        directory_task.abort();
        if let Err(e) = token.undeclare().await {
            debug!(error = %e, "plant: token undeclare failed (session closed?)");
        }
        for q in queryables {
            if let Err(e) = q.undeclare().await {
                debug!(error = %e, "plant: queryable undeclare failed (session closed?)");
            }
        }
        if let Err(e) = servers.undeclare().await {
            debug!(error = %e, "plant: subscriber undeclare failed (session closed?)");
        }
    }
}

/// Asks a server that appeared for its announcement and records it.
async fn ask(session: &Session, directory: &Directory, id: &str) {
    let replies = match session.get(server_key(id)).timeout(ASK_TIMEOUT).await {
        Ok(r) => r,
        Err(e) => return warn!(server = %id, error = %e, "plant: cannot ask a server"),
    };
    while let Ok(reply) = replies.recv_async().await {
        let Ok(sample) = reply.result() else { continue };
        match codec::decode::<v1::PlantServer>(&sample.payload().to_bytes()) {
            Ok(s) if s.server_id == id => {
                info!(server = %id, grpc = %s.grpc_address, cells = ?s.cells, "plant: server known");
                directory.insert(s);
                return;
            }
            Ok(s) => warn!(server = %id, answered = %s.server_id, "plant: a server answered for another"),
            Err(e) => warn!(server = %id, error = %e, "plant: malformed server announcement"),
        }
    }
    debug!(server = %id, "plant: a server did not answer (gone already?)");
}
