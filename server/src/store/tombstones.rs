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

impl Store {
    /// Deletes every version of `(robot_id, name)` held here (NotFound when none); on a stamped store it records
    /// the tombstone that the other servers apply, and drops the tombstones past [`TOMBSTONE_RETENTION`], in the
    /// same transaction.
    pub(crate) fn delete_versions(&self, robot_id: &str, name: &str) -> Result<Deleted, ServerError> {
        self.count(super::DELETE);
        let mut tx = self.db.begin_write().map_err(|e| storage("begin write", e))?;
        tx.set_durability(Durability::Immediate).map_err(|e| storage("set durability", e))?;
        let deleted = {
            let mut prims = tx.open_table(PRIMITIVES).map_err(|e| storage("open primitives", e))?;
            let versions = remove_up_to(&mut prims, robot_id, name, u64::MAX)?;
            let tombstone = match (&self.origin, versions) {
                (Some((_, clock)), 1..) => {
                    let now = clock();
                    let mut last =
                        tx.open_table(LAST_VERSIONS).map_err(|e| storage("open last_versions", e))?;
                    let known = last
                        .get((robot_id, name))
                        .map_err(|e| storage("read last_versions", e))?
                        .map_or(0, |v| v.value());
                    let up_to = now.max(known);
                    last.insert((robot_id, name), up_to).map_err(|e| storage("write last_versions", e))?;
                    let mut stones = tx.open_table(TOMBSTONES).map_err(|e| storage("open tombstones", e))?;
                    let up_to = merge(&mut stones, robot_id, name, up_to)?;
                    expire(&mut stones, ntp64_before(now, TOMBSTONE_RETENTION))?;
                    Some(Tombstone { robot_id: robot_id.into(), name: name.into(), up_to })
                }
                _ => None,
            };
            Deleted { versions, tombstone }
        };
        if deleted.versions == 0 {
            tx.abort().map_err(|e| storage("abort", e))?;
            return Err(ServerError::NotFound(format!("robot `{robot_id}` has no primitive named `{name}`")));
        }
        tx.commit().map_err(|e| storage("commit", e))?;
        Ok(deleted)
    }

    /// Applies a tombstone from another server of the plant: removes the versions up to `up_to` and records it
    /// (merged with the one held), durable when it returns. Returns whether the store changed. A tombstone past
    /// [`TOMBSTONE_RETENTION`] still removes its versions but is not recorded (nor the expired ones held kept), so
    /// that expired tombstones do not travel back and forth between servers' catch-ups.
    pub(crate) fn apply_tombstone(&self, t: &Tombstone) -> Result<bool, ServerError> {
        self.count(super::DELETE);
        let (robot_id, name) = (t.robot_id.as_str(), t.name.as_str());
        let oldest_kept = self.origin.as_ref().map(|(_, clock)| ntp64_before(clock(), TOMBSTONE_RETENTION));
        let expired = oldest_kept.is_some_and(|oldest| t.up_to < oldest);
        let mut tx = self.db.begin_write().map_err(|e| storage("begin write", e))?;
        tx.set_durability(Durability::Immediate).map_err(|e| storage("set durability", e))?;
        let changed = {
            let mut stones = tx.open_table(TOMBSTONES).map_err(|e| storage("open tombstones", e))?;
            let held =
                stones.get((robot_id, name)).map_err(|e| storage("read tombstones", e))?.map(|v| v.value());
            if held.is_some_and(|h| h >= t.up_to) {
                false
            } else if expired {
                let mut prims = tx.open_table(PRIMITIVES).map_err(|e| storage("open primitives", e))?;
                remove_up_to(&mut prims, robot_id, name, t.up_to)? > 0
            } else {
                merge(&mut stones, robot_id, name, t.up_to)?;
                if let Some(oldest) = oldest_kept {
                    expire(&mut stones, oldest)?;
                }
                let mut prims = tx.open_table(PRIMITIVES).map_err(|e| storage("open primitives", e))?;
                remove_up_to(&mut prims, robot_id, name, t.up_to)?;
                let mut last = tx.open_table(LAST_VERSIONS).map_err(|e| storage("open last_versions", e))?;
                let known = last
                    .get((robot_id, name))
                    .map_err(|e| storage("read last_versions", e))?
                    .map_or(0, |v| v.value());
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

/// Removes the versions of `(robot_id, name)` up to `up_to`; returns how many.
fn remove_up_to(
    prims: &mut redb::Table<'_, (&str, &str, u64), &[u8]>,
    robot_id: &str,
    name: &str,
    up_to: u64,
) -> Result<u64, ServerError> {
    let versions: Vec<u64> = prims
        .range((robot_id, name, 0)..=(robot_id, name, up_to))
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
}
