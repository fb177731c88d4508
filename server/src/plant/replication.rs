//! Replicated primitives: every version stored on a server of the plant is put on
//! `dmp/@primitives/<robot-id>/<name>/<version>` (`dmp.v1.PrimitiveRecord`, protobuf), and a delete is a Zenoh
//! delete on `dmp/@primitives/<robot-id>/<name>/<N>`: its tombstone, every version up to `N` deleted
//! (`store/tombstones.rs` has the order rule and the retention). Every server subscribes and stores what it lacks
//! in its redb store ([`Store::insert_replica`], [`Store::apply_tombstone`]). A queryable over the store answers
//! every version and every tombstone it holds (a tombstone as a delete reply), and a querier asks the other
//! servers' queryables on start and each time one (re)appears (its matching status going from none to some), so a
//! server that starts late or comes back catches up, deletes included. Versions and tombstones commute: whatever
//! order they arrive in, a version up to a tombstone is deleted and a later one kept. What arrives is checked as a Put is (names, the
//! primitive's ranges and `limits`, the message size), and a version or tombstone stamped more than the HLC's bound
//! ahead of this server's clock is refused (forged numbers, `store/tombstones.rs`): a refused record is logged
//! (its key, claimed origin, the Zenoh id that stamped it and, when that session is linked to this one, its
//! certificate's common name), audited (`replicate`) and counted, never stored.
//!
//! Only servers may publish on these keys: the access control generated from the access file allows them to server
//! identities alone ([`crate::access::zenoh_acl`]).

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

use dmp_proto::keys::{check_name, every_primitive, parse_primitive_key, primitive_version_key};
use dmp_proto::{codec, v1};
use tokio::sync::mpsc::UnboundedSender;
use tokio::task::JoinHandle;
use tokio_util::sync::CancellationToken;
use tracing::{debug, info, warn};
use zenoh::Session;
use zenoh::bytes::Encoding;
use zenoh::key_expr::KeyExpr;
use zenoh::pubsub::Subscriber;
use zenoh::query::{ConsolidationMode, Query, QueryTarget, Queryable};
use zenoh::sample::{Locality, Sample, SampleKind};

use crate::config::RequestLimits;
use crate::error::ServerError;
use crate::store::{Store, Tombstone};
use crate::wire::primitive_from_proto;

/// How long a catch-up query waits for replies.
const QUERY_TIMEOUT: Duration = Duration::from_secs(5);

/// Puts the versions this server stores, for the others. Cheap to clone.
#[derive(Debug, Clone)]
pub(crate) struct Replicator {
    session: Session,
}

/// The replication of one server's store: its subscriber, queryable and tasks.
#[derive(Debug)]
pub(crate) struct Replication {
    replicator: Replicator,
    subscriber: Subscriber<()>,
    queryable: Queryable<zenoh::handlers::FifoChannelHandler<Query>>,
    tasks: Vec<JoinHandle<()>>,
    stored: Arc<AtomicU64>,
    refused: Arc<AtomicU64>,
}

impl Replication {
    pub(super) async fn start(
        session: &Session,
        store: Store,
        limits: RequestLimits,
        shutdown: CancellationToken,
    ) -> Result<Self, ServerError> {
        let zenoh_err = |e: zenoh::Error| ServerError::Internal(format!("zenoh: primitive replication: {e}"));
        let (tx, mut rx) = tokio::sync::mpsc::unbounded_channel::<Sample>();
        let on_sample = tx.clone();
        let subscriber = session
            .declare_subscriber(every_primitive())
            .allowed_origin(Locality::Remote)
            .callback(move |s| {
                let _ = on_sample.send(s);
            })
            .await
            .map_err(zenoh_err)?;
        let queryable = session
            .declare_queryable(every_primitive())
            .allowed_origin(Locality::Remote)
            .await
            .map_err(zenoh_err)?;
        let (stored, refused) = (Arc::new(AtomicU64::new(0)), Arc::new(AtomicU64::new(0)));
        let mut tasks = Vec::new();
        // Applies what arrives, in order, one store transaction each.
        let (st, counts, on) = (store.clone(), (stored.clone(), refused.clone()), session.clone());
        tasks.push(tokio::spawn(async move {
            while let Some(sample) = rx.recv().await {
                apply(&on, &st, &limits, &sample, &counts).await;
            }
        }));
        // Answers the other servers' catch-up queries.
        let answers = queryable.handler().clone();
        let (st, stop) = (store, shutdown.clone());
        tasks.push(tokio::spawn(async move {
            loop {
                let query = tokio::select! {
                    _ = stop.cancelled() => break,
                    q = answers.recv_async() => match q { Ok(q) => q, Err(_) => break },
                };
                answer(&st, query).await;
            }
        }));
        tasks.push(catch_up(session, tx, shutdown).await?);
        let replicator = Replicator { session: session.clone() };
        Ok(Self { replicator, subscriber, queryable, tasks, stored, refused })
    }

