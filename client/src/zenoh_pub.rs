//! Publishing obstacles over Zenoh, for perception nodes (and `dmpctl scene put --via zenoh`).
//!
//! Keys are `dmp/<cell>/obstacles/<obstacle-id>` (`dmp_proto::keys`): a put adds or replaces the obstacle, a delete
//! removes it. The payload is either the JSON obstacle of the scenario format (plus optional `margin` and `ttl_s`),
//! encoding `application/json`, or the protobuf `dmp.v1.Obstacle`, encoding `application/protobuf`. The session is
//! configured by `dmp_proto::zenoh_session`, as the server's is.
//!
//! Zenoh drops a put made before the subscriber is known to the publisher: call
//! [`ObstaclePublisher::wait_for_subscriber`] once after opening, before the first put. Puts use congestion control
//! `Block` and [`ObstaclePublisher::close`] closes the session gracefully, so a short-lived program loses nothing.
//! `zenoh::open` needs tokio's multi-threaded runtime.
//!
//! A server that starts (or reconnects) after an obstacle was published must still get it.
//! [`ObstaclePublisher::serve_latest`] keeps the latest payload of every key put (a delete forgets it, and so does
//! the end of its `ttl_s`) and sends it again in two ways, as Zenoh topologies differ in which one reaches the
//! server:
//! - it answers the server's catch-up query on `dmp/*/obstacles/**` (the server connects to the node, or the node
//!   was known when the server started);
//! - it puts them again every time a subscriber of the cell's obstacles appears (the node connects to the server,
//!   or reaches it through a router, and the server (re)started or came back after the link was lost). A put and
//!   a resend are serialised, so a resend never brings back a deleted obstacle.
//!
//! The other way is a zenohd storage of `dmp/*/obstacles/**` (see docs/server.md).

use std::collections::BTreeMap;
use std::fmt;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use dmp::scenario::ObstacleSpec;
use dmp_proto::keys::{check_name, obstacle_key, obstacles_of};
use dmp_proto::obstacle_json::JsonObstacle;
use dmp_proto::zenoh_session::{SessionOptions, session_config};
use dmp_proto::{codec, v1};
use zenoh::Wait;
use zenoh::bytes::Encoding;
use zenoh::key_expr::KeyExpr;
use zenoh::pubsub::Publisher;
use zenoh::qos::CongestionControl;
use zenoh::query::{Query, Queryable};

use crate::error::ClientError;

fn zerr(context: &str) -> impl FnOnce(zenoh::Error) -> ClientError + '_ {
    move |e| ClientError::Zenoh(format!("{context}: {e}"))
}

/// `opened`, or its error with the reason when a `tcp/` endpoint of `connect` listens with TLS (plaintext against
/// TLS fails after a timeout, saying only that it could not connect).
async fn with_tls_hint<T>(opened: Result<T, ClientError>, connect: &[String]) -> Result<T, ClientError> {
    let Err(ClientError::Zenoh(message)) = opened else { return opened };
    for endpoint in connect {
        let Some(addr) = endpoint.strip_prefix("tcp/") else { continue };
        let addr = addr.split(['#', '?']).next().unwrap_or(addr);
        if crate::tls_probe::speaks_tls(addr).await {
            return Err(ClientError::Zenoh(format!(
                "{addr} listens with TLS (the server's Zenoh is secured), and `{endpoint}` is plaintext: connect \
                 to tls/{addr} with the CA and a certificate, e.g. --zenoh-config zenoh-perception.json5 as \
                 `dmp-server access init` writes it ({message})"
            )));
        }
    }
    Err(ClientError::Zenoh(message))
}

/// What a publishing peer opens with. With `connect` endpoints, scouting is off, opening fails fast if they cannot
/// be reached, and only the `listen` endpoints are listened on (none: nothing, a publisher needs no port); without,
/// multicast scouting finds the server on the LAN and Zenoh's default `listen` applies unless some are given.
pub(crate) fn publisher_options(connect: &[String], listen: &[String]) -> SessionOptions {
    SessionOptions {
        mode: "peer".into(),
        listen: (!connect.is_empty() || !listen.is_empty()).then(|| listen.to_vec()),
        connect: connect.to_vec(),
        multicast_scouting: connect.is_empty(),
        config_file: None,
        tls: None,
        access_control: None,
    }
}

