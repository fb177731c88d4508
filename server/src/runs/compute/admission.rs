//! Admission by cost: a request's work is estimated ([`super::cost`]) and admitted only while the server can
//! afford it. Real-time streams reserve a rate (work units per second) out of the real-time budget for as long as
//! they run; plans and learns reserve their whole work out of the batch budget while they are queued or running.
//! What cannot be afforded is refused with RESOURCE_EXHAUSTED, naming the cost and the budget.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use crate::config::ComputeConfig;
use crate::error::ServerError;

/// The budgets and what is reserved of them now.
#[derive(Debug)]
pub struct Admission {
    /// Work units per second that every real-time stream together may take.
    realtime_per_s: f64,
    /// Work units that one computation (a plan, a learn, one wake-up of a stream) may take.
    max_job: f64,
    /// Work units that one request may take in all (a plan, a learn, an as-fast-as-read stream).
    max_request: f64,
    /// Work units that plans and learns may have queued or running at once.
    batch_queue: f64,
    realtime_used: Arc<AtomicU64>,
    batch_used: Arc<AtomicU64>,
    /// Requests refused so far, by the budget that refused them (in the order of [`Admission::refusals`]).
    refused: [AtomicU64; 4],
}

/// A reservation of a budget, returned when dropped.
#[derive(Debug)]
pub struct ComputeReservation {
    used: Arc<AtomicU64>,
    amount: u64,
    /// The budget's limit.
    limit: u64,
}

impl ComputeReservation {
    /// Changes the reservation to `amount` (a run's scene grew or shrank after it was admitted), beyond the limit if
    /// need be: what runs is counted as it is, so that new requests see the true load. `false` when the budget is
    /// now over its limit.
    pub fn resize(&mut self, amount: f64) -> bool {
        let amount = if amount.is_nan() { f64::MAX } else { amount };
        let amount = amount.ceil().clamp(0.0, u64::MAX as f64 / 4.0) as u64;
        if amount >= self.amount {
            self.used.fetch_add(amount - self.amount, Ordering::AcqRel);
        } else {
            self.used.fetch_sub(self.amount - amount, Ordering::AcqRel);
        }
        self.amount = amount;
        self.used.load(Ordering::Acquire) <= self.limit
    }
}

impl Drop for ComputeReservation {
    fn drop(&mut self) {
        self.used.fetch_sub(self.amount, Ordering::AcqRel);
    }
}

/// Reserves `amount` of `used` within `limit`, or says how much is in use.
fn reserve(used: &Arc<AtomicU64>, amount: f64, limit: f64) -> Result<ComputeReservation, u64> {
    if !amount.is_finite() {
        return Err(used.load(Ordering::Acquire));
    }
    let amount = amount.ceil().min(u64::MAX as f64 / 4.0) as u64;
    let limit = limit.min(u64::MAX as f64 / 4.0) as u64;
    used.fetch_update(Ordering::AcqRel, Ordering::Acquire, |now| {
        (now.saturating_add(amount) <= limit).then_some(now + amount)
    })
    .map(|_| ComputeReservation { used: used.clone(), amount, limit })
}

/// The budgets' places in [`Admission::refusals`].
const REALTIME: usize = 0;
const JOB: usize = 1;
const REQUEST: usize = 2;
const BATCH_QUEUE: usize = 3;

/// Work units in words: `3.6e8`.
fn units(v: f64) -> String {
    format!("{v:.2e}")
}

impl Admission {
    /// The budgets of `config` for `realtime_threads` real-time threads.
    pub fn new(config: &ComputeConfig, realtime_threads: usize) -> Self {
        Self {
            realtime_per_s: config.realtime_work_per_thread_s * realtime_threads as f64,
            max_job: config.max_job_work,
            max_request: config.max_request_work,
            batch_queue: config.batch_queue_work,
            realtime_used: Arc::default(),
            batch_used: Arc::default(),
            refused: Default::default(),
        }
    }

