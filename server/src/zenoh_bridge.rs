//! The server's Zenoh side: opening the session from [`ZenohConfig`], and the bridge that feeds the cells' scenes
//! (every cell: the bridge subscribes to `dmp/*/...` and a new cell is created on its first sample, up to
//! `limits.max_cells`).
//!
//! | key | payload | effect |
//! | --- | --- | --- |
//! | `dmp/<cell>/obstacles/<obstacle-id>` put | `dmp.v1.Obstacle` (encoding `application/protobuf`) or the JSON obstacle of the scenario format, plus `ttl_s` and `margin` | adds or replaces the obstacle |
//! | `dmp/<cell>/obstacles/<obstacle-id>` delete | | removes it |
//! | `dmp/<cell>/robots/<robot-id>/state` put | `dmp.v1.RobotState` (protobuf) | records the robot, a moving obstacle for the others |
//! | `dmp/<cell>/robots/<robot-id>/state` delete | | forgets the robot |
//!
//! A payload that cannot be decoded or validated is logged at warn with its key and the reason, counted
//! ([`ZenohBridge::malformed_payloads`]) and changes nothing else. Samples are handled in Zenoh's callbacks: decoding
//! and validating one obstacle or robot state takes microseconds and never awaits.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

use dmp_proto::{codec, v1};
use tokio::task::JoinHandle;
use tokio_util::sync::{CancellationToken, DropGuard};
use tracing::{debug, info, warn};
use zenoh::bytes::Encoding;
use zenoh::config::EndPoint;
use zenoh::pubsub::Subscriber;
use zenoh::sample::{Locality, Sample, SampleKind};
use zenoh::{Session, Wait};

use crate::cells::Cells;
use crate::config::ZenohConfig;
use crate::convert::obstacle_from_json;
use crate::error::ServerError;
use crate::robots::check_robot_state;
use crate::scene::now_unix_s;

/// How long opening a session waits for the `connect` endpoints before it fails (only when some are given).
pub const CONNECT_TIMEOUT_MS: u64 = 2000;

/// Period of the reaper that removes obstacles whose time to live has passed.
pub const REAP_PERIOD: Duration = Duration::from_millis(100);

/// Largest obstacle or robot-state payload accepted (larger ones are refused as malformed).
pub const MAX_PAYLOAD_BYTES: usize = 1 << 20;

/// The key of one obstacle: `dmp/<cell>/obstacles/<obstacle-id>`.
pub fn obstacle_key(cell: &str, obstacle_id: &str) -> String {
    format!("dmp/{cell}/obstacles/{obstacle_id}")
}

/// The key of one robot's state: `dmp/<cell>/robots/<robot-id>/state`.
pub fn robot_state_key(cell: &str, robot_id: &str) -> String {
    format!("dmp/{cell}/robots/{robot_id}/state")
}

/// The cell of a key `dmp/<cell>/...` (empty if the key has no such chunk; the subscriptions guarantee one).
fn cell_of(key: &str) -> &str {
    key.split('/').nth(1).unwrap_or_default()
}

