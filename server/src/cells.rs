//! The cells one server serves. A cell is a scene of its own (obstacles, and the states of the robots working in
//! it): a robot avoids its cell's obstacles and its cell-mates, nothing of the other cells. Zenoh keys carry the
//! cell (`dmp/<cell>/...`); a gRPC request names its cell, and an empty name means the server's default cell.
//! Cells are created on first use, up to `limits.max_cells`, and reclaimed when nothing uses them any more (no
//! obstacle, no robot, no stream, no watch): a delete never creates one, nor does a motion, which runs only in a
//! known cell ([`known`]).

pub mod cell;
pub(crate) mod directory;
pub(crate) mod known;
pub mod rendezvous;
pub(crate) mod robot_bus;
pub(crate) mod staleness;
pub(crate) mod state_admission;
pub(crate) mod taken;

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::sync::{Arc, Mutex};

use dmp_proto::keys::check_name;

use crate::cells::cell::Cell;
use crate::cells::directory::Directory;
use crate::cells::taken::{GivenBack, TakenCells};
use crate::config::scene::SceneConfig;
use crate::config::{Config, RequestLimits};
use crate::error::ServerError;
use crate::memory::MemoryBudget;

/// Every cell's scene, by name. Cheap to clone.
#[derive(Debug, Clone)]
pub struct Cells {
    default: Arc<str>,
    max_cells: usize,
    max_obstacles: usize,
    max_scene_bytes: usize,
    memory: MemoryBudget,
    /// Half-width of the workspace box every obstacle's centre must lie in, metres.
    workspace_m: f64,
    /// Each cell's staleness rule is read from here when it is created.
    scene: Arc<SceneConfig>,
    /// The lock is held only to look up or insert, never across an await.
    map: Arc<Mutex<HashMap<Arc<str>, Cell>>>,
    /// The cells served (`cells` of the configuration); None: any.
    served: Option<Arc<BTreeSet<String>>>,
    /// For a cell, the cells of this server whose robots avoid its robots (`plant.neighbours`, reversed).
    avoiders: Arc<HashMap<String, Vec<String>>>,
    /// The plant's servers, to name the one serving a cell this server does not.
    directory: Directory,
    /// The cells served for a dead server of the plant (fail-over), on top of `served`.
    taken: TakenCells,
}

impl Cells {
    /// The cells of a server whose default cell is `default` (created now); each scene holds at most
    /// `max_obstacles`, and there are at most `max_cells`.
    #[cfg(test)]
    pub(crate) fn new(default: &str, max_cells: usize, max_obstacles: usize) -> Result<Self, ServerError> {
        let limits = RequestLimits {
            max_cells,
            max_obstacles,
            max_scene_bytes: usize::MAX,
            ..RequestLimits::default()
        };
        Self::with_limits(default, &limits, MemoryBudget::new(usize::MAX), SceneConfig::default())
    }

    /// The cells of a server whose default cell is `default` (created now), bounded by `limits` (cells, obstacles
    /// and bytes per scene); the scenes reserve their memory from `memory`, and their obstacles go stale by
    /// `scene` (`[scene]` of the configuration).
    pub(crate) fn with_limits(
        default: &str,
        limits: &RequestLimits,
        memory: MemoryBudget,
        scene: SceneConfig,
    ) -> Result<Self, ServerError> {
        check_name("cell", default)?;
        let cells = Self {
            default: default.into(),
            max_cells: limits.max_cells.max(1),
            max_obstacles: limits.max_obstacles,
            max_scene_bytes: limits.max_scene_bytes,
            memory,
            workspace_m: limits.workspace_m,
            scene: Arc::new(scene),
            map: Arc::default(),
            served: None,
            avoiders: Arc::default(),
            directory: Directory::default(),
            taken: TakenCells::default(),
        };
        cells.get("")?;
        Ok(cells)
    }

    /// The cells `config` describes (its default cell, the cells it serves, their neighbours, `[scene]`), each
    /// scene reserving from `memory`, naming the plant's server of a cell they do not serve from `directory`.
    pub(crate) fn from_config(
        config: &Config,
        memory: MemoryBudget,
        directory: Directory,
    ) -> Result<Self, ServerError> {
        config.scene.check()?;
        config.check_plant()?;
        Ok(Self::with_limits(config.default_cell(), &config.limits, memory, config.scene.clone())?
            .serving(&config.cells)
            .with_neighbours(&config.plant.neighbours)
            .with_directory(directory))
    }

