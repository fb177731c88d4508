//! The cells one server serves. A cell is a scene of its own (obstacles, and the states of the robots working in
//! it): a robot avoids its cell's obstacles and its cell-mates, nothing of the other cells. Zenoh keys carry the
//! cell (`dmp/<cell>/...`); a gRPC request names its cell, and an empty name means the server's default cell.
//! Cells are created on first use, up to `limits.max_cells`.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use dmp_proto::keys::check_name;

use crate::cell::Cell;
use crate::error::ServerError;
use crate::staleness::SceneConfig;

/// Every cell's scene, by name. Cheap to clone.
#[derive(Debug, Clone)]
pub struct Cells {
    default: Arc<str>,
    max_cells: usize,
    max_obstacles: usize,
    /// Each cell's staleness rule is read from here when it is created.
    scene: Arc<SceneConfig>,
    /// The lock is held only to look up or insert, never across an await.
    map: Arc<Mutex<HashMap<Arc<str>, Cell>>>,
}

impl Cells {
    /// The cells of a server whose default cell is `default` (created now); each scene holds at most
    /// `max_obstacles`, and there are at most `max_cells`.
    pub fn new(default: &str, max_cells: usize, max_obstacles: usize) -> Result<Self, ServerError> {
        check_name("cell", default)?;
        Self::with_scene(default, max_cells, max_obstacles, SceneConfig::default())
    }

    /// [`Cells::new`] whose cells' obstacles go stale by `scene` (`[scene]` of the configuration).
    pub fn with_scene(
        default: &str,
        max_cells: usize,
        max_obstacles: usize,
        scene: SceneConfig,
    ) -> Result<Self, ServerError> {
        check_name("cell", default)?;
        let cells = Self {
            default: default.into(),
            max_cells: max_cells.max(1),
            max_obstacles,
            scene: Arc::new(scene),
            map: Arc::default(),
        };
        cells.get("")?;
        Ok(cells)
    }

    /// The default cell's name.
    pub fn default_cell(&self) -> &str {
        &self.default
    }

    /// The scene of `cell` (empty: the default cell), created if it is new. Fails on a name that cannot be a
    /// Zenoh key chunk, or when `max_cells` cells exist already.
    pub fn get(&self, cell: &str) -> Result<Cell, ServerError> {
        let name = if cell.is_empty() { &*self.default } else { cell };
        let mut map = self.map.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(s) = map.get(name) {
            return Ok(s.clone());
        }
        check_name("cell", name)?;
        if map.len() >= self.max_cells {
            return Err(ServerError::ResourceExhausted(format!(
                "the server already serves {} cells (the limit); `{name}` is not one of them",
                self.max_cells
            )));
        }
        let name: Arc<str> = name.into();
        let scene = Cell::new(name.clone(), self.max_obstacles).with_staleness(self.scene.for_cell(&name));
        map.insert(name, scene.clone());
        Ok(scene)
    }

    /// Every cell's scene, in no particular order.
    pub fn all(&self) -> Vec<Cell> {
        self.map.lock().unwrap_or_else(|p| p.into_inner()).values().cloned().collect()
    }

    /// How many cells exist.
    pub fn len(&self) -> usize {
        self.map.lock().unwrap_or_else(|p| p.into_inner()).len()
    }

    /// Never true: the default cell always exists.
    pub fn is_empty(&self) -> bool {
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_are_created_once_named_and_bounded() {
        let cells = Cells::new("home", 2, 10).unwrap();
        assert_eq!(cells.len(), 1);
        assert_eq!(cells.get("").unwrap().name(), "home");
        assert_eq!(cells.get("home").unwrap().name(), "home");
        let a = cells.get("a").unwrap();
        a.put(
            dmp_proto::v1::Obstacle {
                id: "o".into(),
                shape: Some(dmp_proto::v1::obstacle::Shape::Superquadric(dmp_proto::v1::Superquadric {
                    semi_axes: vec![1.0, 1.0],
                    exponents: vec![1.0, 1.0],
                })),
                center: vec![0.0, 0.0],
                ..Default::default()
            },
            0.0,
        )
        .unwrap();
        // The same scene again, and the default cell does not see it.
        assert_eq!(cells.get("a").unwrap().snapshot().obstacles.len(), 1);
        assert!(cells.get("").unwrap().snapshot().obstacles.is_empty());
        assert!(matches!(cells.get("b"), Err(ServerError::ResourceExhausted(_))));
        assert!(matches!(cells.get("x/y"), Err(ServerError::InvalidArgument { .. })));
        assert_eq!(cells.all().len(), 2);
    }
}
