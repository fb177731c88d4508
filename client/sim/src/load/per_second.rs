//! Counts per second of the measurement (lock-free, allocated once): when late segments arrived, so that a report
//! tells a stall (many in one second) from a steady shortfall (a few every second).

use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

/// Events counted by the second of the wall clock in which they happened, from an origin.
#[derive(Debug)]
pub(crate) struct PerSecond {
    /// The first second's start, Unix nanoseconds.
    origin_ns: u64,
    counts: Box<[AtomicU64]>,
}

impl PerSecond {
    /// `seconds` seconds from `origin_ns` (Unix nanoseconds); events before the origin count in the first second,
    /// events after the last in the last.
    pub(crate) fn new(origin_ns: u64, seconds: usize) -> Self {
        Self { origin_ns, counts: (0..seconds.max(1)).map(|_| AtomicU64::new(0)).collect() }
    }

    /// One event at `at_ns` (Unix nanoseconds).
    pub(crate) fn record(&self, at_ns: u64) {
        let second = (at_ns.saturating_sub(self.origin_ns) / 1_000_000_000) as usize;
        self.counts[second.min(self.counts.len() - 1)].fetch_add(1, Relaxed);
    }

    /// The counts, second by second.
    pub(crate) fn counts(&self) -> Vec<u64> {
        self.counts.iter().map(|c| c.load(Relaxed)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn events_fall_in_their_second_and_outliers_in_the_ends() {
        let s = PerSecond::new(10_000_000_000, 3);
        for at in
            [9_000_000_000, 10_000_000_000, 10_999_999_999, 11_000_000_000, 12_500_000_000, 99_000_000_000]
        {
            s.record(at);
        }
        assert_eq!(s.counts(), vec![3, 1, 2]);
        assert_eq!(PerSecond::new(0, 0).counts(), vec![0]);
    }
}
