//! Whether the configured Zenoh routers or peers (`zenoh.connect`) are reachable, as the gRPC health of the scene
//! service: NOT_SERVING while they are not (the scene no longer receives their obstacles), SERVING once Zenoh has
//! reconnected. Without `connect` endpoints there is nothing to reach and the status is not touched.
//!
//! "Reachable": a Zenoh link whose remote address is the endpoint's (its host resolved). A peer connects to every
//! endpoint, so every one must be linked; a client connects to one router, so one is enough. Re-evaluated on every
//! link and transport event of the session (what an event removes is left out even if the list still shows it),
//! and every [`RECHECK_PERIOD`].

use std::net::SocketAddr;
use std::time::Duration;

use dmp_proto::v1::scene_service_server::SERVICE_NAME;
use tokio::task::JoinHandle;
use tokio_util::sync::CancellationToken;
use tonic_health::ServingStatus;
use tonic_health::server::HealthReporter;
use tracing::{debug, info, warn};
use zenoh::Session;
use zenoh::config::{EndPoint, ZenohId};
use zenoh::sample::SampleKind;

use crate::error::ServerError;

/// How often reachability is checked between events.
pub(crate) const RECHECK_PERIOD: Duration = Duration::from_secs(1);

/// What an event just removed: left out of the links listed.
#[derive(Debug, Clone, Default)]
enum Gone {
    #[default]
    Nothing,
    /// A link, by its remote address.
    Link(String),
    /// A whole transport, by the remote's id.
    Transport(ZenohId),
}

/// The endpoints to watch and how many must be linked.
#[derive(Debug, Clone)]
struct Targets {
    /// The `host:port` of each `connect` endpoint, as configured.
    addresses: Vec<String>,
    /// A client needs one, a peer all.
    need_all: bool,
}

impl Targets {
    /// The endpoints not linked now.
    async fn unreachable(&self, session: &Session, gone: &Gone) -> Vec<String> {
        let linked: Vec<SocketAddr> = session
            .info()
            .links()
            .await
            .filter(|l| match gone {
                Gone::Nothing => true,
                Gone::Link(dst) => l.dst().to_string() != *dst,
                Gone::Transport(zid) => l.zid() != zid,
            })
            .filter_map(|l| l.dst().address().as_str().parse().ok())
            .collect();
        let mut missing = Vec::new();
        for address in &self.addresses {
            let reached = match tokio::net::lookup_host(address.as_str()).await {
                Ok(mut resolved) => resolved.any(|a| linked.contains(&a)),
                Err(_) => false,
            };
            if !reached {
                missing.push(address.clone());
            }
        }
        missing
    }

    fn serving(&self, missing: &[String]) -> bool {
        if self.need_all { missing.is_empty() } else { missing.len() < self.addresses.len() }
    }
}

/// Sets the scene service's health from the reachability of `connect` now, and spawns the task that follows it
/// until `stop`. `None` when `connect` is empty.
pub(crate) async fn spawn(
    session: &Session,
    connect: &[String],
    client_mode: bool,
    health: HealthReporter,
    stop: CancellationToken,
) -> Result<Option<JoinHandle<()>>, ServerError> {
    if connect.is_empty() {
        return Ok(None);
    }
    let mut addresses = Vec::new();
    for (i, e) in connect.iter().enumerate() {
        let endpoint: EndPoint =
            e.parse().map_err(|err| ServerError::invalid(format!("zenoh.connect[{i}]"), format!("{err}")))?;
        addresses.push(endpoint.address().as_str().to_string());
    }
    let targets = Targets { addresses, need_all: !client_mode };
    let zenoh_err =
        |e: zenoh::Error| ServerError::Internal(format!("zenoh: cannot listen to link events: {e}"));
    let links = session.info().link_events_listener().await.map_err(zenoh_err)?;
    let transports = session.info().transport_events_listener().await.map_err(zenoh_err)?;
    let mut serving = update(session, &targets, &health, None, &Gone::Nothing).await;
    let session = session.clone();
    Ok(Some(tokio::spawn(async move {
        let mut tick = tokio::time::interval(RECHECK_PERIOD);
        tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
        loop {
            let gone = tokio::select! {
                _ = stop.cancelled() => break,
                _ = tick.tick() => Gone::Nothing,
                event = links.recv_async() => match event {
                    Ok(e) => {
                        debug!(kind = ?e.kind(), dst = %e.link().dst(), "zenoh link event");
                        match e.kind() {
                            SampleKind::Delete => Gone::Link(e.link().dst().to_string()),
                            SampleKind::Put => Gone::Nothing,
                        }
                    }
                    Err(_) => break,
                },
                event = transports.recv_async() => match event {
                    Ok(e) => {
                        debug!(kind = ?e.kind(), zid = %e.transport().zid(), "zenoh transport event");
                        match e.kind() {
                            SampleKind::Delete => Gone::Transport(*e.transport().zid()),
                            SampleKind::Put => Gone::Nothing,
                        }
                    }
                    Err(_) => break,
                },
            };
            serving = update(&session, &targets, &health, Some(serving), &gone).await;
        }
    })))
}

/// Evaluates and sets the health when it changed from `was`; returns whether the scene serves.
async fn update(
    session: &Session,
    targets: &Targets,
    health: &HealthReporter,
    was: Option<bool>,
    gone: &Gone,
) -> bool {
    let missing = targets.unreachable(session, gone).await;
    let serving = targets.serving(&missing);
    if was != Some(serving) {
        if serving {
            health.set_service_status(SERVICE_NAME, ServingStatus::Serving).await;
            info!(connect = ?targets.addresses, "zenoh: the configured endpoints are reachable: scene SERVING");
        } else {
            health.set_service_status(SERVICE_NAME, ServingStatus::NotServing).await;
            warn!(unreachable = ?missing, "zenoh: configured endpoints unreachable: scene NOT_SERVING");
        }
    }
    serving
}
