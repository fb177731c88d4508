//! Deletes on a server of a plant: tombstones. Table `tombstones`, key `(robot_id, name)`, value the version up
//! to which every version of the name is deleted.
//!
//! A delete on a stamped store ([`Store::stamped`]) removes the versions it holds and records the tombstone
//! `N = max(clock(), last version)`: every version numbered `N` or less is deleted, wherever and whenever it
//! arrives. It is ordered as versions are (`crate::plant`): a version stamped before the delete (an HLC time before
//! `N`) is deleted on every server, and one stamped after it is kept everywhere. The last version of the name
//! becomes at least `N`, so a server that saw the delete numbers its next version above it whatever its clock.
//! Two tombstones of one name merge into the larger, so applying them in any order gives the same store.
//!
//! Growth is bounded twice: one tombstone per `(robot_id, name)` at most, and a tombstone whose `N` (an NTP64
//! time) is older than [`TOMBSTONE_RETENTION`] by the clock is dropped at the next delete. A server that was down
//! longer than that may bring a deleted version back: start such a server on an empty store, it catches up.
//!
//! A store of a lone server (not stamped) keeps no tombstone: there is no one to tell.
//!
//! Forged numbers. A version or a tombstone that arrives stamped more than [`max_skew`] ahead of this server's
//! clock is refused ([`Store::insert_replica`], [`Store::apply_tombstone`]): no server's clock is that far ahead, so
//! it is forged (a record at 2^64 - 1 would otherwise be the latest forever) or its server's clock is wrong. A mark
//! held beyond that horizon (accepted before this rule, or the clock set back since) is purged by a delete of the
//! name, on any server that holds it: [`Store::delete_versions`] stamps the tombstone at the clock instead, and every
//! server applying that tombstone also drops its versions, tombstone and last version of the name that lie beyond
//! its horizon. Then the name is learned again as usual.

use std::time::Duration;

use redb::{Durability, ReadableDatabase, ReadableTable, TableDefinition, TableError};

use super::{LAST_VERSIONS, PRIMITIVES, Store, storage};
use crate::error::ServerError;

/// `(robot_id, name)` -> every version up to this one is deleted.
pub(super) const TOMBSTONES: TableDefinition<'_, (&str, &str), u64> = TableDefinition::new("tombstones");

/// How long a tombstone is kept: a server down longer than this should restart on an empty store.
pub(crate) const TOMBSTONE_RETENTION: Duration = Duration::from_secs(7 * 24 * 3600);

/// A tombstone: every version of `(robot_id, name)` up to `up_to` is deleted.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Tombstone {
    /// The robot.
    pub robot_id: String,
    /// The primitive's name.
    pub name: String,
    /// The largest version deleted.
    pub up_to: u64,
}

/// What a delete removed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Deleted {
    /// Versions removed from this store.
    pub versions: u64,
    /// The tombstone recorded, on a stamped store (what the other servers of the plant are told).
    pub tombstone: Option<Tombstone>,
}

/// An NTP64 time (seconds in the high 32 bits) `d` earlier than `t`.
fn ntp64_before(t: u64, d: Duration) -> u64 {
    t.saturating_sub(d.as_secs() << 32)
}

/// A duration in NTP64 units (seconds in the high 32 bits, the fraction in the low 32); past 2^32 s, the end of
/// time.
fn ntp64_of(d: Duration) -> u64 {
    let fraction = (u64::from(d.subsec_nanos()) << 32) / 1_000_000_000;
    d.as_secs().checked_mul(1 << 32).map_or(u64::MAX, |s| s.saturating_add(fraction))
}

/// What Zenoh's HLC refuses by default: a timestamp more than 500 ms ahead of its clock (`uhlc`'s
/// `DEFAULT_DELTA_MS`; Zenoh builds its HLC without `with_max_delta`).
const DEFAULT_MAX_SKEW: Duration = Duration::from_millis(500);

/// How far ahead of this server's clock a replicated version or tombstone may be stamped: the bound of the
/// session's HLC (`HLC::update_with_timestamp` refuses a timestamp further ahead), [`DEFAULT_MAX_SKEW`] or
/// `UHLC_MAX_DELTA_MS` when set, as `uhlc` reads it. The plant's clocks must agree within it (NTP does).
pub(crate) fn max_skew() -> Duration {
    static SKEW: std::sync::OnceLock<Duration> = std::sync::OnceLock::new();
    *SKEW.get_or_init(|| {
        std::env::var("UHLC_MAX_DELTA_MS")
            .ok()
            .and_then(|ms| ms.trim().parse().ok())
            .map_or(DEFAULT_MAX_SKEW, Duration::from_millis)
    })
}