    /// The same cells, serving only `cells` (empty: any cell); the default cell must be one of them.
    pub(crate) fn serving(mut self, cells: &[String]) -> Self {
        if !cells.is_empty() {
            let mut set: BTreeSet<String> = cells.iter().cloned().collect();
            set.insert(self.default.to_string());
            self.served = Some(Arc::new(set));
        }
        self
    }

    /// The same cells, whose robots also avoid those of their neighbours: `neighbours` lists, for a cell, the cells
    /// whose robots it avoids.
    pub(crate) fn with_neighbours(mut self, neighbours: &BTreeMap<String, Vec<String>>) -> Self {
        let mut avoiders: HashMap<String, Vec<String>> = HashMap::new();
        for (cell, others) in neighbours {
            for other in others.iter().filter(|o| *o != cell) {
                avoiders.entry(other.clone()).or_default().push(cell.clone());
            }
        }
        self.avoiders = Arc::new(avoiders);
        self
    }

    /// The same cells, naming the plant's server of a cell they do not serve from `directory`.
    pub(crate) fn with_directory(mut self, directory: Directory) -> Self {
        self.directory = directory;
        self
    }

    /// The default cell's name.
    pub(crate) fn default_cell(&self) -> &str {
        &self.default
    }

    /// The plant's live servers as this server knows them.
    pub fn directory(&self) -> &Directory {
        &self.directory
    }

    /// The cells served (its own: not those taken over); None: any.
    pub(crate) fn served(&self) -> Option<Vec<String>> {
        self.served.as_ref().map(|s| s.iter().cloned().collect())
    }

    /// The cells served for a dead server of the plant ([`crate::plant::failover`]).
    pub(crate) fn taken(&self) -> &TakenCells {
        &self.taken
    }

    /// Whether this server serves `cell` (a checked name): one of its own, or one taken over.
    pub fn serves(&self, cell: &str) -> bool {
        self.served.as_ref().is_none_or(|s| s.contains(cell)) || self.taken.contains(cell)
    }

    /// Drops the scene of `cell` (a cell given back after a fail-over: its server keeps it now); streams still
    /// holding it end on their own. Never the default cell.
    pub(crate) fn forget(&self, cell: &str) {
        if cell != &*self.default {
            self.map.lock().unwrap_or_else(|p| p.into_inner()).remove(cell);
        }
    }

    /// The cells of this server whose robots avoid the robots of `cell` (its neighbours that list it).
    pub(crate) fn avoiders_of(&self, cell: &str) -> &[String] {
        self.avoiders.get(cell).map_or(&[], Vec::as_slice)
    }

    /// For a stream starting in `cell` (resolved earlier, maybe several awaits ago): what ends it when the cell, a
    /// taken one, goes back (None for a cell of its own), or the refusal when it went back in the meantime.
    pub(crate) fn stream_guard(&self, cell: &str) -> Result<Option<GivenBack>, ServerError> {
        let given_back = self.taken.until_given_back(cell);
        if given_back.is_none() && !self.serves(cell) {
            return Err(self.not_served(cell));
        }
        Ok(given_back)
    }

    /// The refusal of a cell this server does not serve, naming the server that does when one is known.
    fn not_served(&self, cell: &str) -> ServerError {
        let served = self.served().unwrap_or_default().join(", ");
        let owner = match self.directory.owner_of(cell) {
            Some(s) => format!("it is served by server `{}` at {}", s.server_id, s.grpc_address),
            // A cell whose server is gone: the survivor the fail-over gives it to.
            None => match self
                .directory
                .holder_of(cell, None)
                .and_then(|(home, h)| self.directory.get(&h).map(|s| (home, s)))
            {
                Some((home, s)) => format!(
                    "its server `{home}` is gone, and server `{}` at {} serves it meanwhile",
                    s.server_id, s.grpc_address
                ),
                None => "no server of the plant is known to serve it".into(),
            },
        };
        ServerError::FailedPrecondition(format!(
            "cell `{cell}` is not served by this server (it serves {served}): {owner}"
        ))
    }

