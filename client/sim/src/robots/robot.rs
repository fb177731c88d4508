//! A simulated robot's controller: it keeps the setpoints in force (later segments supersede earlier ones from
//! their start time on, [`Setpoints`]), executes them at its control rate on its clock, and checks what it executed.
//!
//! # The clock
//! - Simulated: the robot's time is the start time of the segment it just read (it reads a segment when it needs
//!   one), so every row before it is executed and nothing is ever late.
//! - Real time: the robot's time is the wall clock minus the run's origin (`start_unix_s - start_time` of the first
//!   segment). A row whose time had already passed when its segment arrived is **late**: the robot executed what
//!   was in force before (or nothing).
//!
//! # Continuity
//! Between two executed rows `k` and `k + 1` (times `dt` apart), per coordinate, with `a` the largest acceleration
//! magnitude of rows `k - 1 ..= k + 2` and `Δa = |a_{k+1} - a_k|` (what the jerk changes in a step):
//! `|x_{k+1} - x_k - v_k dt| <= (CONT_FACTOR a + Δa) dt^2 + CONT_ABS` and
//! `|v_{k+1} - v_k| <= (CONT_FACTOR a + Δa) dt + CONT_ABS`. A jump of a superseding segment that does not continue
//! from the current state breaks one of the two; a motion whose acceleration crosses zero at a high jerk (a
//! jerk-limited one) does not, while the jerk itself is checked against the robot's profile.

use std::sync::atomic::{AtomicU64, Ordering};

use dmp::Trajectory;
use dmp::execution::OrientationPoints;
use dmp_client::setpoints::Setpoints;
use dmp_proto::v1;

use crate::error::SimError;

/// Slack factor of the continuity bounds (the acceleration varies within a step).
pub(crate) const CONT_FACTOR: f64 = 1.5;
/// Absolute slack of the continuity bounds (rounding).
pub(crate) const CONT_ABS: f64 = 1e-9;

/// Segments read by every simulated robot of this process so far: what `dmpctl sim` shows as its progress.
static SEGMENTS_READ: AtomicU64 = AtomicU64::new(0);

/// Segments read by every simulated robot of this process so far.
pub fn segments_read() -> u64 {
    SEGMENTS_READ.load(Ordering::Relaxed)
}

/// What one robot executed.
#[derive(Debug, Clone)]
pub(crate) struct Executed {
    /// The robot's id.
    pub(crate) id: String,
    /// Executed rows, in time order.
    pub(crate) traj: Trajectory,
    /// A pose run's executed orientations, row for row with `traj` (none: a position run).
    pub(crate) orientations: Option<OrientationPoints>,
    /// Rows that arrived after their time.
    pub(crate) late_setpoints: u64,
    /// Rows of `traj` where the robot switched to a superseding segment that arrived late: the step into each
    /// joins what it executed to what it should have executed, and is a consequence of the lateness (counted in
    /// `late_setpoints`), not of the stream.
    pub(crate) late_splices: Vec<usize>,
    /// Segments read.
    pub(crate) segments: u64,
    /// Status of the last segment.
    pub(crate) final_status: v1::SegmentStatus,
}

/// The controller of one robot.
#[derive(Debug)]
pub(crate) struct Controller {
    id: String,
    realtime: bool,
    setpoints: Setpoints,
    executed: Option<Trajectory>,
    executed_orientations: Option<OrientationPoints>,
    /// Rows of `setpoints` already executed, all with times before `clock`.
    committed: usize,
    clock: f64,
    origin_unix: Option<f64>,
    late: u64,
    late_splices: Vec<usize>,
    segments: u64,
    status: v1::SegmentStatus,
}

fn unix_now() -> f64 {
    std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0.0, |d| d.as_secs_f64())
}

impl Controller {
    /// A robot that has read nothing yet.
    pub(crate) fn new(id: impl Into<String>, realtime: bool) -> Self {
        Self {
            id: id.into(),
            realtime,
            setpoints: Setpoints::new(),
            executed: None,
            executed_orientations: None,
            committed: 0,
            clock: f64::NEG_INFINITY,
            origin_unix: None,
            late: 0,
            late_splices: Vec::new(),
            segments: 0,
            status: v1::SegmentStatus::Unspecified,
        }
    }

    /// The run's origin on the wall clock, once a real-time segment was read.
    pub(crate) fn origin_unix(&self) -> Option<f64> {
        self.origin_unix
    }