/// Refuses a stamp `what` (a version or a tombstone) beyond `horizon`, `now` plus [`max_skew`].
pub(super) fn refuse_ahead(what: &str, stamp: u64, (now, horizon): (u64, u64)) -> Result<(), ServerError> {
    if stamp <= horizon {
        return Ok(());
    }
    let ahead = (stamp - now) as f64 / (1u64 << 32) as f64;
    Err(ServerError::FailedPrecondition(format!(
        "{what} {stamp} is stamped {ahead:.3} s ahead of this server's clock, more than the {} ms a plant's clocks \
         may differ by (forged, or its server's clock is wrong)",
        max_skew().as_millis()
    )))
}

impl Store {
    /// This server's clock and its horizon, the clock plus [`max_skew`]: what is stamped beyond it is refused, or
    /// purged by a delete. None on a lone server's store.
    pub(super) fn horizon(&self) -> Option<(u64, u64)> {
        self.origin.as_ref().map(|(_, clock)| {
            let now = clock();
            (now, now.saturating_add(ntp64_of(max_skew())))
        })
    }

    /// Deletes every version of `(robot_id, name)` held here (NotFound when none); on a stamped store it records
    /// the tombstone that the other servers apply, and drops the tombstones past [`TOMBSTONE_RETENTION`], in the
    /// same transaction. A last version or a tombstone of the name held beyond the horizon (forged) is not carried
    /// into the new tombstone, stamped at the clock: the delete purges it, here and on every server that applies
    /// the tombstone, even when no version is held here.
    pub(crate) fn delete_versions(&self, robot_id: &str, name: &str) -> Result<Deleted, ServerError> {
        self.count(super::DELETE);
        let mut tx = self.db.begin_write().map_err(|e| storage("begin write", e))?;
        tx.set_durability(Durability::Immediate).map_err(|e| storage("set durability", e))?;
        let deleted = {
            let mut prims = tx.open_table(PRIMITIVES).map_err(|e| storage("open primitives", e))?;
            let versions = remove_range(&mut prims, robot_id, name, 0, u64::MAX)?;
            let tombstone = match self.horizon() {
                Some((now, beyond)) => {
                    let mut last =
                        tx.open_table(LAST_VERSIONS).map_err(|e| storage("open last_versions", e))?;
                    let known = last
                        .get((robot_id, name))
                        .map_err(|e| storage("read last_versions", e))?
                        .map_or(0, |v| v.value());
                    let mut stones = tx.open_table(TOMBSTONES).map_err(|e| storage("open tombstones", e))?;
                    let held = stones
                        .get((robot_id, name))
                        .map_err(|e| storage("read tombstones", e))?
                        .map_or(0, |v| v.value());
                    let forged = known > beyond || held > beyond;
                    if versions == 0 && !forged {
                        None
                    } else {
                        let within = |n: u64| if n > beyond { 0 } else { n };
                        let up_to = now.max(within(known)).max(within(held));
                        last.insert((robot_id, name), up_to)
                            .map_err(|e| storage("write last_versions", e))?;
                        stones.insert((robot_id, name), up_to).map_err(|e| storage("write tombstones", e))?;
                        expire(&mut stones, ntp64_before(now, TOMBSTONE_RETENTION))?;
                        Some(Tombstone { robot_id: robot_id.into(), name: name.into(), up_to })
                    }
                }
                None => None,
            };
            Deleted { versions, tombstone }
        };
        if deleted.versions == 0 && deleted.tombstone.is_none() {
            tx.abort().map_err(|e| storage("abort", e))?;
            return Err(ServerError::NotFound(format!("robot `{robot_id}` has no primitive named `{name}`")));
        }
        tx.commit().map_err(|e| storage("commit", e))?;
        Ok(deleted)
    }

