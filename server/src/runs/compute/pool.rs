//! A pool of OS threads that does the server's number crunching, so that the async workers only move bytes.
//!
//! A job is a closure. It runs on one of the pool's threads, a panic in it is caught and becomes an error for its
//! caller alone, and a job whose caller has gone (the client cancelled or left, or its deadline passed, so the
//! awaiting future was dropped) is skipped before it starts. Long jobs check [`JobContext::cancelled`] between
//! chunks and stop early.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use tokio::sync::oneshot;
use tracing::{debug, warn};

/// Why a job gave no result.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum JobError {
    /// The job panicked: a bug, reported to its caller only.
    #[error("the computation failed unexpectedly: {0}")]
    Panicked(String),
    /// The pool is gone (the server is shutting down).
    #[error("the compute pool has stopped")]
    Stopped,
}

/// What a running job can ask its pool.
#[derive(Debug)]
pub struct JobContext<'a> {
    caller: &'a oneshot::Sender<std::thread::Result<()>>,
}

impl JobContext<'_> {
    /// True once nobody waits for the result any more (the caller's future was dropped).
    pub fn cancelled(&self) -> bool {
        self.caller.is_closed()
    }
}

type Job = Box<dyn FnOnce() + Send + 'static>;

/// Counters of a pool.
#[derive(Debug, Default)]
pub struct PoolCounters {
    /// Jobs run to the end (or to their panic).
    pub completed: AtomicU64,
    /// Jobs skipped because their caller had gone before they started.
    pub skipped: AtomicU64,
    /// Jobs that panicked.
    pub panicked: AtomicU64,
    /// Jobs running now.
    pub running: AtomicU64,
}

/// A fixed set of named threads taking jobs from one queue (a clone is a handle on the same pool).
#[derive(Debug, Clone)]
pub struct Pool {
    name: &'static str,
    threads: usize,
    queue: crossbeam_channel::Sender<Job>,
    counters: Arc<PoolCounters>,
}

impl Pool {
    /// Starts `threads` threads (at least one) named `<name>-<i>`. `nice` is added to their scheduling niceness
    /// (Linux; 0 leaves it): a batch pool runs at a lower priority than the real-time one, so that it only takes
    /// the time the real-time streams leave.
    pub fn start(name: &'static str, threads: usize, nice: i32) -> std::io::Result<Self> {
        let threads = threads.max(1);
        let (queue, jobs) = crossbeam_channel::unbounded::<Job>();
        for i in 0..threads {
            let jobs = jobs.clone();
            std::thread::Builder::new().name(format!("{name}-{i}")).spawn(move || {
                lower_priority(name, nice);
                // Ends when the pool (every sender) is dropped.
                while let Ok(job) = jobs.recv() {
                    job();
                }
            })?;
        }
        Ok(Self { name, threads, queue, counters: Arc::default() })
    }

    /// The number of threads.
    pub fn threads(&self) -> usize {
        self.threads
    }

    /// Jobs waiting for a thread.
    pub fn queued(&self) -> usize {
        self.queue.len()
    }

    /// The pool's counters.
    pub fn counters(&self) -> &PoolCounters {
        &self.counters
    }

    /// Runs `f` on the pool and waits for its result. Dropping the returned future cancels the job: skipped if it
    /// has not started, told through [`JobContext::cancelled`] if it has.
    pub async fn run<T, F>(&self, f: F) -> Result<T, JobError>
    where
        T: Send + 'static,
        F: FnOnce(&JobContext<'_>) -> T + Send + 'static,
    {
        let (tx, rx) = oneshot::channel::<std::thread::Result<T>>();
        let (done_tx, done_rx) = oneshot::channel::<std::thread::Result<()>>();
        let counters = self.counters.clone();
        let name = self.name;
        let job: Job = Box::new(move || {
            if tx.is_closed() {
                counters.skipped.fetch_add(1, Ordering::Relaxed);
                return;
            }
            counters.running.fetch_add(1, Ordering::AcqRel);
            // `done_tx` is only watched for the caller going away: it is dropped with `rx`'s future.
            let result = {
                let ctx = JobContext { caller: &done_tx };
                catch_unwind(AssertUnwindSafe(|| f(&ctx)))
            };
            if let Err(payload) = &result {
                counters.panicked.fetch_add(1, Ordering::Relaxed);
                warn!(pool = name, panic = %panic_message(payload.as_ref()), "a job panicked");
            }
            counters.completed.fetch_add(1, Ordering::Relaxed);
            counters.running.fetch_sub(1, Ordering::AcqRel);
            let _ = tx.send(result);
            drop(done_tx);
        });
        self.queue.send(job).map_err(|_| JobError::Stopped)?;
        // Keeps `done_rx` alive exactly as long as this future: dropping it closes the job's cancellation flag.
        let _cancel_on_drop = done_rx;
        match rx.await {
            Ok(Ok(v)) => Ok(v),
            Ok(Err(payload)) => Err(JobError::Panicked(panic_message(payload.as_ref()))),
            Err(_) => Err(JobError::Stopped),
        }
    }
}

/// The text of a panic's payload.
fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "a panic without a message".into()
    }
}

