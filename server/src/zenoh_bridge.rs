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
//! | `dmp/<cell>/robots/<robot-id>/alive` liveliness token gone | | forgets the robot |
//!
//! A robot state whose stamp is too far from the server's clock, or whose position or velocity is out of bounds
//! ([`StateAdmission`]), is dropped and counted (`ServerStats.robot_states_dropped`). Whoever publishes robot states
//! declares the robot's liveliness token (`dmp_proto::keys::robot_alive_key`; the server's [`crate::cells::robot_bus`] does):
//! when it goes (the robot retired, or its publisher's session closed or lost), the robot vanishes from its cell. The
//! bridge subscribes to the tokens with history, so it also learns those declared before it started. A state from a
//! publisher without a token is still taken: a stream uses a cell-mate's state only while it is fresh (0.5 s), so
//! such a robot stops counting soon after its publisher stops.
//!
//! On start, and whenever a source comes (back), the bridge also queries `dmp/*/obstacles/**` and applies the
//! replies as samples ([`catch_up`]): obstacles published once before the server started are not lost.
//!
//! The keys are `dmp_proto::keys`'s and the payloads are decoded by `dmp_proto::payload`. A payload that cannot
//! be decoded or validated is logged at warn with its key and the reason, counted
//! ([`ZenohBridge::malformed_counter`]) and changes nothing else. Samples are handled in Zenoh's callbacks: decoding
//! and validating one obstacle or robot state takes microseconds and never awaits.

pub mod threads;

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

use dmp_proto::keys::{self, EVERY_CELL, check_name};
use dmp_proto::payload::{decode_obstacle, decode_robot_state};
use dmp_proto::zenoh_session::{ZenohTls, has_own_access_control, locators, session_config};
use tokio::task::JoinHandle;
use tokio_util::sync::{CancellationToken, DropGuard};
use tracing::{debug, info, warn};
use zenoh::pubsub::Subscriber;
use zenoh::sample::{Locality, Sample, SampleKind};
use zenoh::{Session, Wait};

use crate::access::AccessControl;
use crate::cells::Cells;
use crate::cells::robot_bus::RobotBus;
use crate::cells::state_admission::StateAdmission;
use crate::clock::Clock;
use crate::config::{Config, ZenohConfig};
use crate::error::ServerError;

/// Period of the reaper that removes obstacles whose time to live has passed.
pub(crate) const REAP_PERIOD: Duration = Duration::from_millis(100);

/// What secures a session: TLS files and the access file.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Security<'a> {
    /// The TLS files.
    pub config: &'a crate::config::SecurityConfig,
    /// The access file in force, if any: its access control is generated into the session's configuration.
    pub access: Option<&'a crate::access::Access>,
}

/// Opens the Zenoh session of [`ZenohConfig`], without TLS or access control (the unit tests).
#[cfg(test)]
pub(crate) async fn open_session(cfg: &ZenohConfig) -> Result<Session, ServerError> {
    let none = crate::config::SecurityConfig::default();
    open_secured_session(cfg, &Security { config: &none, access: None }).await
}

