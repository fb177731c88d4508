//! A scene that goes stale: obstacles that nobody has updated for longer than their cell allows
//! (`[scene] stale_after_s`, per cell in `[scene.cells.<name>]`), measured from each obstacle's last update.
//!
//! What happens to a stale obstacle is the cell's `stale_policy`:
//!
//! | policy | the obstacle | the robots of the cell |
//! | --- | --- | --- |
//! | `keep` | stays, frozen where it was when it went stale (a moving one stops drifting), flagged | go on; their segments say `scene_stale` and carry one `SCENE_STALE` warning when it starts |
//! | `drop` | is removed | go on without it |
//! | `stop` | stays, frozen and flagged | hold position until every stale obstacle is updated or deleted; segments say `scene_stale`, one `SCENE_STALE` warning when it starts |
//!
//! The cell marks and drops obstacles ([`crate::cell::Cell::expire`], run by the reaper every
//! `zenoh_bridge::REAP_PERIOD`); a stream reads the flags from the snapshot it already watches ([`StaleGuard`]).
//! A run that ignores the scene is not affected. `stale_after_s = 0` (the default) turns it off: obstacles without
//! a `ttl_s` then live until deleted, and a moving one drifts along its velocity until then.

use std::collections::BTreeMap;

use dmp_proto::v1;
use serde::{Deserialize, Serialize};

use crate::cell::ObstacleSet;
use crate::error::ServerError;
use crate::executor::stream::Control;

/// What a cell does with an obstacle that went stale.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum StalePolicy {
    /// Keep it (frozen, flagged); the robots go on.
    #[default]
    Keep,
    /// Remove it.
    Drop,
    /// Keep it (frozen, flagged) and hold the cell's robots until fresh data arrives.
    Stop,
}

/// One cell's staleness rule.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Staleness {
    /// An obstacle not updated for longer than this, seconds, is stale; 0: never.
    pub after_s: f64,
    /// What happens to it.
    pub policy: StalePolicy,
}

impl Staleness {
    /// True when obstacles never go stale.
    pub fn is_off(&self) -> bool {
        self.after_s <= 0.0
    }
}

/// The `[scene]` section of the configuration.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SceneConfig {
    /// An obstacle not updated for longer than this, seconds, is stale; 0: off.
    pub stale_after_s: f64,
    /// What happens to a stale obstacle.
    pub stale_policy: StalePolicy,
    /// Per-cell overrides, by cell name.
    pub cells: BTreeMap<String, CellSceneConfig>,
}

/// A `[scene.cells.<name>]` table: what it sets overrides `[scene]` for that cell.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CellSceneConfig {
    /// Overrides `scene.stale_after_s`.
    pub stale_after_s: Option<f64>,
    /// Overrides `scene.stale_policy`.
    pub stale_policy: Option<StalePolicy>,
}

impl SceneConfig {
    /// The rule of `cell`.
    pub fn for_cell(&self, cell: &str) -> Staleness {
        let over = self.cells.get(cell);
        Staleness {
            after_s: over.and_then(|c| c.stale_after_s).unwrap_or(self.stale_after_s),
            policy: over.and_then(|c| c.stale_policy).unwrap_or(self.stale_policy),
        }
    }

    /// Every `stale_after_s` is finite and not negative.
    pub fn check(&self) -> Result<(), ServerError> {
        let ok = |v: f64| v.is_finite() && v >= 0.0;
        const RANGE: &str = "must be a finite number of seconds, at least 0 (0: off)";
        if !ok(self.stale_after_s) {
            return Err(ServerError::invalid("scene.stale_after_s", RANGE));
        }
        for (name, c) in &self.cells {
            if c.stale_after_s.is_some_and(|v| !ok(v)) {
                return Err(ServerError::invalid(format!("scene.cells.{name}.stale_after_s"), RANGE));
            }
        }
        Ok(())
    }
}

/// A stream's view of its cell's staleness: it flags the segments, warns once when the scene goes stale, and
/// under `stop` holds the robots (a session's Pause and Resume still decide once the scene is fresh again).
#[derive(Debug, Clone)]
pub struct StaleGuard {
    policy: StalePolicy,
    /// The run ignores the cell's scene: nothing to guard.
    ignored: bool,
    /// The stale obstacles of the last snapshot seen.
    stale: Vec<String>,
    /// The session's own Pause (true) or Resume (false), the last one received.
    paused: bool,
}

impl StaleGuard {
    /// A guard for a run in a cell of `staleness`; `ignore_scene` runs are never flagged nor held.
    pub fn new(staleness: Staleness, ignore_scene: bool) -> Self {
        Self { policy: staleness.policy, ignored: ignore_scene, stale: Vec::new(), paused: false }
    }

    /// The segments computed now are computed with stale obstacles.
    pub fn is_stale(&self) -> bool {
        !self.stale.is_empty()
    }

    /// Reads the stale obstacles of a new snapshot; pushes a `SCENE_STALE` warning into `warnings` when the scene
    /// goes from fresh to stale.
    pub fn observe(&mut self, snapshot: &ObstacleSet, warnings: &mut Vec<v1::Warning>) {
        if self.ignored {
            return;
        }
        let was_stale = self.is_stale();
        self.stale.clear();
        self.stale.extend(snapshot.stale_ids().map(str::to_string));
        if !was_stale && let Some(first) = self.stale.first() {
            let action = match self.policy {
                StalePolicy::Stop => "holding position until they are updated",
                _ => "still avoided where they were last seen",
            };
            warnings.push(v1::Warning {
                kind: v1::warning::Kind::SceneStale as i32,
                field: String::new(),
                reason: format!(
                    "{} obstacle(s) of the cell were not updated within the cell's stale_after_s: {action}",
                    self.stale.len()
                ),
                obstacle_id: first.clone(),
            });
        }
    }

    /// Notes the session's own Pause and Resume among `commands`.
    pub fn note_commands(&mut self, commands: &[Control]) {
        for c in commands {
            match c {
                Control::Pause => self.paused = true,
                Control::Resume => self.paused = false,
                _ => {}
            }
        }
    }

    /// Whether the run must hold: under `stop`, while the scene is stale (or the session paused it); `None` under
    /// the other policies and for runs that ignore the scene.
    pub fn hold(&self) -> Option<bool> {
        (self.policy == StalePolicy::Stop && !self.ignored).then_some(self.paused || self.is_stale())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_override_the_scene_section_and_bad_values_are_refused() {
        let c: SceneConfig = toml::from_str(
            r#"
            stale_after_s = 2.0
            stale_policy = "drop"
            [cells.arm]
            stale_policy = "stop"
            [cells.off]
            stale_after_s = 0.0
            "#,
        )
        .unwrap();
        assert_eq!(c.for_cell("other"), Staleness { after_s: 2.0, policy: StalePolicy::Drop });
        assert_eq!(c.for_cell("arm"), Staleness { after_s: 2.0, policy: StalePolicy::Stop });
        assert!(c.for_cell("off").is_off());
        assert!(SceneConfig::default().for_cell("x").is_off());
        c.check().unwrap();
        let bad = SceneConfig { stale_after_s: -1.0, ..Default::default() };
        assert!(bad.check().unwrap_err().to_string().contains("scene.stale_after_s"));
        let mut bad = SceneConfig::default();
        bad.cells.insert("a".into(), CellSceneConfig { stale_after_s: Some(f64::NAN), stale_policy: None });
        assert!(bad.check().unwrap_err().to_string().contains("scene.cells.a.stale_after_s"));
        assert!(toml::from_str::<SceneConfig>("stale_policy = \"explode\"").is_err());
    }
}