    /// What puts this server's versions.
    pub(crate) fn replicator(&self) -> Replicator {
        self.replicator.clone()
    }

    /// Versions received from other servers and stored so far, and those refused.
    pub(crate) fn counts(&self) -> (u64, u64) {
        (self.stored.load(Ordering::Relaxed), self.refused.load(Ordering::Relaxed))
    }

    pub(super) async fn close(self) {
        let Self { subscriber, queryable, tasks, .. } = self;
        for t in &tasks {
            t.abort();
        }
        if let Err(e) = subscriber.undeclare().await {
            debug!(error = %e, "plant: subscriber undeclare failed (session closed?)");
        }
        if let Err(e) = queryable.undeclare().await {
            debug!(error = %e, "plant: queryable undeclare failed (session closed?)");
        }
    }
}

impl Replicator {
    /// Puts a version this server stored; the others store it. A Zenoh error is logged: the version is durable
    /// here, and the others get it when they next catch up.
    pub(crate) async fn publish(&self, record: &v1::PrimitiveRecord) {
        let key = primitive_version_key(&record.robot_id, &record.name, record.version);
        let sent = self
            .session
            .put(&key, codec::encode(record))
            .encoding(Encoding::APPLICATION_PROTOBUF)
            .allowed_destination(Locality::Remote)
            .await;
        match sent {
            Ok(()) => debug!(key, "plant: primitive replicated"),
            Err(e) => warn!(key, error = %e, "plant: primitive not replicated"),
        }
    }

    /// Tells the others that every version of the tombstone's name up to its `up_to` was deleted here.
    pub(crate) async fn publish_delete(&self, t: &Tombstone) {
        let key = primitive_version_key(&t.robot_id, &t.name, t.up_to);
        if let Err(e) = self.session.delete(&key).allowed_destination(Locality::Remote).await {
            warn!(key, error = %e, "plant: primitive delete not replicated");
        }
    }
}

/// Declares the catch-up querier and spawns the task that asks the other servers on start and whenever one
/// (re)appears; the replies go to `tx` as samples do.
async fn catch_up(
    session: &Session,
    tx: UnboundedSender<Sample>,
    stop: CancellationToken,
) -> Result<JoinHandle<()>, ServerError> {
    let zenoh_err = |e: zenoh::Error| ServerError::Internal(format!("zenoh: primitive catch-up: {e}"));
    let querier = session
        .declare_querier(every_primitive())
        .target(QueryTarget::All)
        .consolidation(ConsolidationMode::None)
        .allowed_destination(Locality::Remote)
        .timeout(QUERY_TIMEOUT)
        .await
        .map_err(zenoh_err)?;
    let listener = querier.matching_listener().await.map_err(zenoh_err)?;
    Ok(tokio::spawn(async move {
        // The listener reports the current status first, then every change.
        let mut matching = false;
        loop {
            tokio::select! {
                _ = stop.cancelled() => break,
                status = listener.recv_async() => match status {
                    Ok(s) if s.matching() && !matching => {
                        matching = true;
                        let on_reply = tx.clone();
                        let sent = querier
                            .get()
                            .callback(move |reply| {
                                if let Ok(sample) = reply.result() {
                                    let _ = on_reply.send(sample.clone());
                                }
                            })
                            .await;
                        match sent {
                            Ok(()) => info!("plant: primitives asked of the other servers"),
                            Err(e) => warn!(error = %e, "plant: primitive catch-up query failed"),
                        }
                    }
                    Ok(s) => matching = s.matching(),
                    Err(_) => break,
                },
            }
        }
        // The matching listener before its querier (the other way round, zenoh logs an ERROR at shutdown).
        drop(listener);
        drop(querier);
    }))
}

/// Stores (or deletes) what one sample says, after checking it.
async fn apply(
    session: &Session,
    store: &Store,
    limits: &RequestLimits,
    sample: &Sample,
    (stored, refused): &(Arc<AtomicU64>, Arc<AtomicU64>),
) {
    let key = sample.key_expr().as_str().to_owned();
    let checked = check(limits, sample);
    // Who sent it, as far as the sample says: the origin its record claims, the Zenoh session that put it (when
    // it attached its source info; Zenoh does not hand the authenticated identity to the application).
    let origin = match &checked {
        Ok(Incoming::Version(r)) => r.origin_server.clone(),
        _ => String::new(),
    };
    let source = sample.source_info().map(|s| s.source_id().zid().to_string()).unwrap_or_default();
    let store = store.clone();
    let done = tokio::task::spawn_blocking(move || match checked? {
        Incoming::Version(record) => store.insert_replica(&record),
        Incoming::Delete(t) => store.apply_tombstone(&t),
    })
    .await
    .unwrap_or_else(|e| Err(ServerError::Internal(e.to_string())));
    match done {
        Ok(true) => {
            stored.fetch_add(1, Ordering::Relaxed);
            debug!(key, "plant: replicated primitive stored");
        }
        Ok(false) => debug!(key, "plant: replicated primitive held already"),
        Err(e) => {
            refused.fetch_add(1, Ordering::Relaxed);
            let (stamped_by, sender) = sender(session, sample).await;
            warn!(key, origin, source, stamped_by, sender, reason = %e, "plant: replicated primitive refused");
            let who = if sender.is_empty() { crate::access::audit::ZENOH_PEER } else { sender.as_str() };
            let reason = format_args!("{key} (claimed origin `{origin}`, stamped by `{stamped_by}`): {e}");
            crate::access::audit::refused(who, "replicate", &reason);
        }
    }
}

