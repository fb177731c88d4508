//! The `[scene]` section of the configuration: when an obstacle nobody updates goes stale, and what its cell does
//! then (`stale_after_s`, `stale_policy`, per cell in `[scene.cells.<name>]`). What a stale obstacle does to the
//! robots is [`crate::cells::staleness`]'s.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::error::ServerError;

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
    pub(crate) fn is_off(&self) -> bool {
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
    pub(crate) fn for_cell(&self, cell: &str) -> Staleness {
        let over = self.cells.get(cell);
        Staleness {
            after_s: over.and_then(|c| c.stale_after_s).unwrap_or(self.stale_after_s),
            policy: over.and_then(|c| c.stale_policy).unwrap_or(self.stale_policy),
        }
    }

    /// Every `stale_after_s` is finite and not negative.
    pub(crate) fn check(&self) -> Result<(), ServerError> {
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
