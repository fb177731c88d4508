//! Percentiles without storing samples: a log-linear histogram of nanoseconds with atomic buckets (shared by every
//! robot task, lock-free, no allocation after construction), a signed variant, and the summaries of the report.
//!
//! # Buckets
//! Values below 128 ns have a bucket each. A value `v` in `[2^e, 2^(e+1))`, `e >= 7`, falls in one of 64 equal
//! buckets of that octave: index `64 (e - 6) + (v >> (e - 6))`. A bucket is at most 1/64 of its lower bound wide,
//! and a percentile is reported as its bucket's midpoint (never above the exact maximum): within 0.8 %.

use std::sync::atomic::{AtomicI64, AtomicU64, Ordering::Relaxed};

use serde::Serialize;

/// Sub-buckets per octave (a power of two).
const SUB: u64 = 64;
/// log2(SUB).
const SUB_BITS: u32 = 6;
/// Buckets of every `u64`: the linear part (`2 SUB`) and 57 octaves of `SUB`.
const BUCKETS: usize = (2 * SUB + (63 - SUB_BITS as u64) * SUB) as usize;

/// A histogram of non-negative durations in nanoseconds.
#[derive(Debug)]
pub(crate) struct Histogram {
    buckets: Box<[AtomicU64]>,
    count: AtomicU64,
    max: AtomicU64,
}

impl Default for Histogram {
    fn default() -> Self {
        Self::new()
    }
}

/// The bucket of `v`.
fn index(v: u64) -> usize {
    if v < 2 * SUB {
        return v as usize;
    }
    let e = 63 - v.leading_zeros();
    let shift = e - SUB_BITS;
    (SUB * shift as u64 + (v >> shift)) as usize
}

/// The smallest value and the width of bucket `i`.
fn bounds(i: usize) -> (u64, u64) {
    let i = i as u64;
    if i < 2 * SUB {
        return (i, 1);
    }
    let shift = i / SUB - 1;
    ((i % SUB + SUB) << shift, 1 << shift)
}

impl Histogram {
    /// An empty histogram.
    pub(crate) fn new() -> Self {
        Self {
            buckets: (0..BUCKETS).map(|_| AtomicU64::new(0)).collect(),
            count: AtomicU64::new(0),
            max: AtomicU64::new(0),
        }
    }

    /// Records one value.
    pub(crate) fn record(&self, ns: u64) {
        self.buckets[index(ns)].fetch_add(1, Relaxed);
        self.count.fetch_add(1, Relaxed);
        self.max.fetch_max(ns, Relaxed);
    }

    /// Values recorded.
    pub(crate) fn count(&self) -> u64 {
        self.count.load(Relaxed)
    }

    /// The largest value (0 when empty).
    pub(crate) fn max(&self) -> u64 {
        self.max.load(Relaxed)
    }

    /// The value of rank `rank` (1 = the smallest), as its bucket's midpoint capped at the maximum; `None` when
    /// there are fewer values.
    pub(crate) fn at_rank(&self, rank: u64) -> Option<u64> {
        if rank == 0 || rank > self.count() {
            return None;
        }
        let mut seen = 0;
        for (i, b) in self.buckets.iter().enumerate() {
            seen += b.load(Relaxed);
            if seen >= rank {
                let (low, width) = bounds(i);
                return Some((low + width / 2).min(self.max()));
            }
        }
        Some(self.max())
    }

    /// The `q`-quantile (`0 < q <= 1`, nearest rank), `None` when empty.
    pub(crate) fn quantile(&self, q: f64) -> Option<u64> {
        self.at_rank(rank(q, self.count()))
    }
}

/// The nearest rank of the `q`-quantile among `n` values (at least 1).
fn rank(q: f64, n: u64) -> u64 {
    ((q * n as f64).ceil() as u64).clamp(1, n.max(1))
}

/// A histogram of signed durations (nanoseconds): negative values are kept apart by magnitude.
#[derive(Debug, Default)]
pub(crate) struct SignedHistogram {
    negative: Histogram,
    non_negative: Histogram,
    min: AtomicI64,
    max: AtomicI64,
}

impl SignedHistogram {
    /// An empty histogram.
    pub(crate) fn new() -> Self {
        Self { min: AtomicI64::new(i64::MAX), max: AtomicI64::new(i64::MIN), ..Default::default() }
    }

    /// Records one value.
    pub(crate) fn record(&self, ns: i64) {
        if ns < 0 {
            self.negative.record(ns.unsigned_abs());
        } else {
            self.non_negative.record(ns as u64);
        }
        self.min.fetch_min(ns, Relaxed);
        self.max.fetch_max(ns, Relaxed);
    }

    /// Values recorded.
    pub(crate) fn count(&self) -> u64 {
        self.negative.count() + self.non_negative.count()
    }

    /// Values recorded that are greater than zero.
    #[cfg(test)]
    pub(crate) fn positive(&self) -> u64 {
        self.non_negative.count() - self.non_negative.buckets[0].load(Relaxed)
    }

    /// The `q`-quantile of the signed values.
    pub(crate) fn quantile(&self, q: f64) -> Option<i64> {
        let (neg, n) = (self.negative.count(), self.count());
        if n == 0 {
            return None;
        }
        let r = rank(q, n);
        if r <= neg {
            // The r-th smallest signed value is the (neg - r + 1)-th largest magnitude below zero.
            self.negative.at_rank(neg - r + 1).map(|m| -(m as i64))
        } else {
            self.non_negative.at_rank(r - neg).map(|v| v as i64)
        }
    }

