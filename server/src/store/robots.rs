//! The robots' records in the store: table `robots`, key `robot_id`, value the protobuf-encoded
//! `v1::RobotRecord` (validated by the service before it is stored, see `services::robots`).
//!
//! The table was added after schema version 1 without changing it: a file written before has no such table until
//! the first put creates it, and reads treat a missing table as no record.

use dmp_proto::v1;
use prost::Message;
use redb::{Durability, ReadableDatabase, TableDefinition, TableError};

use super::{Store, storage};
use crate::error::ServerError;

/// `robot_id` -> the encoded `v1::RobotRecord`.
pub(super) const ROBOTS: TableDefinition<'_, &str, &[u8]> = TableDefinition::new("robots");

impl Store {
    /// Stores `record` as the record of its robot, replacing the one before; durable when it returns.
    pub(crate) fn put_robot(&self, record: &v1::RobotRecord) -> Result<(), ServerError> {
        let mut tx = self.db.begin_write().map_err(|e| storage("begin write", e))?;
        tx.set_durability(Durability::Immediate).map_err(|e| storage("set durability", e))?;
        {
            let mut robots = tx.open_table(ROBOTS).map_err(|e| storage("open robots", e))?;
            robots
                .insert(record.robot_id.as_str(), record.encode_to_vec().as_slice())
                .map_err(|e| storage("write robot", e))?;
        }
        tx.commit().map_err(|e| storage("commit", e))
    }

    /// The record of `robot_id`, if it has one.
    pub(crate) fn get_robot(&self, robot_id: &str) -> Result<Option<v1::RobotRecord>, ServerError> {
        let read = self.db.begin_read().map_err(|e| storage("begin read", e))?;
        let robots = match read.open_table(ROBOTS) {
            Ok(t) => t,
            Err(TableError::TableDoesNotExist(_)) => return Ok(None),
            Err(e) => return Err(storage("open robots", e)),
        };
        let Some(bytes) = robots.get(robot_id).map_err(|e| storage("read robots", e))? else {
            return Ok(None);
        };
        v1::RobotRecord::decode(bytes.value()).map(Some).map_err(|e| {
            ServerError::Storage(format!("the stored record of robot `{robot_id}` is corrupt: {e}"))
        })
    }

    /// Deletes the record of `robot_id` (NotFound when it has none).
    pub(crate) fn delete_robot(&self, robot_id: &str) -> Result<(), ServerError> {
        let mut tx = self.db.begin_write().map_err(|e| storage("begin write", e))?;
        tx.set_durability(Durability::Immediate).map_err(|e| storage("set durability", e))?;
        let removed = {
            let mut robots = tx.open_table(ROBOTS).map_err(|e| storage("open robots", e))?;
            robots.remove(robot_id).map_err(|e| storage("delete robot", e))?.is_some()
        };
        if !removed {
            tx.abort().map_err(|e| storage("abort", e))?;
            return Err(ServerError::NotFound(format!("robot `{robot_id}` has no record")));
        }
        tx.commit().map_err(|e| storage("commit", e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(id: &str, max_speed: f64) -> v1::RobotRecord {
        v1::RobotRecord {
            robot_id: id.into(),
            limits: Some(v1::Limits { max_speed, ..Default::default() }),
            footprint: Some(v1::Superquadric { semi_axes: vec![0.3, 0.2, 0.1], exponents: vec![] }),
            tool: None,
            updated_unix_ms: 7,
            margin: 0.0,
        }
    }

    #[test]
    fn a_record_is_replaced_kept_across_reopen_and_deleted() {
        let dir = tempfile::tempdir().unwrap();
        {
            let store = Store::open(dir.path()).unwrap();
            assert_eq!(store.get_robot("arm").unwrap(), None);
            store.put_robot(&record("arm", 1.0)).unwrap();
            store.put_robot(&record("arm", 0.8)).unwrap();
            store.put_robot(&record("base", 0.5)).unwrap();
        }
        let store = Store::open(dir.path()).unwrap();
        assert_eq!(store.get_robot("arm").unwrap(), Some(record("arm", 0.8)));
        assert_eq!(store.get_robot("base").unwrap(), Some(record("base", 0.5)));
        store.delete_robot("arm").unwrap();
        assert_eq!(store.get_robot("arm").unwrap(), None);
        assert!(matches!(store.delete_robot("arm"), Err(ServerError::NotFound(_))));
        assert_eq!(store.get_robot("base").unwrap(), Some(record("base", 0.5)));
    }
}