    /// Requests refused so far, by the setting of the budget that refused them.
    pub fn refusals(&self) -> [(&'static str, u64); 4] {
        let n = |i: usize| self.refused[i].load(Ordering::Relaxed);
        [
            ("compute.realtime_work_per_thread_s", n(REALTIME)),
            ("compute.max_job_work", n(JOB)),
            ("compute.max_request_work", n(REQUEST)),
            ("compute.batch_queue_work", n(BATCH_QUEUE)),
        ]
    }

    /// Counts a refusal by the budget at `index` of [`Admission::refusals`].
    fn refuse(&self, index: usize) {
        self.refused[index].fetch_add(1, Ordering::Relaxed);
    }

    /// Admits a real-time stream that takes `per_second` work units per second of run time and at most `per_job`
    /// in one wake-up (`what` names the request's fields that set them).
    pub fn realtime(
        &self,
        per_second: f64,
        per_job: f64,
        what: &str,
    ) -> Result<ComputeReservation, ServerError> {
        self.check_job(per_job, what)?;
        reserve(&self.realtime_used, per_second, self.realtime_per_s).map_err(|used| {
            self.refuse(REALTIME);
            ServerError::ResourceExhausted(format!(
                "{what}: this real-time run needs {} work units per second and the real-time budget has {} of {} \
                 left (`compute.realtime_work_per_thread_s`); retry later, or use fewer obstacles, fewer boundary \
                 samples or a coarser integration step",
                units(per_second),
                units((self.realtime_per_s - used as f64).max(0.0)),
                units(self.realtime_per_s),
            ))
        })
    }

    /// Checks that one computation of `per_job` work units fits `compute.max_job_work`.
    pub fn check_job(&self, per_job: f64, what: &str) -> Result<(), ServerError> {
        if per_job.is_nan() || per_job > self.max_job {
            self.refuse(JOB);
            return Err(ServerError::ResourceExhausted(format!(
                "{what}: one computation of this run would take {} work units, more than the limit of {} \
                 (`compute.max_job_work`); use shorter segments, fewer obstacles or fewer boundary samples",
                units(per_job),
                units(self.max_job),
            )));
        }
        Ok(())
    }

    /// Checks that a request of `total` work units fits `compute.max_request_work`.
    pub fn check_request(&self, total: f64, what: &str) -> Result<(), ServerError> {
        if total.is_nan() || total > self.max_request {
            self.refuse(REQUEST);
            return Err(ServerError::ResourceExhausted(format!(
                "{what}: this request would take {} work units, more than the limit of {} \
                 (`compute.max_request_work`); ask for less (a shorter run, fewer obstacles, samples or basis \
                 functions)",
                units(total),
                units(self.max_request),
            )));
        }
        Ok(())
    }

    /// Admits a plan or a learn of `total` work units, held while it is queued or running.
    pub fn batch(&self, total: f64, what: &str) -> Result<ComputeReservation, ServerError> {
        self.check_request(total, what)?;
        reserve(&self.batch_used, total, self.batch_queue).map_err(|used| {
            self.refuse(BATCH_QUEUE);
            ServerError::ResourceExhausted(format!(
                "{what}: the server is busy: {} work units of plans and learns are queued or running, and this \
                 request needs {} more than the {} allowed (`compute.batch_queue_work`); retry later",
                units(used as f64),
                units(total),
                units(self.batch_queue),
            ))
        })
    }

    /// Work units per second reserved by real-time streams now.
    pub fn realtime_in_use(&self) -> u64 {
        self.realtime_used.load(Ordering::Acquire)
    }

    /// Work units per second that real-time streams may reserve together.
    pub fn realtime_budget(&self) -> f64 {
        self.realtime_per_s
    }

    /// Work units of plans and learns that may be queued or running at once.
    pub fn batch_budget(&self) -> f64 {
        self.batch_queue
    }

    /// Work units of plans and learns queued or running now.
    pub fn batch_in_use(&self) -> u64 {
        self.batch_used.load(Ordering::Acquire)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn admission() -> Admission {
        let c = ComputeConfig {
            realtime_work_per_thread_s: 100.0,
            max_job_work: 50.0,
            max_request_work: 1000.0,
            batch_queue_work: 1500.0,
            ..ComputeConfig::default()
        };
        Admission::new(&c, 2)
    }

    #[test]
    fn real_time_rates_add_up_to_the_budget_and_come_back_when_dropped() {
        let a = admission();
        let r1 = a.realtime(150.0, 10.0, "motion").unwrap();
        let err = a.realtime(60.0, 10.0, "motion").unwrap_err();
        assert!(
            matches!(&err, ServerError::ResourceExhausted(m) if m.contains("has 5.00e1 of 2.00e2 left")),
            "{err}"
        );
        let r2 = a.realtime(50.0, 10.0, "motion").unwrap();
        assert_eq!(a.realtime_in_use(), 200);
        drop(r1);
        drop(r2);
        assert_eq!(a.realtime_in_use(), 0);
    }

    #[test]
    fn a_resized_reservation_counts_what_runs_even_beyond_the_budget() {
        let a = admission();
        let mut r = a.realtime(150.0, 10.0, "motion").unwrap();
        assert!(!r.resize(250.0), "over the budget of 200");
        assert_eq!(a.realtime_in_use(), 250);
        assert!(a.realtime(1.0, 1.0, "motion").is_err(), "nothing is left");
        assert!(r.resize(20.0));
        assert_eq!(a.realtime_in_use(), 20);
        assert!(!r.resize(f64::NAN));
        assert!(r.resize(0.0));
        let other = a.realtime(200.0, 10.0, "motion").unwrap();
        drop(r);
        assert_eq!(a.realtime_in_use(), 200);
        drop(other);
        assert_eq!(a.realtime_in_use(), 0);
    }

    #[test]
    fn one_costly_job_or_request_is_refused_whatever_is_free() {
        let a = admission();
        let err = a.realtime(1.0, 51.0, "segment_s").unwrap_err().to_string();
        assert!(err.contains("segment_s") && err.contains("5.10e1") && err.contains("max_job_work"), "{err}");
        let err = a.batch(1001.0, "duration").unwrap_err().to_string();
        assert!(err.contains("max_request_work"), "{err}");
        assert!(a.batch(f64::NAN, "duration").is_err());
        assert!(a.batch(f64::INFINITY, "duration").is_err());
    }

    #[test]
    fn batch_work_is_held_while_queued() {
        let a = admission();
        let r = a.batch(1000.0, "plan").unwrap();
        assert!(a.batch(600.0, "plan").unwrap_err().to_string().contains("busy"));
        drop(r);
        assert!(a.batch(600.0, "plan").is_ok());
    }
}