    /// The `q`-quantile of `max(0, value)`.
    pub(crate) fn quantile_clamped(&self, q: f64) -> Option<u64> {
        self.quantile(q).map(|v| v.max(0) as u64)
    }

    /// The smallest value.
    pub(crate) fn min(&self) -> Option<i64> {
        (self.count() > 0).then(|| self.min.load(Relaxed))
    }

    /// The largest value.
    pub(crate) fn max(&self) -> Option<i64> {
        (self.count() > 0).then(|| self.max.load(Relaxed))
    }
}

/// Nanoseconds to milliseconds, rounded to the microsecond.
pub(crate) fn ms(ns: i64) -> f64 {
    (ns as f64 / 1e3).round() / 1e3
}

/// Percentiles of a non-negative quantity, milliseconds (`null` when nothing was measured).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Percentiles {
    /// Values measured.
    pub count: u64,
    /// Median.
    pub p50: Option<f64>,
    /// 99th percentile.
    pub p99: Option<f64>,
    /// 99.9th percentile.
    pub p999: Option<f64>,
    /// Largest.
    pub max: Option<f64>,
}

impl Percentiles {
    /// Of a histogram.
    pub(crate) fn of(h: &Histogram) -> Self {
        let q = |q| h.quantile(q).map(|v| ms(v as i64));
        Self {
            count: h.count(),
            p50: q(0.5),
            p99: q(0.99),
            p999: q(0.999),
            max: (h.count() > 0).then(|| ms(h.max() as i64)),
        }
    }

    /// Of `max(0, value)` of a signed histogram.
    pub(crate) fn clamped(h: &SignedHistogram) -> Self {
        let q = |q| h.quantile_clamped(q).map(|v| ms(v as i64));
        Self {
            count: h.count(),
            p50: q(0.5),
            p99: q(0.99),
            p999: q(0.999),
            max: h.max().map(|v| ms(v.max(0))),
        }
    }
}

/// Percentiles of a signed quantity, milliseconds.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct SignedPercentiles {
    /// Values measured.
    pub count: u64,
    /// Smallest.
    pub min: Option<f64>,
    /// 1st percentile.
    pub p1: Option<f64>,
    /// Median.
    pub p50: Option<f64>,
    /// 99th percentile.
    pub p99: Option<f64>,
    /// Largest.
    pub max: Option<f64>,
}

impl SignedPercentiles {
    /// Of a signed histogram.
    pub(crate) fn of(h: &SignedHistogram) -> Self {
        let q = |q| h.quantile(q).map(ms);
        Self {
            count: h.count(),
            min: h.min().map(ms),
            p1: q(0.01),
            p50: q(0.5),
            p99: q(0.99),
            max: h.max().map(ms),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn buckets_are_contiguous_and_narrow() {
        let mut last_end = 0;
        for i in 0..BUCKETS {
            let (low, width) = bounds(i);
            assert_eq!(low, last_end, "bucket {i}");
            assert_eq!(index(low), i);
            assert_eq!(index(low + (width - 1)), i);
            assert!(low < 2 * SUB || width * SUB <= low, "bucket {i} too wide");
            last_end = low.wrapping_add(width);
        }
        assert_eq!(last_end, 0, "the last bucket ends at 2^64");
        assert_eq!(index(u64::MAX), BUCKETS - 1);
    }

    #[test]
    fn quantiles_are_within_a_bucket_of_the_exact_ones() {
        let h = Histogram::new();
        assert_eq!(h.quantile(0.5), None);
        let values: Vec<u64> = (1..=10_000).map(|k| k * 1_000).collect();
        for &v in values.iter().rev() {
            h.record(v);
        }
        for q in [0.01, 0.5, 0.99, 0.999, 1.0] {
            let exact = values[rank(q, values.len() as u64) as usize - 1] as f64;
            let got = h.quantile(q).unwrap() as f64;
            assert!((got - exact).abs() <= exact / 64.0, "q {q}: {got} vs {exact}");
        }
        assert_eq!(h.max(), 10_000_000);
        assert_eq!(h.quantile(1.0), Some(10_000_000));
    }

    #[test]
    fn signed_quantiles_order_negative_values_first() {
        let h = SignedHistogram::new();
        assert_eq!((h.quantile(0.5), h.min(), h.max()), (None, None, None));
        // -50 ms .. +49 ms in 1 ms steps: 50 negative values, zero, 49 positive.
        for k in -50..50i64 {
            h.record(k * 1_000_000);
        }
        assert_eq!(h.count(), 100);
        assert_eq!(h.positive(), 49);
        assert_eq!((h.min(), h.max()), (Some(-50_000_000), Some(49_000_000)));
        let near = |got: Option<i64>, exact: i64| {
            let got = got.unwrap();
            assert!((got - exact).abs() <= exact.abs() / 64 + 1, "{got} vs {exact}");
        };
        near(h.quantile(0.01), -50_000_000);
        near(h.quantile(0.5), -1_000_000);
        near(h.quantile(0.51), 0);
        near(h.quantile(0.99), 48_000_000);
        assert_eq!(h.quantile_clamped(0.5), Some(0));
        let p = Percentiles::clamped(&h);
        assert_eq!((p.count, p.p50, p.max), (100, Some(0.0), Some(49.0)));
        let only_negative = SignedHistogram::new();
        only_negative.record(-3_000_000);
        only_negative.record(-2_000_000);
        assert_eq!(only_negative.max(), Some(-2_000_000));
        assert_eq!(Percentiles::clamped(&only_negative).max, Some(0.0));
    }
}
