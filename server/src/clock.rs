//! The server's clock: the wall clock (Unix seconds, what robot states and segments are stamped with) and the
//! monotonic instants that pace real-time streams. Injected, so that tests can run real time on tokio's paused
//! clock: deterministic and fast.

use tokio::time::Instant;

/// Where the wall time comes from.
#[derive(Debug, Clone, Copy)]
enum Source {
    /// The system's wall clock.
    System,
    /// Tokio's clock (paused in tests), anchored to a Unix time.
    #[cfg(test)]
    Tokio { anchor: Instant, anchor_unix_s: f64 },
}

/// The server's clock. Cheap to copy.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Clock {
    source: Source,
}

impl Default for Clock {
    fn default() -> Self {
        Self::system()
    }
}

impl Clock {
    /// The system's wall clock, and tokio's instants for pacing.
    pub(crate) fn system() -> Self {
        Self { source: Source::System }
    }

    /// Wall time that follows tokio's clock from the system's wall time now: with `tokio::time::pause`, time
    /// only moves when the runtime advances it, and wall time with it.
    #[cfg(test)]
    pub(crate) fn following_tokio() -> Self {
        Self { source: Source::Tokio { anchor: Instant::now(), anchor_unix_s: system_unix_s() } }
    }

    /// Wall time, Unix seconds.
    pub(crate) fn now_unix_s(&self) -> f64 {
        match self.source {
            Source::System => system_unix_s(),
            #[cfg(test)]
            Source::Tokio { anchor, anchor_unix_s } => anchor_unix_s + anchor.elapsed().as_secs_f64(),
        }
    }

    /// The monotonic instant that real-time pacing sleeps until (tokio's, which tests may pause).
    pub(crate) fn now(&self) -> Instant {
        Instant::now()
    }
}

/// The system's wall clock, Unix seconds.
pub fn system_unix_s() -> f64 {
    std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.as_secs_f64()).unwrap_or(0.0)
}