    /// Executes every row in force before `t`.
    fn advance(&mut self, t: f64) {
        let Some(traj) = self.setpoints.trajectory() else { return };
        let d = traj.dim();
        let exec = self.executed.get_or_insert_with(|| Trajectory::with_capacity(d, 1024));
        let pose = self.setpoints.orientations();
        while self.committed < traj.len() && traj.t[self.committed] < t {
            let k = self.committed;
            let r = k * d..(k + 1) * d;
            exec.push(traj.t[k], &traj.x[r.clone()], &traj.xd[r.clone()], &traj.xdd[r]);
            if let Some(o) = pose {
                let e = self.executed_orientations.get_or_insert_with(OrientationPoints::default);
                e.q.extend_from_slice(&o.q[4 * k..4 * k + 4]);
                e.omega.extend_from_slice(&o.omega[3 * k..3 * k + 3]);
                e.omega_dot.extend_from_slice(&o.omega_dot[3 * k..3 * k + 3]);
            }
            self.committed += 1;
        }
        self.clock = self.clock.max(t);
    }

    /// Reads one segment (arriving now).
    pub(crate) fn push(&mut self, seg: &v1::Segment) -> Result<(), SimError> {
        self.segments += 1;
        SEGMENTS_READ.fetch_add(1, Ordering::Relaxed);
        self.status = v1::SegmentStatus::try_from(seg.status).unwrap_or(v1::SegmentStatus::Unspecified);
        let now = if self.realtime && seg.start_unix_s > 0.0 {
            let origin = *self.origin_unix.get_or_insert(seg.start_unix_s - seg.start_time);
            unix_now() - origin
        } else {
            seg.start_time
        };
        self.advance(now);
        let d = (seg.dim as usize).max(1);
        let rows = seg.positions.len() / d;
        // Rows of this segment before the robot's time are late; the robot keeps what it executed.
        let late = (0..rows).filter(|&k| seg.start_time + k as f64 * seg.dt < self.clock).count();
        self.late += late as u64;
        let before = self.setpoints.trajectory().map_or(0, Trajectory::len);
        self.setpoints.push(seg)?;
        let after = self.setpoints.trajectory().map_or(0, Trajectory::len);
        // Rows cut by supersession that were executed stay executed: never re-execute before the clock.
        let kept = after.saturating_sub(rows).min(before);
        if self.committed > kept {
            let traj = self.setpoints.trajectory().map(|t| t.t.clone()).unwrap_or_default();
            self.committed = traj.partition_point(|&t| t < self.clock);
            if late > 0 {
                self.late_splices.push(self.executed.as_ref().map_or(0, Trajectory::len));
            }
        }
        Ok(())
    }

    /// The run ended: executes what is left.
    pub(crate) fn finish(mut self) -> Executed {
        self.advance(f64::INFINITY);
        let d = self.setpoints.trajectory().map_or(1, Trajectory::dim);
        Executed {
            id: self.id,
            traj: self.executed.unwrap_or_else(|| Trajectory::with_capacity(d, 0)),
            orientations: self.executed_orientations,
            late_setpoints: self.late,
            late_splices: self.late_splices,
            segments: self.segments,
            final_status: self.status,
        }
    }
}

/// Checks of an executed trajectory.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct Checks {
    /// Steps that break the continuity bounds (or the time step), but for the steps into a late splice.
    pub(crate) discontinuities: u64,
    /// Steps into a late splice ([`Executed::late_splices`]) that break the continuity bounds.
    pub(crate) late_steps: u64,
    /// Values that are NaN or infinite.
    pub(crate) non_finite: u64,
    /// Largest acceleration norm.
    pub(crate) peak_acceleration: f64,
    /// Largest speed.
    pub(crate) peak_speed: f64,
    /// Largest jerk norm, from the accelerations of consecutive rows (`|a_{k+1} - a_k| / (t_{k+1} - t_k)`).
    pub(crate) peak_jerk: f64,
    /// Time of the first discontinuous step, if any.
    pub(crate) first_discontinuity_s: Option<f64>,
}