    /// Applies a tombstone from another server of the plant: removes the versions up to `up_to` and records it
    /// (merged with the one held), durable when it returns. Returns whether the store changed. A tombstone past
    /// [`TOMBSTONE_RETENTION`] still removes its versions but is not recorded (nor the expired ones held kept), so
    /// that expired tombstones do not travel back and forth between servers' catch-ups. A tombstone stamped beyond
    /// the horizon is refused; one within it also purges the name's versions, tombstone and last version held
    /// beyond the horizon (forged: a delete of the name is how an operator purges them across the plant).
    pub(crate) fn apply_tombstone(&self, t: &Tombstone) -> Result<bool, ServerError> {
        self.count(super::DELETE);
        let (robot_id, name) = (t.robot_id.as_str(), t.name.as_str());
        let horizon = self.horizon();
        if let Some(h) = horizon {
            refuse_ahead("tombstone", t.up_to, h)?;
        }
        let beyond = horizon.map_or(u64::MAX, |(_, beyond)| beyond);
        let oldest_kept = horizon.map(|(now, _)| ntp64_before(now, TOMBSTONE_RETENTION));
        let expired = oldest_kept.is_some_and(|oldest| t.up_to < oldest);
        let mut tx = self.db.begin_write().map_err(|e| storage("begin write", e))?;
        tx.set_durability(Durability::Immediate).map_err(|e| storage("set durability", e))?;
        let changed = {
            let mut stones = tx.open_table(TOMBSTONES).map_err(|e| storage("open tombstones", e))?;
            let mut prims = tx.open_table(PRIMITIVES).map_err(|e| storage("open primitives", e))?;
            let mut last = tx.open_table(LAST_VERSIONS).map_err(|e| storage("open last_versions", e))?;
            // What is held beyond the horizon first: forged, purged.
            let mut held =
                stones.get((robot_id, name)).map_err(|e| storage("read tombstones", e))?.map(|v| v.value());
            let mut known = last
                .get((robot_id, name))
                .map_err(|e| storage("read last_versions", e))?
                .map_or(0, |v| v.value());
            let mut purged =
                beyond < u64::MAX && remove_range(&mut prims, robot_id, name, beyond + 1, u64::MAX)? > 0;
            if held.is_some_and(|h| h > beyond) {
                stones.remove((robot_id, name)).map_err(|e| storage("purge tombstone", e))?;
                held = None;
                purged = true;
            }
            if known > beyond {
                known = held.unwrap_or(0).max(t.up_to);
                last.insert((robot_id, name), known).map_err(|e| storage("write last_versions", e))?;
                purged = true;
            }
            if held.is_some_and(|h| h >= t.up_to) {
                purged
            } else if expired {
                remove_range(&mut prims, robot_id, name, 0, t.up_to)? > 0 || purged
            } else {
                merge(&mut stones, robot_id, name, t.up_to)?;
                if let Some(oldest) = oldest_kept {
                    expire(&mut stones, oldest)?;
                }
                remove_range(&mut prims, robot_id, name, 0, t.up_to)?;
                if t.up_to > known {
                    last.insert((robot_id, name), t.up_to).map_err(|e| storage("write last_versions", e))?;
                }
                true
            }
        };
        if changed {
            tx.commit().map_err(|e| storage("commit", e))?;
        } else {
            tx.abort().map_err(|e| storage("abort", e))?;
        }
        Ok(changed)
    }

    /// The version up to which `(robot_id, name)` is deleted, if a tombstone says so.
    pub fn tombstone(&self, robot_id: &str, name: &str) -> Result<Option<u64>, ServerError> {
        let read = self.db.begin_read().map_err(|e| storage("begin read", e))?;
        let stones = match read.open_table(TOMBSTONES) {
            Ok(t) => t,
            Err(TableError::TableDoesNotExist(_)) => return Ok(None),
            Err(e) => return Err(storage("open tombstones", e)),
        };
        Ok(stones.get((robot_id, name)).map_err(|e| storage("read tombstones", e))?.map(|v| v.value()))
    }

