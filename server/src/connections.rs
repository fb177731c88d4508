//! What the server knows of one gRPC connection beyond its bytes: its open streams and when a request last came,
//! so that a connection with neither for `limits.idle_timeout_s` is closed ([`crate::connections::write_batching`] does it),
//! and so that streams can be counted per connection ([`crate::connections::stream_permits`]). HTTP/2 pings do not count as
//! activity: a client that only answers the server's keepalive pings is idle.

pub(crate) mod stream_permits;
pub(crate) mod write_batching;

use std::sync::OnceLock;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::time::Duration;

/// One connection's activity. Shared by the connection and the requests that came on it.
#[derive(Debug)]
pub(crate) struct ConnectionActivity {
    streams: AtomicUsize,
    /// Nanoseconds of [`nanos_now`] at the last request or stream end.
    last_active: AtomicU64,
}

impl Default for ConnectionActivity {
    fn default() -> Self {
        Self { streams: AtomicUsize::new(0), last_active: AtomicU64::new(nanos_now()) }
    }
}

impl ConnectionActivity {
    /// A request came (or a stream ended): the connection is active now.
    pub(crate) fn touch(&self) {
        self.last_active.fetch_max(nanos_now(), Ordering::AcqRel);
    }

    /// Streams open on the connection.
    pub(crate) fn streams(&self) -> usize {
        self.streams.load(Ordering::Acquire)
    }

    /// Counts one more stream unless `max` are open already; true when counted.
    pub(crate) fn try_open_stream(&self, max: usize) -> bool {
        self.touch();
        self.streams.fetch_update(Ordering::AcqRel, Ordering::Acquire, |n| (n < max).then_some(n + 1)).is_ok()
    }

    /// One stream fewer.
    pub(crate) fn close_stream(&self) {
        self.streams.fetch_sub(1, Ordering::AcqRel);
        self.touch();
    }

    /// How long until the connection has been idle for `timeout`: None when it is idle that long already (no
    /// stream open, no request for `timeout`); with a stream open, `timeout` (look again then).
    pub(crate) fn idle_remaining(&self, timeout: Duration) -> Option<Duration> {
        if self.streams() > 0 {
            return Some(timeout);
        }
        let idle = Duration::from_nanos(nanos_now().saturating_sub(self.last_active.load(Ordering::Acquire)));
        timeout.checked_sub(idle).filter(|d| !d.is_zero())
    }
}

/// Nanoseconds since the first call (a monotonic clock of this process).
pub(crate) fn nanos_now() -> u64 {
    static EPOCH: OnceLock<std::time::Instant> = OnceLock::new();
    EPOCH.get_or_init(std::time::Instant::now).elapsed().as_nanos() as u64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_connection_is_idle_without_streams_and_requests() {
        let a = ConnectionActivity::default();
        let long = Duration::from_secs(60);
        assert!(a.idle_remaining(long).is_some(), "just opened");
        std::thread::sleep(Duration::from_millis(20));
        assert!(a.idle_remaining(Duration::from_millis(10)).is_none(), "idle for longer than the timeout");
        assert!(a.try_open_stream(1));
        assert!(!a.try_open_stream(1), "at most one");
        assert_eq!(a.streams(), 1);
        std::thread::sleep(Duration::from_millis(20));
        assert!(a.idle_remaining(Duration::from_millis(10)).is_some(), "a stream keeps it open");
        a.close_stream();
        assert!(a.idle_remaining(Duration::from_millis(10)).is_some(), "the stream's end is activity");
        assert_eq!(a.streams(), 0);
    }
}