/// The Zenoh configuration of [`ZenohConfig`]: mode, listen and connect endpoints, scouting.
///
/// Gossip scouting follows the multicast switch: with it off the session talks only to the endpoints it is given
/// (and to those that connect to it). With `connect` endpoints, opening waits at most [`CONNECT_TIMEOUT_MS`] for
/// them and fails if they cannot be reached, instead of retrying forever in the background; without, Zenoh's
/// defaults apply.
pub fn session_config(cfg: &ZenohConfig) -> Result<zenoh::Config, ServerError> {
    if !matches!(cfg.mode.as_str(), "peer" | "client") {
        return Err(ServerError::invalid(
            "zenoh.mode",
            format!("must be `peer` or `client`, found `{}`", cfg.mode),
        ));
    }
    let endpoints = |field: &str, list: &[String]| -> Result<String, ServerError> {
        for (i, e) in list.iter().enumerate() {
            e.parse::<EndPoint>()
                .map_err(|err| ServerError::invalid(format!("zenoh.{field}[{i}]"), err.to_string()))?;
        }
        Ok(serde_json::to_string(list).expect("a list of strings is JSON"))
    };
    let mut c = zenoh::Config::default();
    let mut set = |key: &str, value: String| -> Result<(), ServerError> {
        c.insert_json5(key, &value)
            .map_err(|e| ServerError::invalid(format!("zenoh config {key}"), e.to_string()))
    };
    set("mode", serde_json::to_string(&cfg.mode).expect("a string is JSON"))?;
    if !cfg.listen.is_empty() {
        set("listen/endpoints", endpoints("listen", &cfg.listen)?)?;
    }
    if !cfg.connect.is_empty() {
        set("connect/endpoints", endpoints("connect", &cfg.connect)?)?;
        set("connect/timeout_ms", CONNECT_TIMEOUT_MS.to_string())?;
        set("connect/exit_on_failure", "true".into())?;
    }
    set("scouting/multicast/enabled", cfg.multicast_scouting.to_string())?;
    set("scouting/gossip/enabled", cfg.multicast_scouting.to_string())?;
    Ok(c)
}

/// Opens the Zenoh session of [`ZenohConfig`] (see [`session_config`]). Fails fast when a `connect` endpoint
/// cannot be reached.
pub async fn open_session(cfg: &ZenohConfig) -> Result<Session, ServerError> {
    let config = session_config(cfg)?;
    let session = zenoh::open(config)
        .await
        .map_err(|e| ServerError::FailedPrecondition(format!("zenoh: cannot open the session: {e}")))?;
    info!(
        zid = %session.zid(),
        mode = %cfg.mode,
        locators = ?locators(&session).await,
        connect = ?cfg.connect,
        multicast_scouting = cfg.multicast_scouting,
        "zenoh session open"
    );
    Ok(session)
}

/// The endpoints the session really listens on (`tcp/127.0.0.1:0` resolved to its port), for peers to connect to.
pub async fn locators(session: &Session) -> Vec<String> {
    session.info().locators().await.into_iter().map(|l| l.to_string()).collect()
}

/// Decodes an obstacle payload whose key names `id_from_key`.
///
/// Encoding `application/protobuf`: a `dmp.v1.Obstacle`; a JSON encoding: the JSON obstacle
/// ([`obstacle_from_json`]); any other (or none): JSON, then protobuf, except that a payload starting with `{` is
/// only JSON (so that bad JSON is reported as such). An id in the payload must equal the key's.
pub fn decode_obstacle(
    encoding: &Encoding,
    bytes: &[u8],
    id_from_key: &str,
) -> Result<v1::Obstacle, ServerError> {
    check_size(bytes)?;
    let protobuf = |bytes: &[u8]| {
        codec::decode::<v1::Obstacle>(bytes)
            .map_err(|e| ServerError::invalid("payload", format!("not a protobuf dmp.v1.Obstacle: {e}")))
    };
    // The encoding's name without its schema (`application/protobuf;dmp.v1.Obstacle`).
    let name = std::borrow::Cow::<'static, str>::from(encoding);
    let mut o = match name.split(';').next().unwrap_or_default() {
        codec::PROTOBUF_ENCODING => protobuf(bytes)?,
        "application/json" | "text/json" => obstacle_from_json(bytes, id_from_key)?,
        _ => match obstacle_from_json(bytes, id_from_key) {
            Ok(o) => o,
            Err(e) if bytes.trim_ascii_start().starts_with(b"{") => return Err(e),
            Err(json) => codec::decode::<v1::Obstacle>(bytes).map_err(|pb| {
                ServerError::invalid(
                    "payload",
                    format!("neither a JSON obstacle ({json}) nor a protobuf dmp.v1.Obstacle ({pb})"),
                )
            })?,
        },
    };
    if o.id.is_empty() {
        o.id = id_from_key.to_owned();
    } else if o.id != id_from_key {
        return Err(ServerError::invalid("id", format!("`{}` differs from the key's `{id_from_key}`", o.id)));
    }
    Ok(o)
}

