//! Where the server's number crunching runs: two pools of OS threads, never the async workers. Real-time streams
//! step on their own pool; plans, learns and as-fast-as-read streams on a batch pool of lower priority, so that no
//! batch work delays a robot. Every request is costed and admitted against budgets first ([`admission`]).

pub mod admission;
pub mod cost;
pub mod pool;

use crate::config::ComputeConfig;
use admission::Admission;
use pool::Pool;

/// The compute pools and the admission budgets.
#[derive(Debug)]
pub struct Compute {
    /// Steps the real-time streams.
    pub realtime: Pool,
    /// Runs plans, learns and as-fast-as-read streams, at a lower priority.
    pub batch: Pool,
    /// The budgets requests are admitted against.
    pub admission: Admission,
}

impl Compute {
    /// The compute fields of the server's stats.
    pub fn stats(&self) -> dmp_proto::v1::ServerStats {
        use std::sync::atomic::Ordering::Relaxed;
        let (rt, batch) = (self.realtime.counters(), self.batch.counters());
        dmp_proto::v1::ServerStats {
            realtime_work_reserved: self.admission.realtime_in_use() as f64,
            realtime_work_budget: self.admission.realtime_budget(),
            batch_work_reserved: self.admission.batch_in_use() as f64,
            batch_work_budget: self.admission.batch_budget(),
            realtime_jobs_running: rt.running.load(Relaxed) as u32,
            batch_jobs_running: batch.running.load(Relaxed) as u32,
            jobs_abandoned: rt.skipped.load(Relaxed) + batch.skipped.load(Relaxed),
            jobs_failed: rt.panicked.load(Relaxed) + batch.panicked.load(Relaxed),
            ..Default::default()
        }
    }

    /// Starts the pools of `config` (0 threads means one per core).
    pub fn start(config: &ComputeConfig) -> std::io::Result<Self> {
        let cores = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
        let or_cores = |n: usize| if n == 0 { cores } else { n };
        let realtime = Pool::start("dmp-realtime", or_cores(config.realtime_threads), 0)?;
        let batch = Pool::start("dmp-batch", or_cores(config.batch_threads), config.batch_nice)?;
        let admission = Admission::new(config, realtime.threads());
        Ok(Self { realtime, batch, admission })
    }
}
