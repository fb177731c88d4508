//! The embedded, crash-safe store of primitives and robot records: one redb file, `<data_dir>/primitives.redb`.
//!
//! Every write is one redb transaction committed with [`Durability::Immediate`] (redb's default, set explicitly):
//! the new commit slot is written with checksums and `fsync`ed before `commit` returns, so a primitive whose
//! [`Store::put`] returned survives `kill -9` and power loss. After a crash redb opens the newest commit slot whose
//! checksum is valid.
//!
//! Layout (schema version [`SCHEMA_VERSION`]):
//!
//! | table | key | value |
//! | --- | --- | --- |
//! | `meta` | `"schema_version"` | `u64`, written when the file is created and checked on every open |
//! | `primitives` | `(robot_id, name, version)` | the protobuf-encoded `v1::PrimitiveRecord` |
//! | `last_versions` | `(robot_id, name)` | the last version ever given to the name |
//! | `robots` | `robot_id` | the protobuf-encoded `v1::RobotRecord` (`store/robots.rs`) |
//! | `tombstones` | `(robot_id, name)` | on a server of a plant, the version up to which the name is deleted (`store/tombstones.rs`) |
//!
//! Versions start at 1 and are never reused, even after a delete: `(robot_id, name, version)` always names one
//! primitive.
//!
//! The API is synchronous (redb is): services call it through `tokio::task::spawn_blocking`.

use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use dmp_proto::primitive::primitive_to_proto;
use dmp_proto::v1;
use prost::Message;
use redb::{Database, Durability, ReadableDatabase, ReadableTable, TableDefinition, TableHandle};

use crate::config::Config;
use crate::error::ServerError;

/// Version of the store's layout. A file of another version is refused on open (never silently reset).
pub(crate) const SCHEMA_VERSION: u64 = 1;

/// Name of the database file inside the data directory.
pub const FILE_NAME: &str = "primitives.redb";

const META: TableDefinition<'_, &str, u64> = TableDefinition::new("meta");
const SCHEMA_KEY: &str = "schema_version";
const PRIMITIVES: TableDefinition<'_, (&str, &str, u64), &[u8]> = TableDefinition::new("primitives");
const LAST_VERSIONS: TableDefinition<'_, (&str, &str), u64> = TableDefinition::new("last_versions");

/// The primitives of every robot. Cheap to clone; one per data directory (redb locks the file, so a second
/// server on the same directory fails to open it).
#[derive(Clone)]
pub struct Store {
    db: Arc<Database>,
    path: Arc<PathBuf>,
    /// Versions kept per `(robot_id, name)`: a put beyond removes the oldest.
    max_versions: usize,
    /// Operations so far, by kind (in the order of [`Store::operations`]).
    operations: Arc<[AtomicU64; 4]>,
    /// On a server of a plant: its id and its clock of versions ([`Store::stamped`]).
    origin: Option<(Arc<str>, VersionClock)>,
}

/// Gives the version of a new primitive on a server of a plant: its HLC time, NTP64 (`crate::plant`).
pub(crate) type VersionClock = Arc<dyn Fn() -> u64 + Send + Sync>;

/// The kinds of operation, in the order of [`Store::operations`].
const PUT: usize = 0;
const GET: usize = 1;
const LIST: usize = 2;
const DELETE: usize = 3;

impl fmt::Debug for Store {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Store").field("path", &self.path).finish_non_exhaustive()
    }
}

/// What a refusal of a damaged store file says to do.
pub(crate) const START_FRESH: &str =
    "the store file is damaged or truncated; move it away or delete it to start with an empty store";

/// A storage error naming what failed.
fn storage(what: impl fmt::Display, e: impl Into<redb::Error>) -> ServerError {
    ServerError::Storage(format!("{what}: {}", e.into()))
}

impl Store {
    /// Opens the store of `config` (`data_dir`, keeping `limits.max_versions` per primitive) on a blocking thread.
    pub(crate) async fn open_configured(config: &Config) -> Result<Store, ServerError> {
        let dir = config.data_dir.clone();
        let max_versions = config.limits.max_versions;
        tokio::task::spawn_blocking(move || Store::open(&dir).map(|s| s.keep_versions(max_versions)))
            .await
            .map_err(|e| ServerError::Internal(e.to_string()))?
    }

