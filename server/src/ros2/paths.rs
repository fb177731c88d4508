//! Each executing robot's planned path as it was sent: the positions of its segments, per cell, for the markers. A
//! segment that supersedes points already sent replaces them (from its first point's run time on). The trajectory
//! publisher writes it, the markers' task reads it; the lock is a std `Mutex`, held only to copy or append, never
//! across an await.

use std::collections::{BTreeMap, HashMap};
use std::sync::{Arc, Mutex};

use dmp_proto::v1;

/// The most points kept per robot: the oldest go first (a long run's path stays bounded in memory and in the
/// markers' size).
pub(crate) const MAX_PATH_POINTS: usize = 4096;

/// One robot's path: run times and positions (3-D, `z = 0` for 2-D robots).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Path {
    /// The run time of each point.
    pub times: Vec<f64>,
    /// The positions.
    pub points: Vec<[f64; 3]>,
}

impl Path {
    /// Adds `segment`'s positions, replacing the points at or after its first point's run time.
    fn extend(&mut self, segment: &v1::Segment) {
        let d = (segment.dim as usize).max(1);
        let keep = self.times.partition_point(|t| *t < segment.start_time - 0.5 * segment.dt);
        self.times.truncate(keep);
        self.points.truncate(keep);
        for (k, row) in segment.positions.chunks_exact(d).enumerate() {
            self.times.push(segment.start_time + k as f64 * segment.dt);
            self.points.push([0, 1, 2].map(|i| if i < d.min(3) { row[i] } else { 0.0 }));
        }
        let over = self.points.len().saturating_sub(MAX_PATH_POINTS);
        self.times.drain(..over);
        self.points.drain(..over);
    }
}

/// The paths of one cell and their version (bumped at every change).
#[derive(Debug, Clone, Default)]
pub(crate) struct CellPaths {
    /// Per robot.
    pub robots: BTreeMap<String, Path>,
    /// Changes at every change.
    pub version: u64,
}

/// Every cell's paths. Cheap to clone.
#[derive(Debug, Clone, Default)]
pub(crate) struct Paths(Arc<Mutex<HashMap<String, CellPaths>>>);

impl Paths {
    /// Adds the segments sent to robots of `cell`.
    pub(crate) fn extend(&self, cell: &str, segments: &[v1::Segment]) {
        let mut all = self.0.lock().unwrap_or_else(|p| p.into_inner());
        let c = all.entry(cell.to_owned()).or_default();
        for s in segments {
            c.robots.entry(s.robot_id.clone()).or_default().extend(s);
        }
        c.version += 1;
    }

    /// Forgets the paths of `robots` of `cell` (their stream ended).
    pub(crate) fn remove(&self, cell: &str, robots: &[String]) {
        let mut all = self.0.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(c) = all.get_mut(cell) {
            for r in robots {
                c.robots.remove(r);
            }
            c.version += 1;
        }
    }

    /// A copy of `cell`'s paths, if its version is not `seen`.
    pub(crate) fn changed(&self, cell: &str, seen: Option<u64>) -> Option<CellPaths> {
        let all = self.0.lock().unwrap_or_else(|p| p.into_inner());
        let c = all.get(cell)?;
        (Some(c.version) != seen).then(|| c.clone())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn segment(start_time: f64, xs: &[f64]) -> v1::Segment {
        v1::Segment {
            robot_id: "r".into(),
            start_time,
            dt: 0.1,
            dim: 2,
            positions: xs.iter().flat_map(|x| [*x, 1.0]).collect(),
            ..Default::default()
        }
    }

    #[test]
    fn superseding_segments_replace_the_points_sent() {
        let p = Paths::default();
        p.extend("c", &[segment(0.0, &[0.0, 1.0, 2.0])]);
        p.extend("c", &[segment(0.3, &[3.0, 4.0])]);
        // Supersedes from t = 0.2 on.
        p.extend("c", &[segment(0.2, &[9.0])]);
        let c = p.changed("c", None).unwrap();
        let xs: Vec<f64> = c.robots["r"].points.iter().map(|q| q[0]).collect();
        assert_eq!(xs, vec![0.0, 1.0, 9.0]);
        assert_eq!(c.robots["r"].points[0], [0.0, 1.0, 0.0]);
        assert!(p.changed("c", Some(c.version)).is_none());
        p.remove("c", &["r".into()]);
        assert!(p.changed("c", Some(c.version)).unwrap().robots.is_empty());
    }

    #[test]
    fn a_path_is_bounded() {
        let p = Paths::default();
        for k in 0..(MAX_PATH_POINTS / 2 + 1) {
            p.extend("c", &[segment(0.2 * k as f64, &[k as f64, k as f64])]);
        }
        let c = p.changed("c", None).unwrap();
        assert_eq!(c.robots["r"].points.len(), MAX_PATH_POINTS);
        assert_eq!(c.robots["r"].points.last().unwrap()[0], (MAX_PATH_POINTS / 2) as f64);
    }
}
