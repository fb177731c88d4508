//! The current setpoints of a stream of segments.
//!
//! The schema's rule (`motion.proto`, `Segment`): segment `k + 1` supersedes the points of earlier segments from its
//! `start_time` on, so the current setpoint at time `t` is the one of the latest segment whose `start_time <= t`.
//! [`Setpoints`] applies the rule as segments arrive: each one cuts the rows at and after its start time, then
//! appends its own points. A segment without points (a final status) supersedes nothing.
//!
//! A pose run's segments also carry orientations (4 per point), angular velocities and accelerations (3 each): they
//! are kept row for row with the positions ([`Setpoints::orientations`]).

use dmp::Trajectory;
use dmp::execution::OrientationPoints;
use dmp_proto::v1;

use crate::error::ClientError;

/// Two times closer than this fraction of `dt` are the same row (times are computed as `start + k dt`).
const SAME_TIME: f64 = 1e-6;

/// The setpoints in force after the segments received so far.
#[derive(Debug, Clone, Default)]
pub struct Setpoints {
    traj: Option<Trajectory>,
    /// A pose run's orientations, row for row with `traj` (none: a position run).
    orientations: Option<OrientationPoints>,
    segments: usize,
    last_status: Option<v1::SegmentStatus>,
}

impl Setpoints {
    /// No segment yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Applies one segment. Fails when it is inconsistent (a value count that is not `points x dim`, a dimension
    /// other than the earlier segments', a bad `dt`), leaving the setpoints unchanged.
    pub fn push(&mut self, seg: &v1::Segment) -> Result<(), ClientError> {
        let d = seg.dim as usize;
        let bad = |m: String| ClientError::Protocol(format!("segment {}: {m}", seg.sequence));
        if d == 0 {
            if seg.positions.is_empty() && seg.velocities.is_empty() && seg.accelerations.is_empty() {
                self.note(seg);
                return Ok(());
            }
            return Err(bad("dim is 0 but it has points".into()));
        }
        let rows = seg.positions.len() / d;
        for (name, v) in [
            ("positions", &seg.positions),
            ("velocities", &seg.velocities),
            ("accelerations", &seg.accelerations),
        ] {
            if v.len() != rows * d || !seg.positions.len().is_multiple_of(d) {
                return Err(bad(format!(
                    "{name} has {} values, expected points x dim = {} x {d}",
                    v.len(),
                    rows
                )));
            }
        }
        if let Some(t) = &self.traj
            && t.dim() != d
        {
            return Err(bad(format!("dim is {d}, earlier segments had {}", t.dim())));
        }
        if rows == 0 {
            self.note(seg);
            return Ok(());
        }
        let pose = !seg.orientations.is_empty();
        if pose {
            for (name, v, n) in [
                ("orientations", &seg.orientations, 4),
                ("angular_velocities", &seg.angular_velocities, 3),
                ("angular_accelerations", &seg.angular_accelerations, 3),
            ] {
                if v.len() != rows * n {
                    return Err(bad(format!(
                        "{name} has {} values, expected points x {n} = {}",
                        v.len(),
                        rows * n
                    )));
                }
            }
        }
        if self.traj.as_ref().is_some_and(|t| !t.is_empty()) && pose != self.orientations.is_some() {
            return Err(bad("a pose run's segments all carry orientations, a position run's none".into()));
        }
        if !(seg.dt.is_finite() && seg.dt > 0.0 && seg.start_time.is_finite()) {
            return Err(bad(format!(
                "start_time {} and dt {} must be finite, dt > 0",
                seg.start_time, seg.dt
            )));
        }
        let traj = self.traj.get_or_insert_with(|| Trajectory::with_capacity(d, rows));
        let cut = seg.start_time - SAME_TIME * seg.dt;
        let keep = traj.t.partition_point(|&t| t < cut);
        traj.t.truncate(keep);
        traj.x.truncate(keep * d);
        traj.xd.truncate(keep * d);
        traj.xdd.truncate(keep * d);
        if pose {
            let o = self.orientations.get_or_insert_with(OrientationPoints::default);
            o.q.truncate(keep * 4);
            o.omega.truncate(keep * 3);
            o.omega_dot.truncate(keep * 3);
            o.q.extend_from_slice(&seg.orientations);
            o.omega.extend_from_slice(&seg.angular_velocities);
            o.omega_dot.extend_from_slice(&seg.angular_accelerations);
        }
        for k in 0..rows {
            let r = k * d..(k + 1) * d;
            traj.push(
                seg.start_time + k as f64 * seg.dt,
                &seg.positions[r.clone()],
                &seg.velocities[r.clone()],
                &seg.accelerations[r],
            );
        }
        self.note(seg);
        Ok(())
    }