    /// Opens the store in `dir` (created if missing): a new file gets the current schema version, an existing one
    /// must have it.
    pub(crate) fn open(dir: impl AsRef<Path>) -> Result<Store, ServerError> {
        let dir = dir.as_ref();
        std::fs::create_dir_all(dir).map_err(|e| {
            ServerError::Storage(format!("cannot create the data directory {}: {e}", dir.display()))
        })?;
        let path = dir.join(FILE_NAME);
        let shown = path.display();
        // redb initialises a 0-byte file as a new database: an existing file that is empty lost its content
        // (a failed copy, a full disk) and is refused rather than silently served as an empty store.
        let existed = match std::fs::metadata(&path) {
            Ok(m) if m.len() == 0 => {
                return Err(ServerError::Storage(format!("{shown} is empty (0 bytes): {START_FRESH}")));
            }
            Ok(_) => true,
            Err(_) => false,
        };
        let db = Database::builder()
            // The file is small (kilobytes per primitive): verifying every page on open turns a file damaged
            // outside redb into an error instead of a panic.
            .set_check_integrity_on_open(true)
            .create(&path)
            .map_err(|e| match e {
                redb::DatabaseError::DatabaseAlreadyOpen => ServerError::Storage(format!(
                    "cannot open {shown}: it is already open (is another dmp-server using this data directory?)"
                )),
                e if existed => storage(format_args!("cannot open {shown} ({START_FRESH})"), e),
                e => storage(format_args!("cannot open {shown}"), e),
            })?;
        let store = Store {
            db: Arc::new(db),
            path: Arc::new(path.clone()),
            max_versions: usize::MAX,
            operations: Arc::default(),
            origin: None,
        };
        store.check_or_initialise()?;
        Ok(store)
    }

    /// The same store keeping at most `max_versions` (at least 1) versions of each primitive: every put beyond
    /// removes the oldest, in its own transaction (all versions are kept by default).
    pub(crate) fn keep_versions(mut self, max_versions: usize) -> Self {
        self.max_versions = max_versions.max(1);
        self
    }

    /// The same store on a server of a plant: a new version is the later of `clock()` (the server's HLC time) and
    /// the last version plus one, and its record names `server_id` as its origin; versions of other servers come
    /// through [`Store::insert_replica`].
    pub(crate) fn stamped(mut self, server_id: &str, clock: VersionClock) -> Self {
        self.origin = Some((server_id.into(), clock));
        self
    }