fn row(v: &[f64], d: usize, k: usize) -> &[f64] {
    &v[k * d..(k + 1) * d]
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Whether `err` breaks `bound` (a NaN error does).
fn exceeds(err: f64, bound: f64) -> bool {
    !err.is_finite() || err > bound
}

/// Checks `traj` (executed at step `dt`); a step into one of the rows `late_splices` is counted apart.
pub(crate) fn check(traj: &Trajectory, dt: f64, late_splices: &[usize]) -> Checks {
    let d = traj.dim();
    let n = traj.len();
    let mut c = Checks::default();
    for v in [&traj.t, &traj.x, &traj.xd, &traj.xdd] {
        c.non_finite += v.iter().filter(|x| !x.is_finite()).count() as u64;
    }
    for k in 0..n {
        let a = norm(row(&traj.xdd, d, k));
        let v = norm(row(&traj.xd, d, k));
        if a.is_finite() {
            c.peak_acceleration = c.peak_acceleration.max(a);
        }
        if v.is_finite() {
            c.peak_speed = c.peak_speed.max(v);
        }
    }
    for k in 0..n.saturating_sub(1) {
        let h = traj.t[k + 1] - traj.t[k];
        let da2: f64 =
            row(&traj.xdd, d, k + 1).iter().zip(row(&traj.xdd, d, k)).map(|(a, b)| (a - b).powi(2)).sum();
        let j = da2.sqrt() / h;
        let spliced = late_splices.contains(&(k + 1));
        if j.is_finite() && !spliced {
            c.peak_jerk = c.peak_jerk.max(j);
        }
        let mut bad = (h - dt).abs() > 1e-6 * dt;
        let lo = k.saturating_sub(1);
        let hi = (k + 2).min(n - 1);
        for i in 0..d {
            let amax = (lo..=hi).map(|j| traj.xdd[j * d + i].abs()).fold(0.0, f64::max);
            let (x0, x1) = (traj.x[k * d + i], traj.x[(k + 1) * d + i]);
            let (v0, v1) = (traj.xd[k * d + i], traj.xd[(k + 1) * d + i]);
            let da = (traj.xdd[(k + 1) * d + i] - traj.xdd[k * d + i]).abs();
            let slack = CONT_FACTOR * amax + da;
            bad |= exceeds((x1 - x0 - v0 * h).abs(), slack * h * h + CONT_ABS);
            bad |= exceeds((v1 - v0).abs(), slack * h + CONT_ABS);
        }
        if spliced {
            c.late_steps += bad as u64;
            continue;
        }
        if bad && c.first_discontinuity_s.is_none() {
            c.first_discontinuity_s = Some(traj.t[k]);
        }
        c.discontinuities += bad as u64;
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seg(seq: u64, start: f64, x: &[f64], v: f64) -> v1::Segment {
        v1::Segment {
            sequence: seq,
            start_time: start,
            dt: 0.01,
            dim: 1,
            positions: x.to_vec(),
            velocities: vec![v; x.len()],
            accelerations: vec![0.0; x.len()],
            status: v1::SegmentStatus::Running as i32,
            ..Default::default()
        }
    }

    #[test]
    fn supersession_and_continuity() {
        let mut c = Controller::new("r", false);
        c.push(&seg(0, 0.0, &[0.0, 0.01, 0.02], 1.0)).unwrap();
        // Supersedes the last row of the first segment with a continuous continuation.
        c.push(&seg(1, 0.02, &[0.02, 0.03], 1.0)).unwrap();
        let e = c.finish();
        assert_eq!(e.traj.len(), 4);
        assert_eq!(e.late_setpoints, 0);
        assert_eq!(check(&e.traj, 0.01, &e.late_splices).discontinuities, 0);

        let mut c = Controller::new("r", false);
        c.push(&seg(0, 0.0, &[0.0, 0.01, 0.02], 1.0)).unwrap();
        c.push(&seg(1, 0.02, &[0.5, 0.51], 1.0)).unwrap();
        let e = c.finish();
        assert_eq!(check(&e.traj, 0.01, &e.late_splices).discontinuities, 1);
    }

    #[test]
    fn a_superseding_segment_that_arrives_late_is_a_late_splice_not_a_discontinuity() {
        let line = |from: f64, n: usize| (0..n).map(|k| from + 0.01 * k as f64).collect::<Vec<_>>();
        let mut c = Controller::new("r", false);
        c.push(&seg(0, 0.0, &line(0.0, 11), 1.0)).unwrap();
        // The robot's clock is now 0.1: rows 0.0 to 0.09 are executed.
        c.push(&seg(1, 0.1, &line(0.1, 5), 1.0)).unwrap();
        // A change from 0.05 on, elsewhere: its rows 0.05 to 0.09 are late, and the robot jumps to its row at 0.1.
        c.push(&seg(2, 0.05, &line(0.5, 10), 1.0)).unwrap();
        let e = c.finish();
        assert_eq!(e.late_setpoints, 5);
        assert_eq!(e.late_splices, vec![10]);
        assert_eq!(e.traj.t[10], 0.1);
        let checks = check(&e.traj, 0.01, &e.late_splices);
        assert_eq!((checks.discontinuities, checks.late_steps), (0, 1));
        // Without knowing the splice, the same step is a discontinuity.
        assert_eq!(check(&e.traj, 0.01, &[]).discontinuities, 1);
    }

    #[test]
    fn peaks_of_speed_acceleration_and_jerk() {
        // 2-D, 1 ms apart: the acceleration steps from (0, 0) to (3, 4) between the second and third rows.
        let mut t = Trajectory::with_capacity(2, 4);
        for (k, a) in [[0.0, 0.0], [0.0, 0.0], [3.0, 4.0], [3.0, 4.0]].iter().enumerate() {
            let s = k as f64 * 1e-3;
            t.push(s, &[0.0, 0.0], &[0.5 * s, 0.0], a);
        }
        let c = check(&t, 1e-3, &[]);
        assert_eq!(c.peak_acceleration, 5.0);
        assert!((c.peak_jerk - 5000.0).abs() < 1e-6, "{}", c.peak_jerk);
        assert!((c.peak_speed - 1.5e-3).abs() < 1e-15);
    }
}