/// Adds `nice` to the calling thread's niceness (on Linux the niceness is per thread).
fn lower_priority(pool: &str, nice: i32) {
    if nice == 0 {
        return;
    }
    #[cfg(target_os = "linux")]
    match rustix::process::getpriority_process(None)
        .and_then(|now| rustix::process::setpriority_process(None, (now + nice).min(19)))
    {
        Ok(()) => debug!(pool, nice, "lowered the priority of a compute thread"),
        Err(e) => warn!(pool, nice, error = %e, "could not lower the priority of a compute thread"),
    }
    #[cfg(not(target_os = "linux"))]
    debug!(pool, nice, "thread priorities are only set on Linux");
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::AtomicBool;
    use std::time::Duration;

    use super::*;

    #[tokio::test]
    async fn a_job_runs_off_the_async_workers_and_returns() {
        let pool = Pool::start("test", 2, 0).unwrap();
        let name = pool.run(|_| std::thread::current().name().map(str::to_string)).await.unwrap();
        assert!(name.unwrap().starts_with("test-"));
    }

    #[tokio::test]
    async fn a_panic_is_an_error_for_its_caller_and_the_pool_goes_on() {
        let pool = Pool::start("test", 1, 0).unwrap();
        let err = pool.run(|_| -> u32 { panic!("boom") }).await.unwrap_err();
        assert_eq!(err, JobError::Panicked("boom".into()));
        assert_eq!(pool.run(|_| 7).await, Ok(7));
        assert_eq!(pool.counters().panicked.load(Ordering::Relaxed), 1);
    }

    #[tokio::test]
    async fn a_dropped_caller_cancels_its_job() {
        let pool = Pool::start("test", 1, 0).unwrap();
        let stopped = Arc::new(AtomicBool::new(false));
        let (started_tx, started_rx) = oneshot::channel();
        let flag = stopped.clone();
        let p = pool.clone();
        let caller = tokio::spawn(async move {
            p.run(move |ctx| {
                let _ = started_tx.send(());
                // A long job that checks for cancellation between its chunks.
                while !ctx.cancelled() {
                    std::thread::sleep(Duration::from_millis(1));
                }
                flag.store(true, Ordering::SeqCst);
            })
            .await
        });
        tokio::time::timeout(Duration::from_secs(10), started_rx).await.unwrap().unwrap();
        // Queued behind the running job (the timeout polls it once, which queues it), then abandoned: never runs.
        let queued =
            tokio::time::timeout(Duration::from_millis(1), pool.run(|_| panic!("must be skipped"))).await;
        assert!(queued.is_err(), "the queued job cannot have run");
        caller.abort();
        // The running job sees the cancellation; the queued one is skipped.
        tokio::time::timeout(Duration::from_secs(10), async {
            while !stopped.load(Ordering::SeqCst) || pool.counters().skipped.load(Ordering::Relaxed) == 0 {
                tokio::time::sleep(Duration::from_millis(1)).await;
            }
        })
        .await
        .expect("the job stops and the queued one is skipped");
        assert_eq!(pool.counters().panicked.load(Ordering::Relaxed), 0);
    }

    #[tokio::test]
    async fn batch_threads_run_at_a_lower_priority() {
        let pool = Pool::start("test", 1, 5).unwrap();
        let here = rustix::process::getpriority_process(None).unwrap();
        let there = pool.run(|_| rustix::process::getpriority_process(None).unwrap()).await.unwrap();
        assert_eq!(there, (here + 5).min(19));
    }
}
