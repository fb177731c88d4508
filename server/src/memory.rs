//! The server's memory account: every stream and every cell's obstacles reserve their estimated bytes from one
//! budget (`limits.max_server_bytes`) before they are admitted, and give them back when they are dropped (the
//! reservation is released by its `Drop`, so a stream whose task ends for any reason, or a cell that goes away,
//! can never leak its share).

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};

use crate::error::ServerError;

/// A budget of bytes shared by the whole server. Cheap to clone.
#[derive(Debug, Clone)]
pub struct MemoryBudget {
    inner: Arc<Inner>,
}

#[derive(Debug)]
struct Inner {
    used: AtomicUsize,
    limit: usize,
    /// Reservations refused so far.
    refused: AtomicU64,
}

impl MemoryBudget {
    /// A budget of `limit` bytes, none reserved.
    pub(crate) fn new(limit: usize) -> Self {
        Self { inner: Arc::new(Inner { used: AtomicUsize::new(0), limit, refused: AtomicU64::new(0) }) }
    }

    /// Bytes reserved now.
    pub fn used(&self) -> usize {
        self.inner.used.load(Ordering::Acquire)
    }

    /// The budget, bytes.
    pub(crate) fn limit(&self) -> usize {
        self.inner.limit
    }

    /// Reservations (a stream, an obstacle) refused so far for want of memory.
    pub(crate) fn refusals(&self) -> u64 {
        self.inner.refused.load(Ordering::Relaxed)
    }

    /// An empty reservation, to grow later.
    pub(crate) fn empty(&self) -> MemoryReservation {
        MemoryReservation { budget: self.clone(), bytes: 0 }
    }

    /// Reserves `bytes` for `what` (named in the refusal), or ResourceExhausted when the server's budget cannot
    /// hold them.
    pub(crate) fn reserve(&self, what: &str, bytes: usize) -> Result<MemoryReservation, ServerError> {
        let mut r = self.empty();
        r.grow(what, bytes)?;
        Ok(r)
    }

    fn take(&self, what: &str, bytes: usize) -> Result<(), ServerError> {
        let limit = self.inner.limit;
        self.inner
            .used
            .fetch_update(Ordering::AcqRel, Ordering::Acquire, |used| {
                used.checked_add(bytes).filter(|&total| total <= limit)
            })
            .map(|_| ())
            .map_err(|used| {
                self.inner.refused.fetch_add(1, Ordering::Relaxed);
                ServerError::ResourceExhausted(format!(
                    "{what} needs about {bytes} bytes, and the server's memory budget (limits.max_server_bytes = \
                     {limit}) has {} left; retry later",
                    limit.saturating_sub(used)
                ))
            })
    }

    fn give_back(&self, bytes: usize) {
        self.inner.used.fetch_sub(bytes, Ordering::AcqRel);
    }
}

/// Bytes reserved from a [`MemoryBudget`]; released when dropped.
#[derive(Debug)]
pub struct MemoryReservation {
    budget: MemoryBudget,
    bytes: usize,
}

impl MemoryReservation {
    /// Bytes held.
    #[cfg(test)]
    pub(crate) fn bytes(&self) -> usize {
        self.bytes
    }

    /// Reserves `bytes` more for `what`, or ResourceExhausted (and nothing changes).
    pub(crate) fn grow(&mut self, what: &str, bytes: usize) -> Result<(), ServerError> {
        self.budget.take(what, bytes)?;
        self.bytes += bytes;
        Ok(())
    }

    /// Gives `bytes` back (at most what is held).
    pub(crate) fn shrink(&mut self, bytes: usize) {
        let bytes = bytes.min(self.bytes);
        self.budget.give_back(bytes);
        self.bytes -= bytes;
    }
}

impl Drop for MemoryReservation {
    fn drop(&mut self) {
        self.budget.give_back(self.bytes);
    }
}

/// Checks `bytes` of `what` against one of the per-item limits (`limit_name` = `limit`): ResourceExhausted naming
/// the limit, the request's bytes and the limit's value.
pub(crate) fn check_within(
    what: &str,
    bytes: usize,
    limit_name: &str,
    limit: usize,
) -> Result<(), ServerError> {
    if bytes > limit {
        return Err(ServerError::ResourceExhausted(format!(
            "{what} needs about {bytes} bytes, more than limits.{limit_name} = {limit}"
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reservations_are_bounded_and_released_on_drop() {
        let budget = MemoryBudget::new(100);
        let a = budget.reserve("a stream", 60).unwrap();
        let e = budget.reserve("another stream", 50).unwrap_err();
        let msg = e.to_string();
        assert!(matches!(e, ServerError::ResourceExhausted(_)));
        assert!(
            msg.contains("another stream needs about 50 bytes") && msg.contains("max_server_bytes = 100"),
            "{msg}"
        );
        assert!(msg.contains("40 left"), "{msg}");
        assert_eq!(budget.used(), 60, "a refusal reserves nothing");
        let mut b = budget.reserve("b", 40).unwrap();
        assert_eq!(budget.used(), 100);
        b.shrink(30);
        assert_eq!((b.bytes(), budget.used()), (10, 70));
        assert!(b.grow("b", 31).is_err());
        b.grow("b", 30).unwrap();
        drop(a);
        assert_eq!(budget.used(), 40);
        drop(b);
        assert_eq!(budget.used(), 0);
    }

    #[test]
    fn per_item_limits_name_themselves() {
        assert!(check_within("segment", 10, "max_segment_bytes", 10).is_ok());
        let msg = check_within("segment", 11, "max_segment_bytes", 10).unwrap_err().to_string();
        assert_eq!(msg, "segment needs about 11 bytes, more than limits.max_segment_bytes = 10");
    }
}