/// Decodes a robot-state payload (protobuf `dmp.v1.RobotState`) whose key names `id_from_key`, and validates it
/// ([`check_robot_state`]); returns it with its footprint. An empty `robot_id` takes the key's.
pub fn decode_robot_state(
    bytes: &[u8],
    id_from_key: &str,
) -> Result<(v1::RobotState, Option<dmp::Shape>), ServerError> {
    check_size(bytes)?;
    let mut state = codec::decode::<v1::RobotState>(bytes)
        .map_err(|e| ServerError::invalid("payload", format!("not a protobuf dmp.v1.RobotState: {e}")))?;
    if state.robot_id.is_empty() {
        state.robot_id = id_from_key.to_owned();
    } else if state.robot_id != id_from_key {
        return Err(ServerError::invalid(
            "robot_id",
            format!("`{}` differs from the key's `{id_from_key}`", state.robot_id),
        ));
    }
    let footprint = check_robot_state(&state)?;
    Ok((state, footprint))
}

fn check_size(bytes: &[u8]) -> Result<(), ServerError> {
    if bytes.len() > MAX_PAYLOAD_BYTES {
        return Err(ServerError::invalid(
            "payload",
            format!("{} bytes, more than the limit of {MAX_PAYLOAD_BYTES}", bytes.len()),
        ));
    }
    Ok(())
}

/// Spawns the task that removes expired obstacles of every cell every [`REAP_PERIOD`] until `stop` is cancelled.
/// The bridge starts one; without Zenoh, start one for the time to live of gRPC puts.
pub fn spawn_reaper(cells: Cells, stop: CancellationToken) -> JoinHandle<()> {
    tokio::spawn(async move {
        let mut tick = tokio::time::interval(REAP_PERIOD);
        tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
        loop {
            tokio::select! {
                _ = stop.cancelled() => break,
                _ = tick.tick() => {
                    let now = now_unix_s();
                    for scene in cells.all() {
                        let n = scene.expire(now);
                        if n > 0 {
                            debug!(cell = scene.cell(), expired = n, version = scene.snapshot().version, "obstacles expired");
                        }
                    }
                }
            }
        }
    })
}

/// What the callbacks share: the scene and the counter of refused payloads.
#[derive(Debug, Clone)]
struct Ingest {
    cells: Cells,
    malformed: Arc<AtomicU64>,
}

impl Ingest {
    fn obstacle(&self, sample: &Sample) {
        if let Err(e) = self.try_obstacle(sample) {
            self.refuse(sample, e);
        }
    }

    fn try_obstacle(&self, sample: &Sample) -> Result<(), ServerError> {
        let key = sample.key_expr().as_str();
        let id = key.rsplit('/').next().unwrap_or_default();
        let scene = self.cells.scene(cell_of(key))?;
        match sample.kind() {
            SampleKind::Delete => {
                let (version, existed) = scene.delete(id);
                debug!(key, existed, version, "obstacle deleted over zenoh");
            }
            SampleKind::Put => {
                let bytes = sample.payload().to_bytes();
                let o = decode_obstacle(sample.encoding(), &bytes, id)?;
                let version = scene.put(o, now_unix_s())?;
                debug!(key, version, "obstacle put over zenoh");
            }
        }
        Ok(())
    }

    fn robot(&self, sample: &Sample) {
        if let Err(e) = self.try_robot(sample) {
            self.refuse(sample, e);
        }
    }