/// What was last put on a key: its encoding, its payload, and when its `ttl_s` ends (`None`: never).
#[derive(Clone)]
struct Put {
    encoding: Encoding,
    bytes: Vec<u8>,
    expires: Option<Instant>,
}

impl Put {
    fn new(encoding: Encoding, bytes: Vec<u8>, ttl_s: f64) -> Self {
        let expires = (ttl_s > 0.0)
            .then(|| Duration::try_from_secs_f64(ttl_s).ok())
            .flatten()
            .and_then(|ttl| Instant::now().checked_add(ttl));
        Self { encoding, bytes, expires }
    }

    fn live(&self, now: Instant) -> bool {
        self.expires.is_none_or(|t| now < t)
    }
}

/// The latest put on each key.
type Latest = BTreeMap<String, Put>;

/// A Zenoh peer that publishes the obstacles of one cell.
pub struct ObstaclePublisher {
    cell: String,
    session: zenoh::Session,
    /// Declared on `dmp/<cell>/obstacles/*` and never put on: its matching status says whether a subscriber of the
    /// cell's obstacles is known.
    probe: Publisher<'static>,
    /// The latest payload put on each key (deletes remove them), for [`ObstaclePublisher::serve_latest`]. The lock
    /// is held to update or copy, never across an await.
    latest: Arc<Mutex<Latest>>,
    /// Answers queries with `latest`, once [`ObstaclePublisher::serve_latest`] was called.
    queryable: Option<Queryable<()>>,
    /// Puts `latest` again when a subscriber appears, once [`ObstaclePublisher::serve_latest`] was called.
    resender: Option<tokio::task::JoinHandle<()>>,
    /// Held across each put or delete and across a resend, so that they reach the subscribers in order.
    sending: Arc<tokio::sync::Mutex<()>>,
}

impl Drop for ObstaclePublisher {
    fn drop(&mut self) {
        if let Some(task) = self.resender.take() {
            task.abort();
        }
    }
}

impl fmt::Debug for ObstaclePublisher {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("ObstaclePublisher")
            .field("cell", &self.cell)
            .field("zid", &self.session.zid())
            .finish()
    }
}

impl ObstaclePublisher {
    /// Opens a peer session for `cell`. With `connect` endpoints, scouting is off, opening fails fast if they cannot
    /// be reached, and only the `listen` endpoints are listened on (none: nothing, a publisher needs no port);
    /// without, multicast scouting finds the server on the LAN and Zenoh's default `listen` applies unless some
    /// are given.
    pub async fn open(cell: &str, connect: &[String], listen: &[String]) -> Result<Self, ClientError> {
        let opened = Self::open_with(cell, session_config(&publisher_options(connect, listen))?).await;
        with_tls_hint(opened, connect).await
    }

    /// Opens a session from a stock Zenoh configuration file (JSON5: endpoints, TLS, credentials), as
    /// `access init` writes for a perception node; `connect` endpoints, when given, replace the file's.
    pub async fn open_from_file(
        cell: &str,
        file: &std::path::Path,
        connect: &[String],
    ) -> Result<Self, ClientError> {
        let mut config = zenoh::Config::from_file(file)
            .map_err(|e| ClientError::argument("zenoh-config", format!("{}: {e}", file.display())))?;
        if !connect.is_empty() {
            let endpoints = SessionOptions { connect: connect.to_vec(), ..publisher_options(connect, &[]) };
            // Checked and set as every session's are.
            let checked = session_config(&endpoints)?;
            let value = checked
                .get_json("connect/endpoints")
                .map_err(|e| ClientError::argument("zenoh-connect", e.to_string()))?;
            config
                .insert_json5("connect/endpoints", &value)
                .map_err(|e| ClientError::argument("zenoh-connect", e.to_string()))?;
        }
        with_tls_hint(Self::open_with(cell, config).await, connect).await
    }