    /// Every tombstone within [`TOMBSTONE_RETENTION`], in key order (what a server of the plant answers a catch-up
    /// query with, besides the versions).
    pub(crate) fn all_tombstones(&self) -> Result<Vec<Tombstone>, ServerError> {
        let oldest_kept =
            self.origin.as_ref().map_or(0, |(_, clock)| ntp64_before(clock(), TOMBSTONE_RETENTION));
        let read = self.db.begin_read().map_err(|e| storage("begin read", e))?;
        let stones = match read.open_table(TOMBSTONES) {
            Ok(t) => t,
            Err(TableError::TableDoesNotExist(_)) => return Ok(Vec::new()),
            Err(e) => return Err(storage("open tombstones", e)),
        };
        let mut out = Vec::new();
        for entry in stones.iter().map_err(|e| storage("read tombstones", e))? {
            let (k, v) = entry.map_err(|e| storage("read tombstones", e))?;
            let (robot_id, name) = k.value();
            if v.value() >= oldest_kept {
                out.push(Tombstone { robot_id: robot_id.into(), name: name.into(), up_to: v.value() });
            }
        }
        Ok(out)
    }
}

/// Whether a tombstone in `tx` deletes `version` of `(robot_id, name)` (a version arriving from another server).
pub(super) fn deleted(
    tx: &redb::WriteTransaction,
    robot_id: &str,
    name: &str,
    version: u64,
) -> Result<bool, ServerError> {
    let stones = tx.open_table(TOMBSTONES).map_err(|e| storage("open tombstones", e))?;
    let up_to = stones.get((robot_id, name)).map_err(|e| storage("read tombstones", e))?.map(|v| v.value());
    Ok(up_to.is_some_and(|n| version <= n))
}

/// Records the tombstone `up_to` of `(robot_id, name)`, merged with the one held (the larger); returns it.
fn merge(
    stones: &mut redb::Table<'_, (&str, &str), u64>,
    robot_id: &str,
    name: &str,
    up_to: u64,
) -> Result<u64, ServerError> {
    let held =
        stones.get((robot_id, name)).map_err(|e| storage("read tombstones", e))?.map_or(0, |v| v.value());
    let up_to = up_to.max(held);
    stones.insert((robot_id, name), up_to).map_err(|e| storage("write tombstones", e))?;
    Ok(up_to)
}

/// Drops the tombstones older than `before`.
fn expire(stones: &mut redb::Table<'_, (&str, &str), u64>, before: u64) -> Result<(), ServerError> {
    stones.retain(|_, up_to| up_to >= before).map_err(|e| storage("expire tombstones", e))
}

