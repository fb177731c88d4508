//! Refused attempts on the audit log (tracing target `audit`, at warn), next to the changes: who (the identity, or
//! `unauthenticated`, or what is known of a Zenoh peer), what it tried (the action), and why it was refused (the
//! reason, never a token). A refusal costs an attacker nothing, so each identity and action is logged at most
//! [`BURST`] times per [`WINDOW`]; the next line of that pair says how many were left out (`suppressed`). At most
//! [`MAX_PAIRS`] pairs are followed at once; beyond them, refusals share one pair, so a flood of made-up names
//! cannot grow memory or the log.
//!
//! | action | refused by |
//! | --- | --- |
//! | `authenticate` | the authentication of a gRPC request (no credentials, an unknown token or certificate) |
//! | the gRPC method (`/dmp.v1.PrimitiveService/List`, …) | a role or scope that does not allow it (PERMISSION_DENIED, [`crate::grpc::authentication`]) |
//! | `reflection` | gRPC reflection, for a role without it |
//! | `stream` | a reload of the access file that ends a stream it no longer allows |
//! | `zenoh publish` | a Zenoh sample the server refuses (its key, payload or a limit) |
//! | `zenoh session` | a Zenoh peer whose identity a reload revoked, still or newly connected ([`crate::zenoh_bridge::revocation`]) |

use std::collections::HashMap;
use std::sync::{Mutex, OnceLock};
use std::time::{Duration, Instant};

use tracing::warn;

/// The identity of a Zenoh sample's publisher: a sample carries none ([`crate::zenoh_bridge::revocation`]).
pub(crate) const ZENOH_PEER: &str = "zenoh peer";

/// Lines per identity and action per [`WINDOW`].
pub(crate) const BURST: u32 = 5;
/// The window of [`BURST`].
pub(crate) const WINDOW: Duration = Duration::from_secs(10);
/// Most (identity, action) pairs followed at once.
pub(crate) const MAX_PAIRS: usize = 1024;

/// One pair's current window.
#[derive(Debug)]
struct Window {
    start: Instant,
    logged: u32,
    suppressed: u64,
}

/// The rate limit of refusal lines.
#[derive(Debug, Default)]
pub(crate) struct Refusals {
    windows: Mutex<HashMap<(String, String), Window>>,
}

impl Refusals {
    /// Whether a refusal of `identity` doing `action` at `now` is logged, and if so how many of the pair were left
    /// out before it.
    fn admit(&self, identity: &str, action: &str, now: Instant) -> Option<u64> {
        // Never held across an await; the map is bounded by MAX_PAIRS.
        let mut windows = self.windows.lock().unwrap_or_else(|p| p.into_inner());
        let mut key = (identity.to_owned(), action.to_owned());
        if !windows.contains_key(&key) && windows.len() >= MAX_PAIRS {
            windows.retain(|_, w| now.duration_since(w.start) < WINDOW);
            if windows.len() >= MAX_PAIRS {
                key = ("*".into(), "*".into());
            }
        }
        let w = windows.entry(key).or_insert(Window { start: now, logged: 0, suppressed: 0 });
        let mut before = 0;
        if now.duration_since(w.start) >= WINDOW {
            before = std::mem::take(&mut w.suppressed);
            w.start = now;
            w.logged = 0;
        }
        if w.logged < BURST {
            w.logged += 1;
            Some(before + std::mem::take(&mut w.suppressed))
        } else {
            w.suppressed += 1;
            None
        }
    }
}

fn refusals() -> &'static Refusals {
    static REFUSALS: OnceLock<Refusals> = OnceLock::new();
    REFUSALS.get_or_init(Refusals::default)
}

/// Audits a refused attempt of `identity` to do `action`, for `reason`, within the rate limit.
pub(crate) fn refused(identity: &str, action: &str, reason: &dyn std::fmt::Display) {
    if let Some(suppressed) = refusals().admit(identity, action, Instant::now()) {
        warn!(target: "audit", identity, action, %reason, suppressed, "refused");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_pair_is_logged_at_most_burst_times_per_window_and_says_what_it_left_out() {
        let r = Refusals::default();
        let t0 = Instant::now();
        let logged = (0..100).filter(|_| r.admit("eve", "execute", t0).is_some()).count();
        assert_eq!(logged, BURST as usize);
        // Another pair has its own window.
        assert_eq!(r.admit("eve", "stream", t0), Some(0));
        assert_eq!(r.admit("mallory", "execute", t0), Some(0));
        // The next window's first line counts the 95 left out.
        assert_eq!(r.admit("eve", "execute", t0 + WINDOW), Some(95));
        assert_eq!(r.admit("eve", "execute", t0 + WINDOW), Some(0));
    }

    #[test]
    fn a_flood_of_names_shares_one_pair_beyond_the_bound() {
        let r = Refusals::default();
        let t0 = Instant::now();
        let logged = (0..10 * MAX_PAIRS).filter(|i| r.admit(&format!("x{i}"), "authenticate", t0).is_some());
        assert_eq!(logged.count(), MAX_PAIRS + BURST as usize);
        assert!(r.windows.lock().unwrap().len() <= MAX_PAIRS + 1);
        // Once their windows are over, the pairs make room again.
        assert_eq!(r.admit("late", "authenticate", t0 + WINDOW), Some(0));
    }
}