    fn note(&mut self, seg: &v1::Segment) {
        self.segments += 1;
        self.last_status = Some(seg.status());
    }

    /// Segments applied.
    pub fn segments(&self) -> usize {
        self.segments
    }

    /// Status of the last segment applied.
    pub fn last_status(&self) -> Option<v1::SegmentStatus> {
        self.last_status
    }

    /// The current setpoints, one row per point in force (none before the first segment with points).
    pub fn trajectory(&self) -> Option<&Trajectory> {
        self.traj.as_ref()
    }

    /// A pose run's current orientations, row for row with [`Setpoints::trajectory`] (none: a position run).
    pub fn orientations(&self) -> Option<&OrientationPoints> {
        self.orientations.as_ref()
    }

    /// The current setpoints; a stream without points gives an empty trajectory of dimension 0.
    pub fn into_trajectory(self) -> Trajectory {
        self.traj.unwrap_or_else(|| Trajectory::with_capacity(0, 0))
    }
}

/// The setpoints in force after `segments`, in order.
pub fn segments_to_trajectory<'a>(
    segments: impl IntoIterator<Item = &'a v1::Segment>,
) -> Result<Trajectory, ClientError> {
    let mut s = Setpoints::new();
    for seg in segments {
        s.push(seg)?;
    }
    Ok(s.into_trajectory())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2-D segment of `n` points from `t0`, position `(base + k, -(base + k))`.
    fn seg(sequence: u64, t0: f64, n: usize, base: f64) -> v1::Segment {
        let mut s = v1::Segment { sequence, start_time: t0, dt: 0.1, dim: 2, ..Default::default() };
        for k in 0..n {
            let v = base + k as f64;
            s.positions.extend([v, -v]);
            s.velocities.extend([1.0, -1.0]);
            s.accelerations.extend([0.0, 0.0]);
        }
        s.status = v1::SegmentStatus::Running as i32;
        s
    }

    #[test]
    fn consecutive_segments_concatenate() {
        let t = segments_to_trajectory(&[seg(0, 0.0, 3, 0.0), seg(1, 0.3, 3, 3.0)]).unwrap();
        assert_eq!(t.len(), 6);
        assert_eq!(t.dim(), 2);
        for k in 0..6 {
            assert!((t.t[k] - 0.1 * k as f64).abs() < 1e-12);
            assert_eq!(t.position(k), &[k as f64, -(k as f64)]);
        }
    }

    #[test]
    fn a_later_segment_supersedes_from_its_start_time() {
        // Segment 0 covers 0.0..=0.9; segment 1 (computed after a scene change) starts at 0.4: rows 0.4.. of
        // segment 0 are replaced, the first four stay.
        let t = segments_to_trajectory(&[seg(0, 0.0, 10, 0.0), seg(1, 0.4, 3, 100.0)]).unwrap();
        assert_eq!(t.len(), 7);
        assert_eq!(t.position(3), &[3.0, -3.0]);
        assert_eq!(t.position(4), &[100.0, -100.0]);
        assert!((t.t[4] - 0.4).abs() < 1e-12);
        assert_eq!(t.position(6), &[102.0, -102.0]);
        // A time that differs from a row's by rounding (0.1 * 3 != 0.3) still supersedes that row.
        let t = segments_to_trajectory(&[seg(0, 0.0, 5, 0.0), seg(1, 0.1 * 3.0 - 1e-12, 2, 50.0)]).unwrap();
        assert_eq!(t.len(), 5);
        assert_eq!(t.position(3), &[50.0, -50.0]);
        // A segment starting before everything replaces everything.
        let t = segments_to_trajectory(&[seg(0, 0.5, 5, 0.0), seg(1, 0.0, 2, 9.0)]).unwrap();
        assert_eq!(t.len(), 2);
        assert_eq!(t.position(0), &[9.0, -9.0]);
    }

    #[test]
    fn empty_segments_carry_a_status_and_supersede_nothing() {
        let mut s = Setpoints::new();
        s.push(&seg(0, 0.0, 4, 0.0)).unwrap();
        let mut end = v1::Segment { sequence: 1, start_time: 0.2, dt: 0.1, dim: 2, ..Default::default() };
        end.status = v1::SegmentStatus::GoalReached as i32;
        s.push(&end).unwrap();
        assert_eq!(s.trajectory().unwrap().len(), 4);
        assert_eq!(s.segments(), 2);
        assert_eq!(s.last_status(), Some(v1::SegmentStatus::GoalReached));
    }

    #[test]
    fn inconsistent_segments_are_refused() {
        let mut s = Setpoints::new();
        s.push(&seg(0, 0.0, 4, 0.0)).unwrap();
        let mut bad = seg(1, 0.4, 2, 0.0);
        bad.velocities.pop();
        assert!(s.push(&bad).unwrap_err().to_string().contains("velocities"));
        let mut bad = seg(1, 0.4, 2, 0.0);
        bad.dim = 4;
        assert!(s.push(&bad).unwrap_err().to_string().contains("dim"));
        let mut bad = seg(1, 0.4, 2, 0.0);
        bad.dt = 0.0;
        assert!(s.push(&bad).is_err());
        assert_eq!(s.trajectory().unwrap().len(), 4, "a refused segment changes nothing");
    }

    /// [`seg`] of a pose run: orientation `(0, 0, sin(v/2), cos(v/2))`, angular velocity and acceleration `v`.
    fn pose_seg(sequence: u64, t0: f64, n: usize, base: f64) -> v1::Segment {
        let mut s = seg(sequence, t0, n, base);
        for k in 0..n {
            let v = base + k as f64;
            s.orientations.extend([0.0, 0.0, (v / 2.0).sin(), (v / 2.0).cos()]);
            s.angular_velocities.extend([v; 3]);
            s.angular_accelerations.extend([v; 3]);
        }
        s
    }

    #[test]
    fn a_pose_runs_orientations_are_superseded_with_its_positions() {
        let mut s = Setpoints::new();
        s.push(&pose_seg(0, 0.0, 10, 0.0)).unwrap();
        s.push(&pose_seg(1, 0.4, 3, 100.0)).unwrap();
        let o = s.orientations().unwrap();
        assert_eq!((o.q.len(), o.omega.len(), o.omega_dot.len()), (28, 21, 21));
        assert_eq!(o.omega[3 * 3], 3.0);
        assert_eq!(o.omega[3 * 4], 100.0);
        assert!((o.q[4 * 4 + 2] - 50f64.sin()).abs() < 1e-15);
        // A position segment in a pose run, or orientations of the wrong length, are refused.
        assert!(s.push(&seg(2, 0.5, 2, 0.0)).unwrap_err().to_string().contains("orientations"));
        let mut bad = pose_seg(2, 0.5, 2, 0.0);
        bad.angular_velocities.pop();
        assert!(s.push(&bad).unwrap_err().to_string().contains("angular_velocities"));
        // A position run has none.
        let t = segments_to_trajectory(&[seg(0, 0.0, 3, 0.0)]).unwrap();
        assert_eq!(t.len(), 3);
        let mut p = Setpoints::new();
        p.push(&seg(0, 0.0, 3, 0.0)).unwrap();
        assert!(p.orientations().is_none());
    }
}