    /// The name of `cell` (empty: the default cell's), checked: what access rules are matched against, before any
    /// cell is created. A cell this server does not serve is refused ([`Cells::serving`]).
    pub(crate) fn resolve<'a>(&'a self, cell: &'a str) -> Result<&'a str, ServerError> {
        let name = if cell.is_empty() { &*self.default } else { cell };
        check_name("cell", name)?;
        if !self.serves(name) {
            return Err(self.not_served(name));
        }
        Ok(name)
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
        if !self.serves(name) {
            return Err(self.not_served(name));
        }
        if map.len() >= self.max_cells {
            self.reclaim_in(&mut map);
        }
        if map.len() >= self.max_cells {
            return Err(ServerError::ResourceExhausted(format!(
                "the server already serves {} cells (limits.max_cells), each in use; `{name}` is not one of them",
                self.max_cells
            )));
        }
        let name: Arc<str> = name.into();
        let scene = Cell::with_budget(
            name.clone(),
            self.max_obstacles,
            self.max_scene_bytes,
            &self.memory,
            self.workspace_m,
        )
        .with_staleness(self.scene.for_cell(&name));
        map.insert(name, scene.clone());
        Ok(scene)
    }

    /// The scene of `cell` (empty: the default cell) if it exists; never creates one (a delete or a read of a cell
    /// that does not exist has nothing to do). Fails on a name that cannot be a Zenoh key chunk.
    pub fn find(&self, cell: &str) -> Result<Option<Cell>, ServerError> {
        let name = if cell.is_empty() { &*self.default } else { cell };
        check_name("cell", name)?;
        if !self.serves(name) {
            return Ok(None);
        }
        Ok(self.map.lock().unwrap_or_else(|p| p.into_inner()).get(name).cloned())
    }

    /// Removes the cells nothing uses (no obstacle, robot, stream or watch), except the default cell; returns how
    /// many.
    pub(crate) fn reclaim(&self) -> usize {
        let mut map = self.map.lock().unwrap_or_else(|p| p.into_inner());
        self.reclaim_in(&mut map)
    }

    fn reclaim_in(&self, map: &mut HashMap<Arc<str>, Cell>) -> usize {
        let before = map.len();
        // Under the map's lock: no one can clone a cell out of the map meanwhile, so an unused cell stays unused.
        map.retain(|name, cell| **name == *self.default || !cell.is_unused());
        before - map.len()
    }

    /// Every cell's scene, in no particular order.
    pub(crate) fn all(&self) -> Vec<Cell> {
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
    use dmp_proto::v1;

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
        assert!(matches!(cells.get("x/y"), Err(ServerError::InvalidArgument { .. })));
        assert_eq!(cells.all().len(), 2);
        // `a` holds an obstacle: no room for `b`.
        assert!(matches!(cells.get("b"), Err(ServerError::ResourceExhausted(_))));
        // Emptied, `a` goes away and `b` takes its place; the default cell stays.
        a.delete("o", 0.0);
        drop(a);
        let b = cells.get("b").unwrap();
        assert_eq!(cells.len(), 2);
        assert!(cells.find("a").unwrap().is_none(), "reclaimed");
        // A cell in use (here: held, as a stream holds its cell) is not reclaimed.
        assert_eq!(cells.reclaim(), 0);
        drop(b);
        assert_eq!(cells.reclaim(), 1);
        assert_eq!(cells.len(), 1);
        assert!(cells.find("home").unwrap().is_some() && cells.find("").unwrap().is_some());
    }