    /// Opens a session with a given configuration.
    pub async fn open_with(cell: &str, config: zenoh::Config) -> Result<Self, ClientError> {
        check_name("cell", cell)?;
        let session = zenoh::open(config).await.map_err(zerr("opening the session"))?;
        let probe =
            session.declare_publisher(obstacles_of(cell)).await.map_err(zerr("declaring the publisher"))?;
        Ok(Self {
            cell: cell.into(),
            session,
            probe,
            latest: Arc::default(),
            queryable: None,
            resender: None,
            sending: Arc::default(),
        })
    }

    /// The cell.
    pub fn cell(&self) -> &str {
        &self.cell
    }

    /// The session (e.g. to read its locators).
    pub fn session(&self) -> &zenoh::Session {
        &self.session
    }

    /// Serves the latest payload of every obstacle this publisher put and did not delete, before and after this
    /// call, to a server that (re)starts or reconnects: answers queries on `dmp/*/obstacles/**` with them, and puts
    /// them again each time a subscriber of the cell's obstacles appears (see the module). Idempotent.
    pub async fn serve_latest(&mut self) -> Result<(), ClientError> {
        if self.queryable.is_some() {
            return Ok(());
        }
        let latest = self.latest.clone();
        let queryable = self
            .session
            .declare_queryable(format!("{}/**", obstacles_of(dmp_proto::keys::EVERY_CELL)))
            .callback(move |query| reply_latest(&latest, &query))
            .await
            .map_err(zerr("declaring the queryable"))?;
        let listener = self.probe.matching_listener().await.map_err(zerr("matching listener"))?;
        let mut matching = self.probe.matching_status().await.map_err(zerr("matching status"))?.matching();
        let (session, latest, sending) = (self.session.clone(), self.latest.clone(), self.sending.clone());
        self.resender = Some(tokio::spawn(async move {
            while let Ok(status) = listener.recv_async().await {
                if status.matching() && !matching {
                    let _order = sending.lock().await;
                    for (key, put) in live(&latest) {
                        // Fails only when the session is closing: there is no one left to send to.
                        let _ = session
                            .put(key, put.bytes)
                            .encoding(put.encoding)
                            .congestion_control(CongestionControl::Block)
                            .await;
                    }
                }
                matching = status.matching();
            }
        }));
        self.queryable = Some(queryable);
        Ok(())
    }

    /// Remembers what is put on `key` (or forgets it) and sends it, in order with the other sends and resends.
    async fn send(&self, key: String, put: Option<Put>) -> Result<(), ClientError> {
        let _order = self.sending.lock().await;
        {
            let mut map = self.latest.lock().unwrap_or_else(|p| p.into_inner());
            match &put {
                Some(p) => map.insert(key.clone(), p.clone()),
                None => map.remove(&key),
            };
        }
        let context = if put.is_some() { "put" } else { "delete" };
        let sent = match put {
            Some(Put { encoding, bytes, .. }) => {
                self.session
                    .put(key, bytes)
                    .encoding(encoding)
                    .congestion_control(CongestionControl::Block)
                    .await
            }
            None => self.session.delete(key).congestion_control(CongestionControl::Block).await,
        };
        sent.map_err(zerr(context))
    }

    /// Waits until a subscriber of the cell's obstacles (the server) is known, at most `timeout`.
    pub async fn wait_for_subscriber(&self, timeout: Duration) -> Result<(), ClientError> {
        let listener = self.probe.matching_listener().await.map_err(zerr("matching listener"))?;
        if self.probe.matching_status().await.map_err(zerr("matching status"))?.matching() {
            return Ok(());
        }
        let matched = async {
            while let Ok(status) = listener.recv_async().await {
                if status.matching() {
                    return true;
                }
            }
            false
        };
        match tokio::time::timeout(timeout, matched).await {
            Ok(true) => Ok(()),
            _ => Err(ClientError::Zenoh(format!(
                "no subscriber of {} after {timeout:?}: is the server running with Zenoh on, in this cell, and \
                 reachable (--zenoh-connect)?",
                obstacles_of(&self.cell)
            ))),
        }
    }

