//! Which cells a motion may run in: the known ones. A motion (Plan, Execute, Session, ExecuteGroup) in any other
//! cell is refused rather than run in a new, empty scene, where a typo in a cell's name would plan and move a
//! robot around no obstacle at all.
//!
//! A cell is known when it is
//! - the server's default cell (always);
//! - configured: listed in `cells`, or given a `[scene.cells.<cell>]` table (an empty one declares a cell without
//!   narrowing the cells served);
//! - served for a dead server of the plant (fail-over: configured at its home);
//! - in use now: its scene holds an obstacle (put over gRPC, Zenoh or ROS 2), a robot's state is in it, or a
//!   stream executes in it.
//!
//! A watch alone does not make a cell known, nor does an earlier motion; a cell whose obstacles and robots are
//! all gone is unknown again unless configured. A cell this server does not serve is refused before, naming the
//! server that does ([`Cells::resolve`]).

use std::collections::BTreeSet;

use super::Cells;
use super::cell::Cell;
use crate::error::ServerError;

/// The most cells a refusal names.
const NAMED_AT_MOST: usize = 16;

impl Cells {
    /// The scene of `cell` (a name [`Cells::resolve`] returned) for a motion: created if it is configured and new,
    /// NOT_FOUND when it is not known. The refusal lists the known cells that `visible` lets the caller see.
    pub(crate) fn for_motion(&self, cell: &str, visible: impl Fn(&str) -> bool) -> Result<Cell, ServerError> {
        if self.is_configured(cell) {
            return self.get(cell);
        }
        let found = self.map.lock().unwrap_or_else(|p| p.into_inner()).get(cell).cloned();
        match found {
            Some(c) if in_use(&c) => Ok(c),
            _ => Err(self.unknown(cell, visible)),
        }
    }

    /// Whether `cell` is known without being in use: the default cell, a configured one, or one taken over.
    fn is_configured(&self, cell: &str) -> bool {
        cell == &*self.default
            || self.served.as_ref().is_some_and(|s| s.contains(cell))
            || self.scene.cells.contains_key(cell)
            || self.taken.contains(cell)
    }

    /// The known cells, the default one first, then by name.
    pub(crate) fn known(&self) -> Vec<String> {
        let mut names: BTreeSet<String> = self.served.iter().flat_map(|s| s.iter().cloned()).collect();
        names.extend(self.scene.cells.keys().filter(|c| self.serves(c)).cloned());
        // A cell taken over is listed once it has a scene here (it is known all the same).
        let listed = |c: &Cell| in_use(c) || self.taken.contains(c.name());
        names.extend(self.all().iter().filter(|c| listed(c)).map(|c| c.name().to_owned()));
        names.remove(&*self.default);
        std::iter::once(self.default.to_string()).chain(names).collect()
    }

    /// The refusal of a motion in `cell`, which is not known.
    fn unknown(&self, cell: &str, visible: impl Fn(&str) -> bool) -> ServerError {
        let known: Vec<String> = self.known().into_iter().filter(|c| visible(c)).collect();
        let mut named: Vec<String> = known.iter().take(NAMED_AT_MOST).map(|c| format!("`{c}`")).collect();
        if known.len() > NAMED_AT_MOST {
            named.push(format!("and {} more", known.len() - NAMED_AT_MOST));
        }
        let list = match named.len() {
            0 => "none that you may see".to_owned(),
            _ => named.join(", "),
        };
        ServerError::NotFound(format!(
            "unknown cell `{cell}`: known cells are {list} (a cell exists once it is configured, has obstacles, or \
             a robot runs in it)"
        ))
    }
}

/// Whether something is in `cell` now: an obstacle, a robot's state or an executing stream.
fn in_use(cell: &Cell) -> bool {
    !cell.snapshot().obstacles.is_empty() || cell.robot_count() > 0 || cell.streams() > 0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::RequestLimits;
    use crate::config::scene::{CellSceneConfig, SceneConfig};
    use crate::memory::MemoryBudget;
    use dmp_proto::v1;

    fn obstacle() -> v1::Obstacle {
        v1::Obstacle {
            id: "o".into(),
            shape: Some(v1::obstacle::Shape::Superquadric(v1::Superquadric {
                semi_axes: vec![1.0, 1.0],
                exponents: vec![1.0, 1.0],
            })),
            center: vec![0.0, 0.0],
            ..Default::default()
        }
    }

    fn refusal(cells: &Cells, cell: &str) -> String {
        match cells.for_motion(cell, |_| true) {
            Err(ServerError::NotFound(m)) => m,
            other => panic!("{cell}: {other:?}"),
        }
    }

    #[test]
    fn a_motion_runs_in_the_default_cell_a_configured_one_or_one_in_use() {
        let cells = Cells::new("home", 10, 10).unwrap().serving(&["home".into(), "bench".into()]);
        assert_eq!(cells.for_motion("home", |_| true).unwrap().name(), "home");
        assert_eq!(cells.for_motion("bench", |_| true).unwrap().name(), "bench", "configured, created now");
        let lone = Cells::new("home", 10, 10).unwrap();
        let m = refusal(&lone, "hmoe");
        assert!(m.starts_with("unknown cell `hmoe`: known cells are `home` (a cell exists"), "{m}");
        assert!(lone.find("hmoe").unwrap().is_none(), "a refusal creates no cell");
        // A watch does not make a cell known; an obstacle does, until it goes.
        let watched = lone.get("a").unwrap();
        let rx = watched.subscribe();
        refusal(&lone, "a");
        watched.put(obstacle(), 0.0).unwrap();
        assert_eq!(lone.for_motion("a", |_| true).unwrap().name(), "a");
        assert_eq!(lone.known(), ["home", "a"]);
        watched.delete("o", 0.0);
        refusal(&lone, "a");
        // A robot's state does too.
        watched.update_robot(v1::RobotState { robot_id: "r".into(), ..Default::default() }, None);
        assert!(lone.for_motion("a", |_| true).is_ok());
        drop(rx);
    }

    #[test]
    fn a_scene_table_declares_a_cell_and_a_refusal_names_at_most_some() {
        let mut scene = SceneConfig::default();
        scene.cells.insert("declared".into(), CellSceneConfig::default());
        let limits = RequestLimits { max_cells: 100, ..RequestLimits::default() };
        let cells = Cells::with_limits("home", &limits, MemoryBudget::new(usize::MAX), scene).unwrap();
        assert!(cells.for_motion("declared", |_| true).is_ok());
        for i in 0..20 {
            cells.get(&format!("c{i:02}")).unwrap().put(obstacle(), 0.0).unwrap();
        }
        let m = refusal(&cells, "x");
        assert!(m.contains("known cells are `home`, `c00`, `c01`"), "{m}");
        assert!(m.contains("and 6 more (a cell exists"), "{m}");
        let m = cells.for_motion("x", |c| c == "declared").unwrap_err().to_string();
        assert!(m.contains("known cells are `declared` ("), "{m}");
        let m = cells.for_motion("x", |_| false).unwrap_err().to_string();
        assert!(m.contains("known cells are none that you may see"), "{m}");
    }
}
