//! What a plan or a stream reported beside its setpoints, for its `--out` data and figure: the scene versions it
//! went through (events), the limits in force (`LimitsInForce`, on the plan or the stream's first segment) and
//! each segment's smallest clearance. Written as `limits.json` and `clearance.csv`; a server that sends neither
//! leaves them out, and the figure is drawn without limit lines.

use std::fmt::Write as _;
use std::path::Path;

use dmp_plot::{Event, Safety};
use dmp_proto::v1;

use crate::error::DmpctlError;
use crate::outputs::{to_json, write_file};

/// What a run reported beside its setpoints.
#[derive(Debug, Default)]
pub(crate) struct RunRecord {
    last_version: Option<u64>,
    /// A change of scene version after the first segment, each.
    pub(crate) events: Vec<Event>,
    /// The limits in force, as the server sent them (the first that came).
    pub(crate) limits: Option<v1::LimitsInForce>,
    /// Per segment with obstacles: `(sequence, start time, end time, smallest clearance in metres)`.
    pub(crate) clearance: Vec<(u64, f64, f64, f64)>,
}

impl RunRecord {
    /// The record of a plan: its one segment and its limits.
    pub(crate) fn plan(seg: &v1::Segment, limits: Option<&v1::LimitsInForce>) -> Self {
        let mut r = Self::default();
        r.see(seg);
        if r.limits.is_none() {
            r.limits = limits.cloned();
        }
        r
    }

    /// Notes a segment: its scene version, its limits (the first segment's), its smallest clearance.
    pub(crate) fn see(&mut self, seg: &v1::Segment) {
        if self.last_version.is_some_and(|v| v != seg.scene_version) {
            self.events.push(Event::new(seg.start_time, format!("scene version {}", seg.scene_version)));
        }
        self.last_version = Some(seg.scene_version);
        if self.limits.is_none() {
            self.limits = seg.limits.clone();
        }
        if let Some(c) = seg.min_clearance {
            let points = if seg.dim == 0 { 0 } else { seg.positions.len() / seg.dim as usize };
            let end = seg.start_time + seg.dt * points.saturating_sub(1) as f64;
            self.clearance.push((seg.sequence, seg.start_time, end, c));
        }
    }

    /// What the figure draws of it: the limits and the safety distance in force, and each of `scene`'s obstacles'
    /// own safety distance. Without limits in force, only the obstacles' own.
    pub(crate) fn safety(&self, scene: &[&v1::Obstacle]) -> Safety {
        let obstacle_margins = scene.iter().map(|o| (o.id.clone(), o.margin)).collect();
        let Some(l) = &self.limits else { return Safety { obstacle_margins, ..Safety::default() } };
        let b = l.limits.unwrap_or_default();
        Safety {
            max_speed: b.max_speed,
            max_acceleration: b.max_acceleration,
            max_jerk: b.max_jerk,
            max_angular_speed: b.max_angular_speed,
            max_angular_acceleration: b.max_angular_acceleration,
            max_angular_jerk: b.max_angular_jerk,
            profile: l.profile.clone(),
            margin: l.margin,
            obstacle_margins,
        }
    }

    /// Writes `out/limits.json` (the limits in force) and `out/clearance.csv` (`sequence,t_start,t_end,
    /// min_clearance`, a row per segment with obstacles), each only if the server sent it.
    pub(crate) fn write(&self, out: &Path) -> Result<(), DmpctlError> {
        if let Some(l) = &self.limits {
            let b = l.limits.unwrap_or_default();
            let json = serde_json::json!({
                "limits": {
                    "max_speed": b.max_speed,
                    "max_acceleration": b.max_acceleration,
                    "max_jerk": b.max_jerk,
                    "max_angular_speed": b.max_angular_speed,
                    "max_angular_acceleration": b.max_angular_acceleration,
                    "max_angular_jerk": b.max_angular_jerk,
                },
                "profile": l.profile,
                "unlimited": l.unlimited,
                "margin": l.margin,
            });
            write_file(out, "limits.json", to_json(&json).as_bytes())?;
        }
        if !self.clearance.is_empty() {
            let mut csv = String::from("sequence,t_start,t_end,min_clearance\n");
            for (seq, t0, t1, c) in &self.clearance {
                let _ = writeln!(csv, "{seq},{t0},{t1},{c}");
            }
            write_file(out, "clearance.csv", csv.as_bytes())?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn segment(sequence: u64, limits: Option<v1::LimitsInForce>, clearance: Option<f64>) -> v1::Segment {
        v1::Segment {
            sequence,
            start_time: sequence as f64 * 2.5,
            dt: 0.25,
            dim: 2,
            positions: vec![0.0; 20],
            min_clearance: clearance,
            limits,
            ..v1::Segment::default()
        }
    }

    #[test]
    fn a_streams_limits_and_clearances_are_written_and_drawn_and_older_data_has_none() {
        let limits = v1::LimitsInForce {
            limits: Some(v1::Limits { max_speed: 1.7, max_jerk: 6500.0, ..v1::Limits::default() }),
            profile: "server default".into(),
            unlimited: vec!["max_acceleration".into()],
            margin: 0.02,
        };
        let mut r = RunRecord::default();
        r.see(&segment(0, Some(limits), Some(0.3)));
        r.see(&segment(1, None, Some(0.25)));
        let peg = v1::Obstacle { id: "peg".into(), margin: 0.05, ..v1::Obstacle::default() };
        let s = r.safety(&[&peg]);
        assert_eq!((s.max_speed, s.max_acceleration, s.max_jerk, s.margin), (1.7, 0.0, 6500.0, 0.02));
        assert_eq!(s.profile, "server default");
        assert_eq!(s.obstacle_margins, [("peg".to_string(), 0.05)]);
        let dir = tempfile::tempdir().unwrap();
        r.write(dir.path()).unwrap();
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.path().join("limits.json")).unwrap()).unwrap();
        assert_eq!(json["limits"]["max_jerk"], 6500.0);
        assert_eq!(json["profile"], "server default");
        assert_eq!(json["unlimited"][0], "max_acceleration");
        let csv = std::fs::read_to_string(dir.path().join("clearance.csv")).unwrap();
        assert_eq!(
            csv.lines().collect::<Vec<_>>(),
            ["sequence,t_start,t_end,min_clearance", "0,0,2.25,0.3", "1,2.5,4.75,0.25"]
        );
        // An older server: no limits, no clearance; nothing written, nothing drawn.
        let mut old = RunRecord::default();
        old.see(&segment(0, None, None));
        let old_dir = tempfile::tempdir().unwrap();
        old.write(old_dir.path()).unwrap();
        assert!(std::fs::read_dir(old_dir.path()).unwrap().next().is_none());
        assert_eq!(old.safety(&[]), Safety::default());
    }
}