    #[test]
    fn only_the_cells_served_are_and_a_refusal_names_their_server() {
        let directory = Directory::default();
        let cells = Cells::new("a", 10, 10)
            .unwrap()
            .serving(&["a".into(), "b".into()])
            .with_neighbours(&BTreeMap::from([("a".into(), vec!["c".into()])]))
            .with_directory(directory.clone());
        assert!(cells.get("b").is_ok() && cells.resolve("").unwrap() == "a");
        let e = cells.get("c").unwrap_err().to_string();
        assert!(
            e.contains("cell `c` is not served") && e.contains("serves a, b") && e.contains("no server"),
            "{e}"
        );
        assert!(cells.find("c").unwrap().is_none());
        directory.insert(v1::PlantServer {
            server_id: "s2".into(),
            grpc_address: "http://s2:1".into(),
            cells: vec!["c".into()],
            ..Default::default()
        });
        let e = cells.resolve("c").unwrap_err();
        assert!(
            matches!(&e, ServerError::FailedPrecondition(m) if m.contains("served by server `s2` at http://s2:1"))
        );
        // s2 dies; s3 lives: the fail-over gives c to s3 (the only live server besides this one, which serves a
        // and b and is not in its own directory here).
        directory.insert(v1::PlantServer {
            server_id: "s3".into(),
            grpc_address: "http://s3:1".into(),
            cells: vec!["d".into()],
            ..Default::default()
        });
        directory.remove("s2");
        let e = cells.resolve("c").unwrap_err().to_string();
        assert!(
            e.contains("its server `s2` is gone, and server `s3` at http://s3:1 serves it meanwhile"),
            "{e}"
        );
        assert_eq!(cells.avoiders_of("c"), ["a"]);
        assert!(cells.avoiders_of("a").is_empty());
    }

    #[test]
    fn a_watched_cell_or_one_with_robots_is_kept() {
        let cells = Cells::new("home", 3, 10).unwrap();
        let rx = cells.get("watched").unwrap().subscribe();
        cells
            .get("robots")
            .unwrap()
            .update_robot(dmp_proto::v1::RobotState { robot_id: "r".into(), ..Default::default() }, None);
        assert_eq!(cells.reclaim(), 0);
        drop(rx);
        assert_eq!(cells.reclaim(), 1);
        cells.find("robots").unwrap().unwrap().remove_robot("r");
        assert_eq!(cells.reclaim(), 1);
        assert_eq!(cells.len(), 1);
    }

    #[test]
    fn scenes_are_bounded_in_bytes_per_cell_and_across_cells() {
        let limits =
            RequestLimits { max_scene_bytes: 3_000, max_server_bytes: 5_000, ..RequestLimits::default() };
        let memory = MemoryBudget::new(limits.max_server_bytes);
        let cells = Cells::with_limits("home", &limits, memory.clone(), Default::default()).unwrap();
        let o = |id: &str| dmp_proto::v1::Obstacle {
            id: id.into(),
            shape: Some(dmp_proto::v1::obstacle::Shape::Superquadric(dmp_proto::v1::Superquadric {
                semi_axes: vec![1.0; 16],
                exponents: vec![1.0; 16],
            })),
            center: vec![0.0; 16],
            ..Default::default()
        };
        let bytes = crate::cells::cell::obstacle_bytes(&o("a1"));
        assert!(bytes > 1_000 && bytes < 1_500, "{bytes}");
        let a = cells.get("a").unwrap();
        a.put(o("a1"), 0.0).unwrap();
        a.put(o("a2"), 0.0).unwrap();
        let e = a.put(o("a3"), 0.0).unwrap_err().to_string();
        assert!(e.contains("max_scene_bytes = 3000") && e.contains("cell `a`"), "{e}");
        a.put(o("a2"), 0.0).expect("a replacement takes the place of the old one");
        assert_eq!(memory.used(), 2 * bytes);
        let b = cells.get("b").unwrap();
        b.put(o("b1"), 0.0).unwrap();
        let e = b.put(o("b2"), 0.0).unwrap_err().to_string();
        assert!(e.contains("max_server_bytes = 5000"), "{e}");
        assert_eq!(b.snapshot().obstacles.len(), 1, "a refusal changes nothing");
        a.delete("a1", 0.0);
        b.put(o("b2"), 0.0).expect("room again");
        assert_eq!(memory.used(), 3 * bytes);
        b.expire(0.0);
        assert_eq!(memory.used(), 3 * bytes, "no ttl: nothing expires");
        drop((a, b));
        assert_eq!(memory.used(), 3 * bytes, "cells with obstacles stay");
    }
}