    /// Operations called so far (whatever their result), by kind: `put` (a learn or a put), `get`, `list` (a
    /// page), `delete`.
    pub(crate) fn operations(&self) -> [(&'static str, u64); 4] {
        let n = |i: usize| self.operations[i].load(Ordering::Relaxed);
        [("put", n(PUT)), ("get", n(GET)), ("list", n(LIST)), ("delete", n(DELETE))]
    }

    fn count(&self, kind: usize) {
        self.operations[kind].fetch_add(1, Ordering::Relaxed);
    }

    /// Writes the schema version into an empty file, or checks the one found.
    fn check_or_initialise(&self) -> Result<(), ServerError> {
        let shown = self.path.display();
        let read = self.db.begin_read().map_err(|e| storage("begin read", e))?;
        let tables: Vec<String> = read
            .list_tables()
            .map_err(|e| storage("list tables", e))?
            .map(|t| t.name().to_string())
            .collect();
        if tables.is_empty() {
            drop(read);
            let mut tx = self.db.begin_write().map_err(|e| storage("begin write", e))?;
            tx.set_durability(Durability::Immediate).map_err(|e| storage("set durability", e))?;
            {
                let mut meta = tx.open_table(META).map_err(|e| storage("create table meta", e))?;
                meta.insert(SCHEMA_KEY, SCHEMA_VERSION).map_err(|e| storage("write meta", e))?;
                tx.open_table(PRIMITIVES).map_err(|e| storage("create table primitives", e))?;
                tx.open_table(LAST_VERSIONS).map_err(|e| storage("create table last_versions", e))?;
                tx.open_table(robots::ROBOTS).map_err(|e| storage("create table robots", e))?;
                tx.open_table(tombstones::TOMBSTONES).map_err(|e| storage("create table tombstones", e))?;
            }
            tx.commit().map_err(|e| storage("commit", e))?;
            return Ok(());
        }
        if !tables.iter().any(|t| t == META.name()) {
            return Err(ServerError::Storage(format!(
                "{shown} is not a dmp-server store (no `meta` table; tables: {tables:?})"
            )));
        }
        let meta = read.open_table(META).map_err(|e| storage("open meta", e))?;
        let found = meta.get(SCHEMA_KEY).map_err(|e| storage("read meta", e))?.map(|v| v.value());
        match found {
            Some(SCHEMA_VERSION) => Ok(()),
            Some(v) => Err(ServerError::Storage(format!(
                "{shown} has schema version {v}, this server reads version {SCHEMA_VERSION}; \
                 use a matching server or migrate the file (it was left untouched)"
            ))),
            None => Err(ServerError::Storage(format!("{shown} has a `meta` table without `{SCHEMA_KEY}`"))),
        }
    }

    /// Stores `primitive` as the next version of `(robot_id, name)`; durable when it returns.
    pub(crate) fn put(
        &self,
        robot_id: &str,
        name: &str,
        primitive: &dmp::Primitive,
        now_unix_ms: i64,
    ) -> Result<v1::PrimitiveRecord, ServerError> {
        self.count(PUT);
        primitive.validate()?;
        let mut tx = self.db.begin_write().map_err(|e| storage("begin write", e))?;
        tx.set_durability(Durability::Immediate).map_err(|e| storage("set durability", e))?;
        let record = {
            let mut last = tx.open_table(LAST_VERSIONS).map_err(|e| storage("open last_versions", e))?;
            let known = last
                .get((robot_id, name))
                .map_err(|e| storage("read last_versions", e))?
                .map_or(0, |v| v.value());
            let horizon = self.horizon();
            if horizon.is_some_and(|(_, beyond)| known > beyond) {
                return Err(ServerError::FailedPrecondition(format!(
                    "the last version of robot `{robot_id}`'s `{name}` is {known}, more than {} ms ahead of this \
                     server's clock (forged, or the clock was set back): delete the name on this server to purge \
                     it across the plant, then learn it again",
                    tombstones::max_skew().as_millis()
                )));
            }
            // Never wraps: a version after u64::MAX would be 0, older than every other.
            let version = known.checked_add(1).ok_or_else(|| {
                ServerError::FailedPrecondition(format!(
                    "robot `{robot_id}`'s `{name}` has used every version number (the last is {known}): delete \
                     the name to purge it, then learn it again"
                ))
            })?;
            let version = horizon.map_or(version, |(now, _)| version.max(now));
            last.insert((robot_id, name), version).map_err(|e| storage("write last_versions", e))?;
            let record = v1::PrimitiveRecord {
                robot_id: robot_id.into(),
                name: name.into(),
                version,
                created_unix_ms: now_unix_ms,
                primitive: Some(primitive_to_proto(primitive)),
                origin_server: self.origin.as_ref().map(|(id, _)| id.to_string()).unwrap_or_default(),
            };
            let mut prims = tx.open_table(PRIMITIVES).map_err(|e| storage("open primitives", e))?;
            prims
                .insert((robot_id, name, version), record.encode_to_vec().as_slice())
                .map_err(|e| storage("write primitive", e))?;
            self.prune(&mut prims, robot_id, name)?;
            record
        };
        tx.commit().map_err(|e| storage("commit", e))?;
        Ok(record)
    }

    /// Removes the oldest versions of `(robot_id, name)` beyond `max_versions`, in the caller's transaction: a
    /// crash keeps both the new version and the removal or neither.
    fn prune(
        &self,
        prims: &mut redb::Table<'_, (&str, &str, u64), &[u8]>,
        robot_id: &str,
        name: &str,
    ) -> Result<(), ServerError> {
        let kept: Vec<u64> = prims
            .range((robot_id, name, 0)..=(robot_id, name, u64::MAX))
            .map_err(|e| storage("read primitives", e))?
            .map(|entry| entry.map(|(k, _)| k.value().2))
            .collect::<Result<_, _>>()
            .map_err(|e| storage("read primitives", e))?;
        for v in &kept[..kept.len().saturating_sub(self.max_versions)] {
            prims.remove((robot_id, name, *v)).map_err(|e| storage("prune primitive", e))?;
        }
        Ok(())
    }

    /// Stores a version that another server of the plant stored (its record, checked by the caller) unless this
    /// store holds it already; durable when it returns. Returns whether it was stored. The same version from two
    /// origins (two servers stamping the same HLC time) keeps the record of the smaller origin id, on every server.
    /// A version that a tombstone deletes is not stored.
    /// A version older than the `max_versions` kept is pruned at once, as it would have been.
    /// A version stamped beyond the horizon ([`tombstones::max_skew`] ahead of this server's clock) is refused.
    pub(crate) fn insert_replica(&self, record: &v1::PrimitiveRecord) -> Result<bool, ServerError> {
        self.count(PUT);
        let (robot_id, name, version) = (record.robot_id.as_str(), record.name.as_str(), record.version);
        if let Some(h) = self.horizon() {
            tombstones::refuse_ahead("version", version, h)?;
        }
        let mut tx = self.db.begin_write().map_err(|e| storage("begin write", e))?;
        tx.set_durability(Durability::Immediate).map_err(|e| storage("set durability", e))?;
        let stored = {
            let mut prims = tx.open_table(PRIMITIVES).map_err(|e| storage("open primitives", e))?;
            let held = prims
                .get((robot_id, name, version))
                .map_err(|e| storage("read primitives", e))?
                .map(|v| decode(v.value()))
                .transpose()?;
            let replace = held.is_none_or(|h| record.origin_server < h.origin_server)
                && !tombstones::deleted(&tx, robot_id, name, version)?;
            if replace {
                prims
                    .insert((robot_id, name, version), record.encode_to_vec().as_slice())
                    .map_err(|e| storage("write primitive", e))?;
                self.prune(&mut prims, robot_id, name)?;
                let mut last = tx.open_table(LAST_VERSIONS).map_err(|e| storage("open last_versions", e))?;
                let known = last
                    .get((robot_id, name))
                    .map_err(|e| storage("read last_versions", e))?
                    .map_or(0, |v| v.value());
                if version > known {
                    last.insert((robot_id, name), version).map_err(|e| storage("write last_versions", e))?;
                }
            }
            replace
        };
        if stored {
            tx.commit().map_err(|e| storage("commit", e))?;
        } else {
            tx.abort().map_err(|e| storage("abort", e))?;
        }
        Ok(stored)
    }

    /// Every stored version of every primitive, in key order (what a server of the plant answers a catch-up query
    /// with).
    pub(crate) fn all_records(&self) -> Result<Vec<v1::PrimitiveRecord>, ServerError> {
        self.count(LIST);
        let read = self.db.begin_read().map_err(|e| storage("begin read", e))?;
        let prims = read.open_table(PRIMITIVES).map_err(|e| storage("open primitives", e))?;
        let mut out = Vec::new();
        for entry in prims.iter().map_err(|e| storage("read primitives", e))? {
            let (_, value) = entry.map_err(|e| storage("read primitives", e))?;
            out.push(decode(value.value())?);
        }
        Ok(out)
    }

    /// One version of `(robot_id, name)`; `version` 0 means the latest.
    pub fn get(&self, robot_id: &str, name: &str, version: u64) -> Result<v1::PrimitiveRecord, ServerError> {
        self.count(GET);
        let read = self.db.begin_read().map_err(|e| storage("begin read", e))?;
        let prims = read.open_table(PRIMITIVES).map_err(|e| storage("open primitives", e))?;
        let found = if version == 0 {
            let mut range = prims
                .range((robot_id, name, 0)..=(robot_id, name, u64::MAX))
                .map_err(|e| storage("read primitives", e))?;
            range.next_back().transpose().map_err(|e| storage("read primitives", e))?.map(|(_, v)| v)
        } else {
            prims.get((robot_id, name, version)).map_err(|e| storage("read primitives", e))?
        };
        match found {
            Some(bytes) => decode(bytes.value()),
            None if version == 0 => {
                Err(ServerError::NotFound(format!("robot `{robot_id}` has no primitive named `{name}`")))
            }
            None => Err(ServerError::NotFound(format!(
                "robot `{robot_id}` has no version {version} of primitive `{name}`"
            ))),
        }
    }

    /// The latest version of each primitive of `robot_id`, sorted by name (empty when the robot has none).
    pub fn list(&self, robot_id: &str) -> Result<Vec<v1::PrimitiveRecord>, ServerError> {
        Ok(self.list_page(robot_id, None, usize::MAX)?.0)
    }

    /// One page of [`Store::list`]: at most `page_size` records whose names come after `after` (from the first
    /// when None), and the last name of the page when more follow (the next page's `after`).
    pub(crate) fn list_page(
        &self,
        robot_id: &str,
        after: Option<&str>,
        page_size: usize,
    ) -> Result<(Vec<v1::PrimitiveRecord>, Option<String>), ServerError> {
        use std::ops::Bound;
        self.count(LIST);
        let read = self.db.begin_read().map_err(|e| storage("begin read", e))?;
        let prims = read.open_table(PRIMITIVES).map_err(|e| storage("open primitives", e))?;
        let start = match after {
            Some(name) => Bound::Excluded((robot_id, name, u64::MAX)),
            None => Bound::Included((robot_id, "", 0)),
        };
        let range = prims
            .range::<(&str, &str, u64)>((start, Bound::Unbounded))
            .map_err(|e| storage("read primitives", e))?;
        // Keys are sorted by (robot, name, version): the last entry of each name is its latest version.
        let mut out: Vec<v1::PrimitiveRecord> = Vec::new();
        let mut pending: Option<(String, Vec<u8>)> = None;
        for entry in range {
            let (key, value) = entry.map_err(|e| storage("read primitives", e))?;
            let (robot, name, _) = key.value();
            if robot != robot_id {
                break;
            }
            if let Some((n, bytes)) = pending.take_if(|(n, _)| n != name) {
                debug_assert!(n.as_str() < name);
                out.push(decode(&bytes)?);
                if out.len() >= page_size.max(1) {
                    // Another name follows: the page is full.
                    return Ok((out, Some(n)));
                }
            }
            pending = Some((name.to_string(), value.value().to_vec()));
        }
        if let Some((_, bytes)) = pending {
            out.push(decode(&bytes)?);
        }
        Ok((out, None))
    }

    /// One page of the robots that have primitives, sorted by id: at most `page_size` of those `visible` lets
    /// through whose ids come after `after` (from the first when None), each with its number of names and the
    /// creation time of its newest latest version; and the last id of the page when more may follow.
    pub(crate) fn list_robots_page(
        &self,
        after: Option<&str>,
        page_size: usize,
        visible: impl Fn(&str) -> bool,
    ) -> Result<(Vec<v1::RobotSummary>, Option<String>), ServerError> {
        use std::ops::Bound;
        self.count(LIST);
        let read = self.db.begin_read().map_err(|e| storage("begin read", e))?;
        let prims = read.open_table(PRIMITIVES).map_err(|e| storage("open primitives", e))?;
        let start = match after {
            Some(robot) => Bound::Included((robot, "", 0)),
            None => Bound::Unbounded,
        };
        let range = prims
            .range::<(&str, &str, u64)>((start, Bound::Unbounded))
            .map_err(|e| storage("read primitives", e))?;
        let mut out: Vec<v1::RobotSummary> = Vec::new();
        // The entry read last: (robot, name, its bytes); keys are sorted, so the last entry of a name is its
        // latest version, the newest of that name.
        let mut last: Option<(String, String, Vec<u8>)> = None;
        let finish_name = |out: &mut Vec<v1::RobotSummary>, robot: &str, bytes: &[u8]| {
            let created = decode(bytes)?.created_unix_ms;
            match out.last_mut() {
                Some(s) if s.robot_id == robot => {
                    s.primitives += 1;
                    s.updated_unix_ms = s.updated_unix_ms.max(created);
                }
                _ => out.push(v1::RobotSummary {
                    robot_id: robot.into(),
                    primitives: 1,
                    updated_unix_ms: created,
                }),
            }
            Ok::<_, ServerError>(())
        };
        for entry in range {
            let (key, value) = entry.map_err(|e| storage("read primitives", e))?;
            let (robot, name, _) = key.value();
            if after.is_some_and(|a| robot <= a) || !visible(robot) {
                continue;
            }
            if let Some((r, _, bytes)) = last.take_if(|(r, n, _)| r != robot || n != name) {
                finish_name(&mut out, &r, &bytes)?;
                if r != robot && out.len() >= page_size.max(1) {
                    // Another robot follows: the page is full.
                    return Ok((out, Some(r)));
                }
            }
            last = Some((robot.to_string(), name.to_string(), value.value().to_vec()));
        }
        if let Some((r, _, bytes)) = last {
            finish_name(&mut out, &r, &bytes)?;
        }
        Ok((out, None))
    }

    /// Deletes every version of `(robot_id, name)`; returns how many were removed (NotFound when none). On a
    /// server of a plant it also records a tombstone ([`Store::delete_versions`]).
    #[cfg(test)]
    pub(crate) fn delete(&self, robot_id: &str, name: &str) -> Result<u64, ServerError> {
        Ok(self.delete_versions(robot_id, name)?.versions)
    }
}

fn decode(bytes: &[u8]) -> Result<v1::PrimitiveRecord, ServerError> {
    v1::PrimitiveRecord::decode(bytes)
        .map_err(|e| ServerError::Storage(format!("a stored record is corrupt: {e}")))
}

mod robots;
mod tombstones;

pub(crate) use self::tombstones::Tombstone;

#[cfg(test)]
mod tests;
