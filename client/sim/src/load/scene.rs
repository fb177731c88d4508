//! Scene updates over Zenoh and their latency: a perception node that moves one fixed obstacle of one cell at a
//! time (round-robin over the cells), and the matching of each update with the first segment, at any robot of
//! that cell, computed with a newer scene.
//!
//! Before a put, the updater reads the cell's scene version `v` (ListObstacles on the cell) and arms the cell's
//! [`CellProbe`] with `v` and the time of the put; the first segment of the cell that arrives with a
//! `scene_version > v` disarms it and gives the latency (arrival minus put time, both on this machine's wall
//! clock). A probe still armed when its cell is updated again, or at the end, is an unanswered update.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

use dmp_client::grpc::DmpClient;
use dmp_client::zenoh_pub::ObstaclePublisher;
use tokio::time::{Instant, MissedTickBehavior};

use super::layout::{FIXED_OBSTACLES, OBSTACLE_SHIFT, fixed_obstacle};
use super::{Errors, unix_now_ns};

/// A probe that is not armed.
const UNARMED: u64 = u64::MAX;

/// Longest wait for a ListObstacles or a put.
const CALL_TIMEOUT: Duration = Duration::from_secs(2);

/// The pending scene update of one cell (lock-free: the robots of the cell check it on every segment).
#[derive(Debug)]
pub(crate) struct CellProbe {
    /// The scene version before the update (`UNARMED`: none pending).
    baseline: AtomicU64,
    /// When the update was put, Unix nanoseconds.
    put_ns: AtomicU64,
}

impl Default for CellProbe {
    fn default() -> Self {
        Self { baseline: AtomicU64::new(UNARMED), put_ns: AtomicU64::new(0) }
    }
}

impl CellProbe {
    /// Arms the probe for an update put at `put_ns` on top of scene version `baseline`; true when the previous
    /// update was still unanswered.
    pub(crate) fn arm(&self, baseline: u64, put_ns: u64) -> bool {
        let previous = self.baseline.swap(UNARMED, Ordering::AcqRel);
        self.put_ns.store(put_ns, Ordering::Relaxed);
        self.baseline.store(baseline.min(UNARMED - 1), Ordering::Release);
        previous != UNARMED
    }

    /// A segment computed with `version` arrived at `arrival_ns`: the latency of the pending update, if this is
    /// the first segment that accounts for it.
    pub(crate) fn answer(&self, version: u64, arrival_ns: u64) -> Option<u64> {
        let baseline = self.baseline.load(Ordering::Acquire);
        if version <= baseline || baseline == UNARMED {
            return None;
        }
        self.baseline.compare_exchange(baseline, UNARMED, Ordering::AcqRel, Ordering::Relaxed).ok()?;
        Some(arrival_ns.saturating_sub(self.put_ns.load(Ordering::Relaxed)))
    }

    /// Disarms the probe; true when an update was pending.
    pub(crate) fn disarm(&self) -> bool {
        self.baseline.swap(UNARMED, Ordering::AcqRel) != UNARMED
    }
}

/// What the updater did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct UpdaterOutcome {
    /// Updates put.
    pub(crate) sent: u64,
    /// Updates no segment accounted for before the cell's next update or the end.
    pub(crate) unanswered: u64,
}

/// The updater's schedule and world.
#[derive(Debug, Clone)]
pub(crate) struct Updates {
    /// Updates per second.
    pub(crate) hz: f64,
    /// The cells (names), round-robin.
    pub(crate) cells: Vec<String>,
    /// Dimension of the obstacles.
    pub(crate) dim: usize,
    /// First update.
    pub(crate) begin: Instant,
    /// No update at or after this instant.
    pub(crate) end: Instant,
}

/// Puts updates until `u.end`, then waits `settle` for the last answers and disarms every probe. `clients[c]`
/// lists cell `c`'s obstacles (a client `with_cell`); `probes[c]` is its probe, which the robots answer.
pub(crate) async fn run_updater(
    publisher: &ObstaclePublisher,
    clients: &[DmpClient],
    probes: &[Arc<CellProbe>],
    errors: &Errors,
    u: &Updates,
    settle: Duration,
) -> UpdaterOutcome {
    let mut out = UpdaterOutcome::default();
    let n = u.cells.len();
    if n == 0 || u.hz <= 0.0 {
        return out;
    }
    let mut tick = tokio::time::interval_at(u.begin, Duration::from_secs_f64(1.0 / u.hz));
    tick.set_missed_tick_behavior(MissedTickBehavior::Delay);
    for round in 0.. {
        if tick.tick().await >= u.end {
            break;
        }
        let c = round % n;
        let k = (round / n) % FIXED_OBSTACLES;
        // Each obstacle goes out by OBSTACLE_SHIFT on one pass over the cells and back on the next.
        let shift = if (round / (n * FIXED_OBSTACLES)).is_multiple_of(2) { OBSTACLE_SHIFT } else { 0.0 };
        let baseline = match tokio::time::timeout(CALL_TIMEOUT, clients[c].list_obstacles()).await {
            Ok(Ok(snapshot)) => snapshot.scene_version,
            Ok(Err(e)) => {
                errors.add(format!("scene update: listing cell {}: {e}", u.cells[c]));
                continue;
            }
            Err(_) => {
                errors.add(format!("scene update: listing cell {} timed out", u.cells[c]));
                continue;
            }
        };
        let obstacle = fixed_obstacle(u.dim, k, shift);
        out.unanswered += probes[c].arm(baseline, unix_now_ns()) as u64;
        match tokio::time::timeout(CALL_TIMEOUT, publisher.put_proto_in(&u.cells[c], &obstacle)).await {
            Ok(Ok(())) => out.sent += 1,
            Ok(Err(e)) => {
                probes[c].disarm();
                errors.add(format!("scene update: {e}"));
            }
            Err(_) => {
                probes[c].disarm();
                errors.add("scene update: the Zenoh put timed out".to_string());
            }
        }
    }
    tokio::time::sleep(settle).await;
    for p in probes {
        out.unanswered += p.disarm() as u64;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_probe_is_answered_once_by_a_newer_version() {
        let p = CellProbe::default();
        assert_eq!(p.answer(5, 100), None, "not armed");
        assert!(!p.arm(5, 1_000));
        assert_eq!(p.answer(5, 2_000), None, "the same version does not account for the update");
        assert_eq!(p.answer(6, 3_500), Some(2_500));
        assert_eq!(p.answer(7, 4_000), None, "answered once");
        assert!(!p.disarm());
        assert!(!p.arm(7, 5_000));
        assert!(p.arm(7, 6_000), "the previous update was unanswered");
        assert_eq!(p.answer(8, 6_100), Some(100));
    }
}
