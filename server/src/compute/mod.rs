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