/// Removes the versions of `(robot_id, name)` from `from` to `to` (both included); returns how many.
fn remove_range(
    prims: &mut redb::Table<'_, (&str, &str, u64), &[u8]>,
    robot_id: &str,
    name: &str,
    from: u64,
    to: u64,
) -> Result<u64, ServerError> {
    let versions: Vec<u64> = prims
        .range((robot_id, name, from)..=(robot_id, name, to))
        .map_err(|e| storage("read primitives", e))?
        .map(|entry| entry.map(|(k, _)| k.value().2))
        .collect::<Result<_, _>>()
        .map_err(|e| storage("read primitives", e))?;
    for v in &versions {
        prims.remove((robot_id, name, *v)).map_err(|e| storage("delete primitive", e))?;
    }
    Ok(versions.len() as u64)
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicU64, Ordering};

    use super::*;
    use crate::store::VersionClock;

    fn line() -> dmp::Primitive {
        dmp::Primitive::straight_line(5, 4.0, vec![1050.0, 900.0], None, 1.0, vec![0.0, 0.0], vec![1.0, 1.0])
            .unwrap()
    }

    /// A stamped store whose clock reads `now`.
    fn stamped(dir: &std::path::Path, id: &str, now: &Arc<AtomicU64>) -> Store {
        let now = now.clone();
        let clock: VersionClock = Arc::new(move || now.load(Ordering::SeqCst));
        Store::open(dir).unwrap().stamped(id, clock)
    }

    #[test]
    fn a_delete_stamps_a_tombstone_that_deletes_older_versions_everywhere_and_keeps_newer() {
        let (d1, d2) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
        let (t1, t2) = (Arc::new(AtomicU64::new(100)), Arc::new(AtomicU64::new(50)));
        let (s1, s2) = (stamped(d1.path(), "s1", &t1), stamped(d2.path(), "s2", &t2));
        let old = s1.put("r", "x", &line(), 1).unwrap();
        assert_eq!(old.version, 100);
        // s2 has not seen it yet; s1 deletes it at time 200.
        t1.store(200, Ordering::SeqCst);
        let d = s1.delete_versions("r", "x").unwrap();
        let t = d.tombstone.unwrap();
        assert_eq!((d.versions, t.up_to), (1, 200));
        // The version arrives at s2 after the tombstone: refused. Applying a tombstone twice changes nothing.
        assert!(s2.apply_tombstone(&t).unwrap());
        assert!(!s2.apply_tombstone(&t).unwrap());
        assert!(!s2.insert_replica(&old).unwrap());
        assert!(s2.get("r", "x", 0).is_err());
        // s2's clock is behind (50), yet its next version is above the delete.
        let new = s2.put("r", "x", &line(), 2).unwrap();
        assert_eq!(new.version, 201);
        assert!(s1.insert_replica(&new).unwrap());
        // A stale copy of the tombstone does not delete the newer version.
        assert!(!s1.apply_tombstone(&t).unwrap());
        assert_eq!(s1.get("r", "x", 0).unwrap().version, 201);
        // Tombstones survive a reopen.
        drop(s2);
        let s2 = stamped(d2.path(), "s2", &t2);
        assert_eq!(s2.tombstone("r", "x").unwrap(), Some(200));
        assert_eq!(s2.all_tombstones().unwrap(), vec![t]);
    }

    #[test]
    fn a_tombstone_past_the_retention_is_dropped_and_a_lone_store_keeps_none() {
        let dir = tempfile::tempdir().unwrap();
        let day = 86_400u64 << 32;
        let now = Arc::new(AtomicU64::new(day));
        let s = stamped(dir.path(), "s1", &now);
        s.put("r", "a", &line(), 1).unwrap();
        s.delete_versions("r", "a").unwrap();
        now.store(day * 9, Ordering::SeqCst);
        s.put("r", "b", &line(), 1).unwrap();
        s.delete_versions("r", "b").unwrap();
        let names: Vec<String> = s.all_tombstones().unwrap().into_iter().map(|t| t.name).collect();
        assert_eq!(names, ["b"], "the tombstone of 8 days ago went");

        // One of 8 days ago arriving from another server (a catch-up) removes its versions but is not kept, nor
        // answered on: expired tombstones do not travel back and forth.
        s.put("r", "c", &line(), 1).unwrap();
        let stale = Tombstone { robot_id: "r".into(), name: "c".into(), up_to: day * 9 + 1 };
        let expired = Tombstone { robot_id: "r".into(), name: "d".into(), up_to: day };
        s.put("r", "d", &line(), 1).unwrap();
        assert!(s.apply_tombstone(&expired).is_ok());
        assert!(s.get("r", "d", 0).is_ok(), "its versions are newer than it");
        assert_eq!(s.tombstone("r", "d").unwrap(), None, "not recorded");
        assert!(s.apply_tombstone(&stale).unwrap());
        assert!(s.get("r", "c", 0).is_err());
        // 8 days later: the tombstones of b and c expire, at the next tombstone applied and in the answers.
        now.store(day * 17, Ordering::SeqCst);
        assert!(s.all_tombstones().unwrap().is_empty());
        s.put("r", "e", &line(), 1).unwrap();
        let fresh = Tombstone { robot_id: "r".into(), name: "e".into(), up_to: day * 17 + 5 };
        assert!(s.apply_tombstone(&fresh).unwrap());
        assert_eq!((s.tombstone("r", "b").unwrap(), s.tombstone("r", "c").unwrap()), (None, None));
        assert_eq!(s.all_tombstones().unwrap(), vec![fresh]);

        let lone_dir = tempfile::tempdir().unwrap();
        let lone = Store::open(lone_dir.path()).unwrap();
        lone.put("r", "a", &line(), 1).unwrap();
        assert_eq!(lone.delete_versions("r", "a").unwrap(), Deleted { versions: 1, tombstone: None });
        assert!(lone.all_tombstones().unwrap().is_empty());
    }

    /// An NTP64 time in 2025, as a plant's clocks read.
    const NOW: u64 = 3_960_000_000 << 32;

    #[test]
    fn a_version_or_tombstone_stamped_beyond_the_skew_is_refused_and_versions_never_wrap() {
        let dir = tempfile::tempdir().unwrap();
        let now = Arc::new(AtomicU64::new(NOW));
        let s = stamped(dir.path(), "s1", &now);
        let mut forged = s.put("r", "x", &line(), 1).unwrap();
        assert_eq!(forged.version, NOW);
        let ms = |n: u64| ntp64_of(Duration::from_millis(n));
        for (version, kept) in [(u64::MAX, false), (NOW + ms(600), false), (NOW + ms(400), true)] {
            forged.version = version;
            let stone = Tombstone { robot_id: "r".into(), name: "y".into(), up_to: version };
            for got in [s.insert_replica(&forged), s.apply_tombstone(&stone)] {
                match got {
                    Ok(stored) => assert!(kept && stored, "{version} stored"),
                    Err(e) => {
                        assert!(!kept, "{version}: {e}");
                        assert!(matches!(e, ServerError::FailedPrecondition(_)), "{e}");
                        assert!(e.to_string().contains("ahead of this server's clock"), "{e}");
                    }
                }
            }
        }
        assert_eq!(s.get("r", "x", 0).unwrap().version, NOW + ms(400));
        assert_eq!(s.tombstone("r", "y").unwrap(), Some(NOW + ms(400)));

        // A lone store has no clock to bound by: it never wraps either, it refuses.
        let lone_dir = tempfile::tempdir().unwrap();
        let lone = Store::open(lone_dir.path()).unwrap();
        forged.version = u64::MAX;
        assert!(lone.insert_replica(&forged).unwrap());
        let e = lone.put("r", "x", &line(), 2).unwrap_err();
        assert!(e.to_string().contains("used every version number"), "{e}");
        assert_eq!(lone.get("r", "x", 0).unwrap().version, u64::MAX, "nothing stored at 0");
    }

    #[test]
    fn a_delete_purges_forged_marks_held_from_before_on_every_server_and_the_name_is_learned_again() {
        let (d1, d2) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
        // Both clocks at the end of time: what a server accepted before forged numbers were refused.
        let (t1, t2) = (Arc::new(AtomicU64::new(u64::MAX)), Arc::new(AtomicU64::new(u64::MAX)));
        let (s1, s2) = (stamped(d1.path(), "s1", &t1), stamped(d2.path(), "s2", &t2));
        let legit = s1.put("r", "x", &line(), 1).unwrap();
        let mut forged = legit.clone();
        forged.version = u64::MAX - 7;
        for s in [&s1, &s2] {
            s.insert_replica(&forged).unwrap();
        }
        let stone = Tombstone { robot_id: "r".into(), name: "y".into(), up_to: u64::MAX };
        assert!(s2.apply_tombstone(&stone).unwrap());
        t1.store(NOW, Ordering::SeqCst);
        t2.store(NOW - 5, Ordering::SeqCst);

        // The forged version is the latest, and a learn would follow it: refused, naming the purge.
        let e = s1.put("r", "x", &line(), 2).unwrap_err();
        assert!(
            matches!(e, ServerError::FailedPrecondition(_)) && e.to_string().contains("delete the name"),
            "{e}"
        );
        // The operator deletes it on s1: the tombstone is stamped at the clock, not after the forged version.
        let d = s1.delete_versions("r", "x").unwrap();
        let t = d.tombstone.unwrap();
        assert_eq!(t.up_to, NOW);
        assert!(s2.apply_tombstone(&t).unwrap(), "s2 purges its forged version with it");
        assert!(s2.get("r", "x", 0).is_err());
        // Learned again on either: above the delete, the latest on both.
        let again = s2.put("r", "x", &line(), 3).unwrap();
        assert!(again.version > NOW && again.version < NOW + (1 << 32), "{}", again.version);
        assert!(s1.insert_replica(&again).unwrap());
        for s in [&s1, &s2] {
            assert_eq!(s.get("r", "x", 0).unwrap().version, again.version);
        }

        // A forged tombstone alone (no version held): the name cannot be learned, a delete purges it.
        let e = s2.put("r", "y", &line(), 4).unwrap_err();
        assert!(e.to_string().contains("delete the name"), "{e}");
        let d = s2.delete_versions("r", "y").unwrap();
        let t = d.tombstone.unwrap();
        assert_eq!((d.versions, t.up_to), (0, NOW - 5));
        assert_eq!(s2.tombstone("r", "y").unwrap(), Some(NOW - 5));
        let y = s2.put("r", "y", &line(), 5).unwrap();
        assert!(s1.apply_tombstone(&t).unwrap());
        assert!(s1.insert_replica(&y).unwrap(), "y replicates again");
        // A name with nothing held, forged or not, is still not found.
        assert!(matches!(s1.delete_versions("r", "none"), Err(ServerError::NotFound(_))));
    }
}