    fn try_robot(&self, sample: &Sample) -> Result<(), ServerError> {
        let key = sample.key_expr().as_str();
        let id = key.strip_suffix("/state").and_then(|k| k.rsplit('/').next()).unwrap_or_default();
        let scene = self.cells.scene(cell_of(key))?;
        match sample.kind() {
            SampleKind::Delete => {
                scene.remove_robot(id);
                debug!(key, "robot retired over zenoh");
            }
            SampleKind::Put => {
                let (state, footprint) = decode_robot_state(&sample.payload().to_bytes(), id)?;
                scene.update_robot(state, footprint);
            }
        }
        Ok(())
    }

    fn refuse(&self, sample: &Sample, reason: ServerError) {
        let count = self.malformed.fetch_add(1, Ordering::Relaxed) + 1;
        warn!(key = %sample.key_expr(), %reason, malformed_payloads = count, "zenoh payload refused");
    }
}

/// The subscribers that feed the scene from Zenoh, and the time-to-live reaper.
#[derive(Debug)]
pub struct ZenohBridge {
    obstacles: Subscriber<()>,
    robots: Subscriber<()>,
    reaper: JoinHandle<()>,
    /// Cancels the reaper when the bridge is closed or dropped (it also stops on the server's shutdown).
    stop: DropGuard,
    malformed: Arc<AtomicU64>,
}

impl ZenohBridge {
    /// Subscribes to the obstacles and robot states of every cell on `session` and starts the reaper, which stops
    /// on `shutdown` or [`ZenohBridge::close`]. The robot states this session publishes itself ([`crate::robots`])
    /// are not received back: the publisher records them locally.
    pub async fn start(
        session: Session,
        cells: Cells,
        shutdown: CancellationToken,
    ) -> Result<Self, ServerError> {
        let cell = "*";
        let malformed = Arc::new(AtomicU64::new(0));
        let ingest = Ingest { cells: cells.clone(), malformed: malformed.clone() };
        let zenoh_err = |e: zenoh::Error| ServerError::Internal(format!("zenoh: cannot subscribe: {e}"));

        let obstacles_key = obstacle_key(cell, "*");
        let i = ingest.clone();
        let obstacles = session
            .declare_subscriber(&obstacles_key)
            .callback(move |sample| i.obstacle(&sample))
            .await
            .map_err(zenoh_err)?;
        let robots_key = robot_state_key(cell, "*");
        let robots = session
            .declare_subscriber(&robots_key)
            .callback(move |sample| ingest.robot(&sample))
            .allowed_origin(Locality::Remote)
            .await
            .map_err(zenoh_err)?;

        let stop = shutdown.child_token();
        let reaper = spawn_reaper(cells, stop.clone());
        info!(obstacles = %obstacles_key, robots = %robots_key, "zenoh bridge subscribed");
        Ok(Self { obstacles, robots, reaper, stop: stop.drop_guard(), malformed })
    }

    /// How many payloads were refused so far (malformed, invalid, or over a limit).
    pub fn malformed_payloads(&self) -> u64 {
        self.malformed.load(Ordering::Relaxed)
    }

    /// The counter behind [`ZenohBridge::malformed_payloads`], to read after the bridge is gone.
    pub fn malformed_counter(&self) -> Arc<AtomicU64> {
        self.malformed.clone()
    }

    /// Undeclares the subscribers (waiting for running callbacks, so the scene changes no more) and stops the
    /// reaper. The session can be closed afterwards.
    pub async fn close(self) {
        let Self { obstacles, robots, reaper, stop, malformed: _ } = self;
        drop(stop);
        let undeclared = tokio::task::spawn_blocking(move || {
            for s in [obstacles, robots] {
                let key = s.key_expr().to_string();
                if let Err(e) = s.undeclare().wait_callbacks().wait() {
                    debug!(key, error = %e, "zenoh subscriber undeclare failed (session closed?)");
                }
            }
        })
        .await;
        if let Err(e) = undeclared {
            warn!(error = %e, "zenoh subscriber undeclare task failed");
        }
        if let Err(e) = reaper.await {
            warn!(error = %e, "ttl reaper task failed");
        }
        debug!("zenoh bridge closed");
    }
}

#[cfg(test)]
mod tests;