/// Who sent a sample, as far as this server knows: the Zenoh id whose clock stamped it (the sending session's, or
/// a router's that stamped it on the way), and, when that session is linked to this one, the common name of its
/// verified certificate (empty when unknown). Zenoh does not say which link a sample came in on: a session may
/// stamp with another's id, so the name is a lead for the operator, not a proof.
async fn sender(session: &Session, sample: &Sample) -> (String, String) {
    let Some(stamp) = sample.timestamp() else { return (String::new(), String::new()) };
    let zid = stamp.get_id().to_string();
    let cn = session
        .info()
        .links()
        .await
        .find(|l| l.zid().to_string() == zid)
        .and_then(|l| l.auth_identifier().map(str::to_owned))
        .unwrap_or_default();
    (zid, cn)
}

/// What a replication sample asks for.
enum Incoming {
    Version(Box<v1::PrimitiveRecord>),
    Delete(Tombstone),
}

/// Checks a sample as a Put is checked: the key, the names, the record matching its key, the primitive's ranges.
fn check(limits: &RequestLimits, sample: &Sample) -> Result<Incoming, ServerError> {
    let key = sample.key_expr().as_str();
    let names = parse_primitive_key(key)
        .ok_or_else(|| ServerError::invalid("key", "is not dmp/@primitives/<robot-id>/<name>[/<version>]"))?;
    check_name("robot_id", names.robot_id)?;
    check_name("name", names.name)?;
    let (robot_id, name) = (names.robot_id.to_owned(), names.name.to_owned());
    match (sample.kind(), names.version) {
        (SampleKind::Delete, Some(up_to)) if up_to > 0 => {
            Ok(Incoming::Delete(Tombstone { robot_id, name, up_to }))
        }
        (SampleKind::Put, Some(version)) => {
            if sample.payload().len() > limits.max_message_bytes {
                return Err(ServerError::ResourceExhausted(format!(
                    "a record of {} bytes, more than limits.max_message_bytes = {}",
                    sample.payload().len(),
                    limits.max_message_bytes
                )));
            }
            let record: v1::PrimitiveRecord = codec::decode(&sample.payload().to_bytes()).map_err(|e| {
                ServerError::invalid("payload", format!("is not a dmp.v1.PrimitiveRecord: {e}"))
            })?;
            if record.robot_id != robot_id || record.name != name || record.version != version || version == 0
            {
                return Err(ServerError::invalid(
                    "payload",
                    "names another robot, primitive or version than its key",
                ));
            }
            let proto =
                record.primitive.as_ref().ok_or_else(|| ServerError::invalid("primitive", "is required"))?;
            primitive_from_proto(proto, limits)?.validate()?;
            Ok(Incoming::Version(Box::new(record)))
        }
        _ => Err(ServerError::invalid("key", "a put or a delete names a version (not 0)")),
    }
}

/// Answers a catch-up query with every stored tombstone (a delete reply) and version whose key it asks for.
async fn answer(store: &Store, query: Query) {
    let asked: KeyExpr<'static> = query.key_expr().clone().into_owned();
    let store = store.clone();
    let read = move || Ok::<_, ServerError>((store.all_tombstones()?, store.all_records()?));
    let (tombstones, records) = match tokio::task::spawn_blocking(read).await {
        Ok(Ok(r)) => r,
        Ok(Err(e)) => return warn!(error = %e, "plant: cannot read the store for a catch-up query"),
        Err(e) => return warn!(error = %e, "plant: catch-up answer failed"),
    };
    let mut sent = 0;
    for t in tombstones {
        let key = primitive_version_key(&t.robot_id, &t.name, t.up_to);
        let Ok(k) = KeyExpr::try_from(key.as_str()) else { continue };
        if !asked.intersects(&k) {
            continue;
        }
        match query.reply_del(k).await {
            Ok(()) => sent += 1,
            Err(e) => return warn!(error = %e, "plant: catch-up answer cut short"),
        }
    }
    for r in records {
        let key = primitive_version_key(&r.robot_id, &r.name, r.version);
        let Ok(k) = KeyExpr::try_from(key.as_str()) else { continue };
        if !asked.intersects(&k) {
            continue;
        }
        match query.reply(k, codec::encode(&r)).encoding(Encoding::APPLICATION_PROTOBUF).await {
            Ok(()) => sent += 1,
            Err(e) => return warn!(error = %e, "plant: catch-up answer cut short"),
        }
    }
    debug!(asked = %asked, sent, "plant: catch-up query answered");
}
