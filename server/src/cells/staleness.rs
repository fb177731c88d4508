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
//! The cell marks and drops obstacles ([`crate::cells::cell::Cell::expire`], run by the reaper every
//! `zenoh_bridge::REAP_PERIOD`); a stream reads the flags from the snapshot it already watches ([`StaleGuard`]).
//! A run that ignores the scene is not affected. `stale_after_s = 0` (the default) turns it off: obstacles without
//! a `ttl_s` then live until deleted, and a moving one drifts along its velocity until then.

use dmp_proto::v1;

use crate::cells::cell::ObstacleSet;
use crate::config::scene::{StalePolicy, Staleness};

/// A stream's view of its cell's staleness: it flags the segments, warns once when the scene goes stale, and
/// under `stop` holds the robots (a session's Pause and Resume still decide once the scene is fresh again).
#[derive(Debug, Clone)]
pub(crate) struct StaleGuard {
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
    pub(crate) fn new(staleness: Staleness, ignore_scene: bool) -> Self {
        Self { policy: staleness.policy, ignored: ignore_scene, stale: Vec::new(), paused: false }
    }

    /// The segments computed now are computed with stale obstacles.
    pub(crate) fn is_stale(&self) -> bool {
        !self.stale.is_empty()
    }

    /// Reads the stale obstacles of a new snapshot; pushes a `SCENE_STALE` warning into `warnings` when the scene
    /// goes from fresh to stale.
    pub(crate) fn observe(&mut self, snapshot: &ObstacleSet, warnings: &mut Vec<v1::Warning>) {
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

    /// Notes the session's own Pause (`true`) or Resume (`false`).
    pub(crate) fn note_paused(&mut self, paused: bool) {
        self.paused = paused;
    }

    /// Whether the run must hold: under `stop`, while the scene is stale (or the session paused it); `None` under
    /// the other policies and for runs that ignore the scene.
    pub(crate) fn hold(&self) -> Option<bool> {
        (self.policy == StalePolicy::Stop && !self.ignored).then_some(self.paused || self.is_stale())
    }
}