/// Opens the Zenoh session of [`ZenohConfig`] (built by `dmp_proto::zenoh_session::session_config`), its `tls/`
/// endpoints with the server's certificate and mutual TLS, and the access control generated from the access file.
/// Fails fast when a `connect` endpoint cannot be reached.
pub(crate) async fn open_secured_session(
    cfg: &ZenohConfig,
    security: &Security<'_>,
) -> Result<Session, ServerError> {
    let mut options = cfg.session_options();
    if cfg.uses_tls() {
        let s = security.config;
        let (Some(cert), Some(key), Some(ca)) = (&s.tls_cert, &s.tls_key, &s.tls_client_ca) else {
            return Err(ServerError::FailedPrecondition(
                "zenoh: `tls/` endpoints need security.tls_cert, tls_key and tls_client_ca".into(),
            ));
        };
        options.tls =
            Some(ZenohTls { root_ca: ca.clone(), cert: cert.clone(), key: key.clone(), mutual: true });
    }
    if let Some(access) = security.access {
        options.access_control = Some(crate::access::zenoh_acl::access_control(access));
        if has_own_access_control(&options)? {
            warn!(
                "zenoh: the access control of the Zenoh configuration file replaces the one generated from the access file"
            );
        } else {
            info!("zenoh: access control generated from the access file (default deny)");
        }
    }
    let config = session_config(&options)?;
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

/// Spawns the task that removes expired obstacles of every cell, and the cells nothing uses any more, every
/// [`REAP_PERIOD`] until `stop` is cancelled.
/// The bridge starts one; without Zenoh, start one for the time to live of gRPC puts.
pub(crate) fn spawn_reaper(cells: Cells, clock: Clock, stop: CancellationToken) -> JoinHandle<()> {
    tokio::spawn(async move {
        let mut tick = tokio::time::interval(REAP_PERIOD);
        tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
        loop {
            tokio::select! {
                _ = stop.cancelled() => break,
                _ = tick.tick() => {
                    let now = clock.now_unix_s();
                    for scene in cells.all() {
                        let n = scene.expire(now);
                        if n > 0 {
                            debug!(cell = scene.name(), expired = n, version = scene.snapshot().version, "obstacles expired");
                        }
                    }
                    let reclaimed = cells.reclaim();
                    if reclaimed > 0 {
                        debug!(reclaimed, cells = cells.len(), "unused cells reclaimed");
                    }
                }
            }
        }
    })
}

/// Applies the samples of the subscribers' callbacks to the cells' scenes, and counts those it refuses.
#[derive(Debug, Clone)]
struct SceneUpdater {
    cells: Cells,
    malformed: Arc<AtomicU64>,
    clock: Clock,
    admission: StateAdmission,
}

impl SceneUpdater {
    fn obstacle(&self, sample: &Sample) {
        if let Err(e) = self.try_obstacle(sample) {
            self.refuse(sample, e);
        }
    }

    fn try_obstacle(&self, sample: &Sample) -> Result<(), ServerError> {
        let key = sample.key_expr().as_str();
        let names = keys::parse_obstacle_key(key)
            .ok_or_else(|| ServerError::invalid("key", "is not dmp/<cell>/obstacles/<obstacle-id>"))?;
        let id = names.id;
        match sample.kind() {
            SampleKind::Delete => {
                // A delete never creates a cell: in a cell that does not exist there is nothing to delete.
                let Some(scene) = self.cells.find(names.cell)? else {
                    debug!(key, "obstacle delete over zenoh for a cell that does not exist");
                    return Ok(());
                };
                let (version, existed) = scene.delete(id, self.clock.now_unix_s());
                if existed {
                    info!(cell = names.cell, obstacle = id, version, source = "zenoh", "obstacle deleted");
                } else {
                    debug!(key, version, "obstacle delete over zenoh: no such obstacle");
                }
            }
            SampleKind::Put => {
                if !self.cells.serves(names.cell) {
                    debug!(key, "obstacle over zenoh for a cell this server does not serve");
                    return Ok(());
                }
                let scene = self.cells.get(names.cell)?;
                let bytes = sample.payload().to_bytes();
                // The encoding's name, with its schema if any (`application/protobuf;dmp.v1.Obstacle`).
                let encoding = std::borrow::Cow::<'static, str>::from(sample.encoding());
                let o = decode_obstacle(&encoding, &bytes, id)?;
                let known = scene.snapshot().obstacles.contains_key(id);
                let version = scene.put(o, self.clock.now_unix_s())?;
                // A new obstacle at info; the updates of a known one (a tracker's 20 Hz) at debug.
                if known {
                    debug!(cell = names.cell, obstacle = id, version, source = "zenoh", "obstacle updated");
                } else {
                    info!(cell = names.cell, obstacle = id, version, source = "zenoh", "obstacle added");
                }
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
        let names = keys::parse_robot_state_key(key)
            .ok_or_else(|| ServerError::invalid("key", "is not dmp/<cell>/robots/<robot-id>/state"))?;
        let id = names.id;
        match sample.kind() {
            SampleKind::Delete => {
                for scene in self.robot_cells(names.cell, false)? {
                    scene.remove_robot(id);
                    debug!(key, cell = scene.name(), "robot retired over zenoh");
                }
            }
            SampleKind::Put => {
                check_name("robot_id", id)?;
                let scenes = self.robot_cells(names.cell, true)?;
                if scenes.is_empty() {
                    debug!(key, "robot state of a cell this server neither serves nor neighbours");
                    return Ok(());
                }
                let (state, footprint) = decode_robot_state(&sample.payload().to_bytes(), id)?;
                match self.admission.admit(&state, self.clock.now_unix_s()) {
                    Ok(()) => {
                        for scene in &scenes {
                            scene.update_robot(state.clone(), footprint.clone());
                        }
                    }
                    Err(e) => {
                        warn!(key, reason = %e, dropped = self.admission.dropped(), "robot state dropped")
                    }
                }
            }
        }
        Ok(())
    }

    /// A robot's liveliness token came or went: gone, the robot is forgotten.
    fn liveliness(&self, sample: &Sample) {
        let key = sample.key_expr().as_str();
        let Some(names) = keys::parse_robot_alive_key(key) else {
            return self
                .refuse(sample, ServerError::invalid("key", "is not dmp/<cell>/robots/<robot-id>/alive"));
        };
        if sample.kind() == SampleKind::Delete {
            match self.robot_cells(names.cell, false) {
                Ok(scenes) => {
                    for scene in scenes {
                        scene.remove_robot(names.id);
                        debug!(key, cell = scene.name(), "robot gone with its liveliness token");
                    }
                }
                Err(e) => self.refuse(sample, e),
            }
        }
    }

    /// The scenes a robot of `cell` counts in: its cell's when this server serves it, and those of the cells that
    /// list it as a neighbour (`plant.neighbours`). `create`: created if need be (a put), else only those that
    /// exist (a delete never creates a cell).
    fn robot_cells(&self, cell: &str, create: bool) -> Result<Vec<crate::cells::cell::Cell>, ServerError> {
        check_name("cell", cell)?;
        let names = std::iter::once(cell)
            .filter(|c| self.cells.serves(c))
            .chain(self.cells.avoiders_of(cell).iter().map(String::as_str));
        let mut out = Vec::new();
        for name in names {
            if create {
                out.push(self.cells.get(name)?);
            } else if let Some(scene) = self.cells.find(name)? {
                out.push(scene);
            }
        }
        Ok(out)
    }

    fn refuse(&self, sample: &Sample, reason: ServerError) {
        let count = self.malformed.fetch_add(1, Ordering::Relaxed) + 1;
        warn!(key = %sample.key_expr(), %reason, malformed_payloads = count, "zenoh payload refused");
        // A sample names no identity (see `revocation`): the audit line names the key.
        let reason = format_args!("{}: {reason}", sample.key_expr());
        crate::access::audit::refused(crate::access::audit::ZENOH_PEER, "zenoh publish", &reason);
    }
}

/// The server's side of Zenoh: the session (none with `zenoh.disabled`), the bridge that feeds the scenes, the
/// robots' state bus, and the locators the session listens on.
#[derive(Debug)]
pub(crate) struct ZenohSide {
    /// The session; none without Zenoh.
    pub session: Option<Session>,
    /// The bridge; none without Zenoh.
    pub bridge: Option<ZenohBridge>,
    /// Publishes the executing robots' states (locally only, without Zenoh).
    pub robots: RobotBus,
    /// What the session listens on (empty without Zenoh).
    pub locators: Vec<String>,
    /// Audits the Zenoh peers a reload of the access file revoked ([`revocation`]); none on an open server.
    revocation: Option<JoinHandle<()>>,
}

impl ZenohSide {
    /// Opens the session `config.zenoh` describes, secured by `config.security` and `access`, and starts the bridge
    /// into `cells` (robot states taken as `admission` says) and the robot bus. Without Zenoh, only the reaper that
    /// expires obstacles put over gRPC with a time to live.
    pub(crate) async fn start(
        config: &Config,
        access: &AccessControl,
        cells: &Cells,
        clock: Clock,
        admission: &StateAdmission,
        shutdown: &CancellationToken,
    ) -> Result<Self, ServerError> {
        if config.zenoh.disabled {
            spawn_reaper(cells.clone(), clock, shutdown.clone());
            return Ok(Self {
                session: None,
                bridge: None,
                robots: RobotBus::new(None),
                locators: Vec::new(),
                revocation: None,
            });
        }
        let mut reloads = access.reloads();
        let access = reloads.borrow_and_update().clone();
        let security = Security { config: &config.security, access: access.as_deref() };
        let session = open_secured_session(&config.zenoh, &security).await?;
        // Zenoh's access control is the one of the file in force now, whatever a reload brings later.
        let revocation = match &access {
            Some(opened) => {
                Some(revocation::spawn(&session, opened.clone(), reloads, shutdown.child_token()).await?)
            }
            None => None,
        };
        let bridge =
            ZenohBridge::start(session.clone(), cells.clone(), clock, admission.clone(), shutdown.clone())
                .await?;
        let locators = locators(&session).await;
        let robots = RobotBus::new(Some((session.clone(), config.defaults.robot_state_period_s)))
            .mirroring(cells.clone());
        Ok(Self { session: Some(session), bridge: Some(bridge), robots, locators, revocation })
    }

    /// Closes the bridge, then the session.
    pub(crate) async fn close(self) {
        if let Some(r) = self.revocation {
            r.abort();
        }
        if let Some(b) = self.bridge {
            b.close().await;
        }
        if let Some(s) = self.session
            && let Err(e) = s.close().await
        {
            warn!(error = %e, "closing the Zenoh session");
        }
    }
}

/// The subscribers that feed the scene from Zenoh, the catch-up querier, and the time-to-live reaper.
#[derive(Debug)]
pub(crate) struct ZenohBridge {
    /// Applies obstacle samples from elsewhere (a fail-over's query for a taken cell's scene).
    updater: SceneUpdater,
    obstacles: Subscriber<()>,
    robots: Subscriber<()>,
    /// The robots' liveliness tokens.
    alive: Subscriber<()>,
    reaper: JoinHandle<()>,
    catch_up: JoinHandle<()>,
    /// Cancels the reaper when the bridge is closed or dropped (it also stops on the server's shutdown).
    stop: DropGuard,
    malformed: Arc<AtomicU64>,
}

impl ZenohBridge {
    /// Subscribes to the obstacles and robot states of every cell on `session` and starts the reaper, which stops
    /// on `shutdown` or [`ZenohBridge::close`]. The robot states this session publishes itself ([`crate::cells::robot_bus`])
    /// are not received back: the publisher records them locally. Robot states from elsewhere are taken as
    /// `admission` says.
    pub(crate) async fn start(
        session: Session,
        cells: Cells,
        clock: Clock,
        admission: StateAdmission,
        shutdown: CancellationToken,
    ) -> Result<Self, ServerError> {
        let malformed = Arc::new(AtomicU64::new(0));
        let updater = SceneUpdater { cells: cells.clone(), malformed: malformed.clone(), clock, admission };
        let zenoh_err = |e: zenoh::Error| ServerError::Internal(format!("zenoh: cannot subscribe: {e}"));

        let obstacles_key = keys::obstacles_of(EVERY_CELL);
        let on_obstacle = updater.clone();
        let obstacles = session
            .declare_subscriber(&obstacles_key)
            .callback(move |sample| on_obstacle.obstacle(&sample))
            .await
            .map_err(zenoh_err)?;
        let stop = shutdown.child_token();
        let catch_up = catch_up::spawn(&session, updater.clone(), stop.clone()).await?;
        let robots_key = keys::robot_states_of(EVERY_CELL);
        let on_robot = updater.clone();
        let robots = session
            .declare_subscriber(&robots_key)
            .callback(move |sample| on_robot.robot(&sample))
            .allowed_origin(Locality::Remote)
            .await
            .map_err(zenoh_err)?;
        let alive_key = keys::robots_alive_of(EVERY_CELL);
        let on_alive = updater.clone();
        let alive = session
            .liveliness()
            .declare_subscriber(&alive_key)
            .history(true)
            .callback(move |sample| on_alive.liveliness(&sample))
            .await
            .map_err(zenoh_err)?;

        let reaper = spawn_reaper(cells, clock, stop.clone());
        info!(obstacles = %obstacles_key, robots = %robots_key, alive = %alive_key, "zenoh bridge subscribed");
        Ok(Self { updater, obstacles, robots, alive, reaper, catch_up, stop: stop.drop_guard(), malformed })
    }

    /// What applies an obstacle sample as if it had been published (the same checks, counted alike).
    pub(crate) fn obstacle_sink(&self) -> crate::plant::failover::ObstacleSink {
        let updater = self.updater.clone();
        Arc::new(move |sample| updater.obstacle(sample))
    }

    /// How many payloads were refused so far (malformed, invalid, or over a limit).
    #[cfg(test)]
    pub(crate) fn malformed_payloads(&self) -> u64 {
        self.malformed.load(Ordering::Relaxed)
    }

    /// How many payloads were refused so far (malformed, invalid, or over a limit), to read after the bridge is gone.
    pub(crate) fn malformed_counter(&self) -> Arc<AtomicU64> {
        self.malformed.clone()
    }

    /// Undeclares the subscribers (waiting for running callbacks, so the scene changes no more) and stops the
    /// reaper. The session can be closed afterwards.
    pub(crate) async fn close(self) {
        let Self { obstacles, robots, alive, reaper, catch_up, stop, malformed: _, updater: _ } = self;
        drop(stop);
        let undeclared = tokio::task::spawn_blocking(move || {
            for s in [obstacles, robots, alive] {
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
        if let Err(e) = catch_up.await {
            warn!(error = %e, "catch-up task failed");
        }
        if let Err(e) = reaper.await {
            warn!(error = %e, "ttl reaper task failed");
        }
        debug!("zenoh bridge closed");
    }
}

pub(crate) mod catch_up;
pub(crate) mod reachability;
pub(crate) mod revocation;
#[cfg(test)]
mod tests;
