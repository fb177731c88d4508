//! `dmp.v1.ServerService`: the server's own resource use and traffic, for operators and load tests.

use std::sync::Arc;
use std::sync::atomic::Ordering;

use dmp_proto::v1;
use dmp_proto::v1::server_service_server::ServerService;
use tonic::{Request, Response, Status};

use crate::state::AppState;

/// The service.
#[derive(Debug, Clone)]
pub struct ServerServiceImpl {
    state: Arc<AppState>,
}

impl ServerServiceImpl {
    /// The service over the server's state.
    pub fn new(state: Arc<AppState>) -> Self {
        Self { state }
    }

    /// The statistics now.
    pub fn stats(&self) -> v1::ServerStats {
        let s = &self.state;
        let cells = s.cells.all();
        v1::ServerStats {
            uptime_s: s.counters.started.elapsed().as_secs_f64(),
            cpu_seconds: cpu_time::ProcessTime::try_now()
                .map(|t| t.as_duration().as_secs_f64())
                .unwrap_or(0.0),
            rss_bytes: memory_stats::memory_stats().map_or(0, |m| m.physical_mem as u64),
            open_streams: (s.streams.open_executions() + s.streams.open_watches()) as u32,
            segments_sent: s.counters.segments_sent.load(Ordering::Relaxed),
            cells: cells.len() as u32,
            robots: cells.iter().map(|c| c.robot_count()).sum::<usize>() as u32,
            robot_states_dropped: s.state_admission.dropped(),
            ..s.compute.stats()
        }
    }
}

#[tonic::async_trait]
impl ServerService for ServerServiceImpl {
    async fn get_stats(&self, _: Request<v1::GetStatsRequest>) -> Result<Response<v1::ServerStats>, Status> {
        Ok(Response::new(self.stats()))
    }
}