    /// Puts a JSON obstacle under `id` (its own `id`, if any, should be the same).
    pub async fn put_json(&self, id: &str, obstacle: &serde_json::Value) -> Result<(), ClientError> {
        check_name("id", id)?;
        let bytes =
            serde_json::to_vec(obstacle).map_err(|e| ClientError::argument("obstacle", e.to_string()))?;
        let ttl_s = obstacle.get("ttl_s").and_then(serde_json::Value::as_f64).unwrap_or(0.0);
        self.send(obstacle_key(&self.cell, id), Some(Put::new(Encoding::APPLICATION_JSON, bytes, ttl_s)))
            .await
    }

    /// Puts a scenario-format obstacle with an optional time to live (seconds; 0: forever).
    pub async fn put_spec(&self, spec: &ObstacleSpec, ttl_s: f64) -> Result<(), ClientError> {
        self.put_obstacle(&JsonObstacle { spec: spec.clone(), margin: 0.0, ttl_s }).await
    }

    /// Puts a JSON obstacle (e.g. read with [`JsonObstacle::parse`]).
    pub async fn put_obstacle(&self, obstacle: &JsonObstacle) -> Result<(), ClientError> {
        self.put_json(&obstacle.spec.id, &obstacle.to_json()).await
    }

    /// Puts a protobuf obstacle (encoding `application/protobuf`) under its id.
    pub async fn put_proto(&self, obstacle: &v1::Obstacle) -> Result<(), ClientError> {
        self.put_proto_in(&self.cell, obstacle).await
    }

    /// Puts a protobuf obstacle under its id in another cell than the publisher's (the server subscribes to every
    /// cell's obstacles, so [`ObstaclePublisher::wait_for_subscriber`] on one cell covers the others).
    pub async fn put_proto_in(&self, cell: &str, obstacle: &v1::Obstacle) -> Result<(), ClientError> {
        check_name("cell", cell)?;
        check_name("id", &obstacle.id)?;
        let put = Put::new(Encoding::from(codec::PROTOBUF_ENCODING), codec::encode(obstacle), obstacle.ttl_s);
        self.send(obstacle_key(cell, &obstacle.id), Some(put)).await
    }

    /// Removes the obstacle `id`.
    pub async fn delete(&self, id: &str) -> Result<(), ClientError> {
        check_name("id", id)?;
        self.send(obstacle_key(&self.cell, id), None).await
    }

    /// Closes the session gracefully (what was put is sent first).
    pub async fn close(mut self) -> Result<(), ClientError> {
        if let Some(task) = self.resender.take() {
            task.abort();
        }
        drop(self.queryable.take());
        self.session.close().await.map_err(zerr("close"))
    }
}

/// A copy (taken under the lock) of the remembered puts whose `ttl_s` has not ended.
fn live(latest: &Mutex<Latest>) -> Vec<(KeyExpr<'static>, Put)> {
    let now = Instant::now();
    let map = latest.lock().unwrap_or_else(|p| p.into_inner());
    map.iter()
        .filter(|(_, put)| put.live(now))
        .filter_map(|(key, put)| Some((KeyExpr::try_from(key.clone()).ok()?, put.clone())))
        .collect()
}

/// Replies to `query` with every live remembered payload whose key it asks for.
fn reply_latest(latest: &Mutex<Latest>, query: &Query) {
    for (key, put) in live(latest).into_iter().filter(|(key, _)| query.key_expr().intersects(key)) {
        // A reply fails only when the session is closing: there is no one left to answer.
        let _ = query.reply(key, put.bytes).encoding(put.encoding).wait();
    }
}

#[cfg(test)]
mod tests;
