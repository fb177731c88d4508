//! `dmp.v1.ServerService`: the server's own resource use and traffic, for operators and load tests.

use std::sync::Arc;
use std::sync::atomic::Ordering;

use dmp_proto::v1;
use dmp_proto::v1::server_service_server::ServerService;
use tonic::{Request, Response, Status};

use crate::access::Action;
use crate::grpc::shared::ServiceState;

/// The service.
#[derive(Debug, Clone)]
pub(crate) struct ServerServiceImpl {
    state: Arc<ServiceState>,
}

impl ServerServiceImpl {
    /// The service over the server's state.
    pub(crate) fn new(state: Arc<ServiceState>) -> Self {
        Self { state }
    }

    /// The statistics now.
    pub(crate) fn stats(&self) -> v1::ServerStats {
        let s = &self.state;
        let cells = s.cells.all();
        v1::ServerStats {
            uptime_s: s.runs.counters.started.elapsed().as_secs_f64(),
            cpu_seconds: cpu_time::ProcessTime::try_now()
                .map(|t| t.as_duration().as_secs_f64())
                .unwrap_or(0.0),
            rss_bytes: memory_stats::memory_stats().map_or(0, |m| m.physical_mem as u64),
            open_streams: (s.runs.streams.open_executions() + s.runs.streams.open_watches()) as u32,
            segments_sent: s.runs.counters.segments_sent.load(Ordering::Relaxed),
            cells: cells.len() as u32,
            robots: cells.iter().map(|c| c.robot_count()).sum::<usize>() as u32,
            robot_states_dropped: s.state_admission.dropped(),
            ..s.runs.compute.stats()
        }
    }
}

#[tonic::async_trait]
impl ServerService for ServerServiceImpl {
    async fn get_stats(
        &self,
        request: Request<v1::GetStatsRequest>,
    ) -> Result<Response<v1::ServerStats>, Status> {
        self.state.caller(&request)?.check(&Action::Stats)?;
        Ok(Response::new(self.stats()))
    }

    async fn get_info(
        &self,
        request: Request<v1::GetInfoRequest>,
    ) -> Result<Response<v1::ServerInfo>, Status> {
        let caller = self.state.caller(&request)?;
        let s = &self.state;
        let security = &s.config.security;
        Ok(Response::new(v1::ServerInfo {
            version: env!("CARGO_PKG_VERSION").into(),
            cell: s.cells.default_cell().into(),
            tls: security.tls_cert.is_some(),
            mutual_tls: security.tls_cert.is_some() && security.tls_client_ca.is_some(),
            access_control: s.access.enabled(),
            insecure: s.exposure.insecure(),
            insecure_reasons: s.exposure.warnings.clone(),
            identity: caller.name().into(),
            role: caller.role().as_str().into(),
            zenoh_locators: s.zenoh_locators.clone(),
            limits: Some(limits(&s.config)),
        }))
    }
}

/// The limits of `config` that bound a client's requests.
fn limits(config: &crate::config::Config) -> v1::ServerLimits {
    let l = &config.limits;
    v1::ServerLimits {
        max_message_bytes: l.max_message_bytes as u64,
        max_samples: l.max_samples as u64,
        max_dim: l.max_dim as u64,
        max_obstacles: l.max_obstacles as u64,
        max_streams_per_client: l.max_streams_per_client as u64,
        max_steps: l.max_steps as u64,
        workspace_m: l.workspace_m,
        max_request_work: config.compute.max_request_work,
    }
}
