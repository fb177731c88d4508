//! One robot of the load: its session (real-time pacing, a new goal every `tau` seconds, a stop at the end) and
//! the accounting of its setpoints.
//!
//! # Accounting
//! The setpoint of run time `t` is due at `start_unix_s + (t - start_time)` of its segment. It is **on time** when
//! the segment that carries it in the end (the latest one covering `t`: a later segment supersedes earlier points
//! from its start time on) arrived before it was due. A segment that arrives at `a` carries its points due before
//! `a` late: a prefix of the segment. So the [`Ledger`] keeps, per segment still open to supersession, a *run*:
//! its first point's index, its length and its late prefix, in a ring buffer allocated once. A new segment cuts the
//! runs it supersedes and is appended; runs whose points were all due more than [`FINALIZE_AFTER_S`] before the
//! latest arrival can no longer be superseded and are counted. Every operation is O(1) amortised and allocation-free.
//!
//! Expected setpoints: those due from the run's first point (its origin, `start_unix_s` of segment 0) to the end of
//! the measurement, `rate` per second. A setpoint that never arrived is not on time. Segments count (for
//! lateness, late segments, supersession) when their first point is due before the end.

use std::collections::VecDeque;
use std::sync::Arc;
use std::time::Duration;

use dmp_client::grpc::DmpClient;
use dmp_proto::v1;
use tokio::time::{Instant, MissedTickBehavior};
use tokio_stream::StreamExt;

use super::layout::RobotPlan;
use super::per_second::PerSecond;
use super::scene::CellProbe;
use super::stats::{Histogram, SignedHistogram};
use super::{unix_now, unix_now_ns};
use dmp_proto::segment_view::SegmentView;

/// Runs whose points were all due this long before the latest arrival are final.
pub(crate) const FINALIZE_AFTER_S: f64 = 1.0;
/// Longest wait for a session to open.
pub(crate) const OPEN_TIMEOUT: Duration = Duration::from_secs(10);
/// A stream with no segment for this long has failed (real time sends one every segment).
pub(crate) const STALL_TIMEOUT: Duration = Duration::from_secs(5);
/// Longest wait for the stream to close after the stop.
pub(crate) const STOP_TIMEOUT: Duration = Duration::from_secs(5);

/// The points of one segment still in force.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Run {
    /// Index of the first point (run time / dt).
    first: i64,
    /// Points.
    len: i64,
    /// Leading points that arrived after they were due.
    late: i64,
}

impl Run {
    fn end(&self) -> i64 {
        self.first + self.len
    }
}

/// What one segment was.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SegmentFacts {
    /// Arrival minus the due time of its first point, nanoseconds (negative: early).
    pub(crate) lateness_ns: i64,
    /// It replaced points of earlier segments.
    pub(crate) superseding: bool,
    /// Its first point is due before the end of the measurement.
    pub(crate) in_window: bool,
}

/// The setpoint accounting of one robot.
#[derive(Debug)]
pub(crate) struct Ledger {
    runs: VecDeque<Run>,
    /// Wall time of run time 0, Unix seconds (from the first segment).
    origin_unix: Option<f64>,
    dt: f64,
    /// End of the measurement, Unix seconds.
    end_unix: f64,
    /// Points before this index are counted.
    frontier: i64,
    on_time: u64,
    /// A pose robot's: every segment must carry its orientations.
    pose: bool,
}

impl Ledger {
    /// A ledger for a measurement that ends at `end_unix` (Unix seconds).
    pub(crate) fn new(end_unix: f64) -> Self {
        Self {
            runs: VecDeque::with_capacity(256),
            origin_unix: None,
            dt: 0.0,
            end_unix,
            frontier: 0,
            on_time: 0,
            pose: false,
        }
    }

    /// The same ledger for a pose robot (`pose`): a segment without the orientations, angular velocities and
    /// accelerations of its points ([`SegmentView::has_pose`]) cannot be placed, and ends the robot.
    pub(crate) fn with_pose(mut self, pose: bool) -> Self {
        self.pose = pose;
        self
    }

    /// Index of the last point due at or before the end.
    fn last_index(&self) -> i64 {
        match self.origin_unix {
            Some(o) if self.dt > 0.0 => ((self.end_unix - o) / self.dt + 1e-6).floor() as i64,
            _ => -1,
        }
    }

    fn count(&mut self, run: Run) {
        let hi = self.last_index().min(run.end() - 1);
        let lo = (run.first + run.late).max(0);
        self.on_time += (hi - lo + 1).max(0) as u64;
        self.frontier = self.frontier.max(run.end());
    }

    /// Accounts for `seg`, which arrived at `arrival_unix`. Fails on a segment that cannot be placed in time (not
    /// real-time paced, or without a valid step).
    pub(crate) fn push(&mut self, seg: &SegmentView, arrival_unix: f64) -> Result<SegmentFacts, String> {
        if !(seg.start_unix_s > 0.0 && seg.dt > 0.0 && seg.dt.is_finite()) {
            return Err(format!(
                "segment {} has start_unix_s {} and dt {}: not real-time paced",
                seg.sequence, seg.start_unix_s, seg.dt
            ));
        }
        if self.pose && !seg.has_pose() {
            return Err(format!(
                "segment {} of a pose robot lacks the orientations, angular velocities or accelerations of its {} \
                 points",
                seg.sequence,
                seg.points()
            ));
        }
        let origin = *self.origin_unix.get_or_insert(seg.start_unix_s - seg.start_time);
        self.dt = seg.dt;
        let len = seg.points() as i64;
        let mut first = (seg.start_time / seg.dt).round() as i64;
        let behind = arrival_unix - seg.start_unix_s;
        // Points k with start_unix_s + k dt < arrival are late.
        let mut late = if behind > 0.0 { ((behind / seg.dt).ceil() as i64).min(len) } else { 0 };
        let facts = SegmentFacts {
            lateness_ns: (behind * 1e9).round() as i64,
            superseding: self.runs.back().is_some_and(|r| r.end() > first),
            in_window: seg.start_unix_s <= self.end_unix,
        };
        // Points already counted stay as they were.
        let mut len_left = len;
        if first < self.frontier {
            let skip = (self.frontier - first).min(len);
            first += skip;
            len_left -= skip;
            late = (late - skip).max(0);
        }
        while let Some(back) = self.runs.back_mut() {
            if back.first >= first {
                self.runs.pop_back();
            } else {
                if back.end() > first {
                    back.len = first - back.first;
                    back.late = back.late.min(back.len);
                }
                break;
            }
        }
        if len_left > 0 {
            self.runs.push_back(Run { first, len: len_left, late });
        }
        let settled = ((arrival_unix - FINALIZE_AFTER_S - origin) / seg.dt + 1e-6).floor() as i64;
        while let Some(&front) = self.runs.front() {
            if front.end() > settled {
                break;
            }
            self.runs.pop_front();
            self.count(front);
        }
        Ok(facts)
    }

    /// Ends the accounting: `(expected, on_time)`. `scheduled_unix` is when the robot was to start, for a robot
    /// that never received a segment; `rate` its setpoints per second.
    pub(crate) fn finish(mut self, scheduled_unix: f64, rate: f64) -> (u64, u64) {
        while let Some(run) = self.runs.pop_front() {
            self.count(run);
        }
        let expected = match self.origin_unix {
            Some(_) => (self.last_index() + 1).max(0) as u64,
            None => ((self.end_unix - scheduled_unix) * rate + 1e-6).floor().max(0.0) as u64,
        };
        (expected, self.on_time.min(expected))
    }
}

/// The histograms every robot adds to.
#[derive(Debug)]
pub(crate) struct Shared {
    /// Arrival minus due time of each segment's first point.
    pub(crate) lateness: SignedHistogram,
    /// The same, of superseding segments only.
    pub(crate) superseding_lateness: SignedHistogram,
    /// Scene update to the first segment that accounts for it.
    pub(crate) scene_latency: Histogram,
    /// Late segments by the second of their arrival.
    pub(crate) late_per_second: PerSecond,
}

impl Shared {
    /// Histograms, and `seconds` seconds of late segments from `origin_unix_s`.
    pub(crate) fn new(origin_unix_s: f64, seconds: usize) -> Self {
        Self {
            lateness: SignedHistogram::new(),
            superseding_lateness: SignedHistogram::new(),
            scene_latency: Histogram::new(),
            late_per_second: PerSecond::new((origin_unix_s.max(0.0) * 1e9) as u64, seconds),
        }
    }
}

/// One robot's run.
#[derive(Debug, Clone)]
pub(crate) struct RobotTask {
    /// The robot.
    pub(crate) plan: RobotPlan,
    /// The session's start.
    pub(crate) start: v1::ExecuteRequest,
    /// When to open the session.
    pub(crate) start_at: Instant,
    /// When to stop.
    pub(crate) end_at: Instant,
    /// `start_at` and `end_at` on the wall clock, Unix seconds.
    pub(crate) start_unix: f64,
    /// End of the measurement, Unix seconds.
    pub(crate) end_unix: f64,
    /// Setpoints per second.
    pub(crate) rate: f64,
    /// A new goal this often.
    pub(crate) retarget_every: Duration,
    /// The lateness of its server's segments (with several servers, one per server; else `shared.lateness`'s
    /// twin).
    pub(crate) server_lateness: Arc<SignedHistogram>,
    /// A pose robot's orientations, in the order of its goals (`--pose`); None for a position robot.
    pub(crate) orientations: Option<[super::pose::Quaternion; 2]>,
}

/// What one robot saw.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct RobotOutcome {
    /// The robot.
    pub(crate) id: String,
    /// Setpoints due in the measurement.
    pub(crate) expected: u64,
    /// Of which on time.
    pub(crate) on_time: u64,
    /// Segments whose first point was due in the measurement.
    pub(crate) segments: u64,
    /// Of which arrived after their first point was due.
    pub(crate) late_segments: u64,
    /// Whether segment 0 was late.
    pub(crate) late_first_segment: bool,
    /// Segments that replaced points of earlier ones.
    pub(crate) superseding_segments: u64,
    /// Segments with status STALLED.
    pub(crate) stalled_segments: u64,
    /// Segments with status COLLISION.
    pub(crate) collision_segments: u64,
    /// The session opened.
    pub(crate) started: bool,
    /// Goal changes sent.
    pub(crate) retargets: u64,
    /// Why the stream failed.
    pub(crate) error: Option<String>,
}

/// Runs one robot to the end; never fails: an error ends the robot and is in its outcome.
pub(crate) async fn run_robot(
    client: DmpClient,
    task: RobotTask,
    probe: Arc<CellProbe>,
    shared: Arc<Shared>,
) -> RobotOutcome {
    let mut out = RobotOutcome { id: task.plan.id.clone(), ..Default::default() };
    let mut ledger = Ledger::new(task.end_unix).with_pose(task.orientations.is_some());
    tokio::time::sleep_until(task.start_at).await;
    out.error = stream(&client, &task, &probe, &shared, &mut ledger, &mut out).await.err();
    (out.expected, out.on_time) = ledger.finish(task.start_unix, task.rate);
    out
}

async fn stream(
    client: &DmpClient,
    task: &RobotTask,
    probe: &CellProbe,
    shared: &Shared,
    ledger: &mut Ledger,
    out: &mut RobotOutcome,
) -> Result<(), String> {
    let opened = client.session_decoded::<SegmentView>(task.start.clone());
    let (sender, mut segments) = match tokio::time::timeout(OPEN_TIMEOUT, opened).await {
        Err(_) => return Err(format!("opening the session timed out after {OPEN_TIMEOUT:?}")),
        Ok(Err(e)) => return Err(format!("opening the session: {e}")),
        Ok(Ok(s)) => s,
    };
    out.started = true;
    let retarget = tokio::time::sleep_until(task.start_at + task.retarget_every);
    let end = tokio::time::sleep_until(task.end_at);
    tokio::pin!(retarget, end);
    let mut watchdog = tokio::time::interval(Duration::from_secs(1));
    watchdog.set_missed_tick_behavior(MissedTickBehavior::Delay);
    let mut goal = 0;
    // Unix seconds of the latest segment (the watchdog's reference).
    let mut last_arrival = unix_now();
    let mut last_status = v1::SegmentStatus::Unspecified;
    let mut stop_deadline: Option<Instant> = None;
    loop {
        tokio::select! {
            biased;
            next = segments.next() => match next {
                Some(Ok(seg)) => {
                    let arrival_ns = unix_now_ns();
                    let arrival = arrival_ns as f64 * 1e-9;
                    last_arrival = arrival;
                    let facts = ledger.push(&seg, arrival)?;
                    last_status = seg.status();
                    if let Some(ns) = probe.answer(seg.scene_version, arrival_ns) {
                        shared.scene_latency.record(ns);
                    }
                    if facts.in_window {
                        out.segments += 1;
                        if facts.lateness_ns > 0 {
                            out.late_segments += 1;
                            out.late_first_segment |= seg.sequence == 0;
                            shared.late_per_second.record(arrival_ns);
                        }
                        shared.lateness.record(facts.lateness_ns);
                        task.server_lateness.record(facts.lateness_ns);
                        if facts.superseding {
                            out.superseding_segments += 1;
                            shared.superseding_lateness.record(facts.lateness_ns);
                        }
                        match last_status {
                            v1::SegmentStatus::Stalled => out.stalled_segments += 1,
                            v1::SegmentStatus::Collision => out.collision_segments += 1,
                            _ => {}
                        }
                    }
                }
                Some(Err(e)) => return Err(e.to_string()),
                None if stop_deadline.is_some() => return Ok(()),
                None => {
                    return Err(format!("the stream ended before the stop (last status {})", last_status.as_str_name()));
                }
            },
            _ = &mut retarget, if stop_deadline.is_none() => {
                goal = 1 - goal;
                let position = task.plan.goals[goal].clone();
                let sent = match task.orientations {
                    Some(q) => sender.set_pose_goal(position, Some(q[goal])).await,
                    None => sender.set_goal(position).await,
                };
                sent.map_err(|e| format!("new goal: {e}"))?;
                out.retargets += 1;
                let next = retarget.deadline() + task.retarget_every;
                retarget.as_mut().reset(next);
            }
            _ = &mut end, if stop_deadline.is_none() => {
                // The end of the measurement: the robot decelerates to rest and the server closes the stream.
                sender.stop().await.map_err(|e| format!("stop: {e}"))?;
                stop_deadline = Some(Instant::now() + STOP_TIMEOUT);
            }
            now = watchdog.tick() => {
                if unix_now() - last_arrival > STALL_TIMEOUT.as_secs_f64() {
                    return Err(format!("no segment for {STALL_TIMEOUT:?}"));
                }
                if stop_deadline.is_some_and(|d| now > d) {
                    return Err(format!("the stream did not close within {STOP_TIMEOUT:?} of the stop"));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DT: f64 = 0.001;
    const T0: f64 = 1_000.0;

    /// A 1-D segment of `n` points from run time `start` (real time, origin T0).
    fn seg(sequence: u64, start: f64, n: usize) -> SegmentView {
        SegmentView {
            sequence,
            start_time: start,
            dt: DT,
            dim: 1,
            positions: vec![0u8; 8 * n].into(),
            start_unix_s: T0 + start,
            ..Default::default()
        }
    }

    #[test]
    fn early_segments_are_on_time_and_the_window_bounds_the_count() {
        // 100 ms of 10-point segments, each arriving 50 ms early; the measurement ends at run time 0.0995 s.
        let mut l = Ledger::new(T0 + 0.0995);
        for k in 0..12 {
            let f = l.push(&seg(k, k as f64 * 0.01, 10), T0 + k as f64 * 0.01 - 0.05).unwrap();
            assert_eq!(f.lateness_ns, -50_000_000);
            assert!(!f.superseding);
            assert_eq!(f.in_window, k < 10);
        }
        // Points 0..=99 are due at or before the end.
        assert_eq!(l.finish(T0, 1000.0), (100, 100));
    }

    #[test]
    fn a_late_superseding_segment_makes_its_leading_points_late() {
        let mut l = Ledger::new(T0 + 1.0);
        for k in 0..5 {
            l.push(&seg(k, k as f64 * 0.01, 10), T0 - 0.05).unwrap();
        }
        // Supersedes from point 20 on, arriving 2.5 ms after point 20 was due: points 20, 21, 22 are late.
        let f = l.push(&seg(5, 0.02, 10), T0 + 0.0225).unwrap();
        assert!(f.superseding);
        assert_eq!(f.lateness_ns, 2_500_000);
        // Then on time up to point 999 (run time 0.999 s); point 1000, due at the end, never arrives.
        for k in 0..97 {
            let start = 0.03 + k as f64 * 0.01;
            l.push(&seg(6 + k, start, 10), T0 + start - 0.04).unwrap();
        }
        let (expected, on_time) = l.finish(T0, 1000.0);
        assert_eq!(expected, 1001, "points 0 ..= 1000");
        assert_eq!(on_time, 1001 - 3 - 1, "three late, and point 1000 never arrived");
    }

    #[test]
    fn settled_runs_are_counted_once_and_missing_points_are_not_on_time() {
        let mut l = Ledger::new(T0 + 10.0);
        // 2 s of on-time segments (finalised along the way: the ring stays small).
        for k in 0..200 {
            let start = k as f64 * 0.01;
            l.push(&seg(k, start, 10), T0 + start - 0.05).unwrap();
            assert!(l.runs.len() <= 110, "{}", l.runs.len());
        }
        // Points up to 940 were due more than a second before the last arrival (1.94 s): settled.
        assert_eq!(l.frontier, 940);
        // A superseding segment far in the past does not recount settled points (and is late by 1.5 s); it
        // supersedes every point not yet settled, and nothing replaces them: the stream ends.
        let f = l.push(&seg(200, 0.5, 10), T0 + 2.0).unwrap();
        assert_eq!(f.lateness_ns, 1_500_000_000);
        assert!(l.runs.is_empty());
        let (expected, on_time) = l.finish(T0, 1000.0);
        assert_eq!(expected, 10_001);
        assert_eq!(on_time, 940);
    }

    #[test]
    fn a_pose_robot_needs_the_orientations_of_every_point() {
        let mut l = Ledger::new(T0 + 1.0).with_pose(true);
        let e = l.push(&seg(0, 0.0, 10), T0).unwrap_err();
        assert!(e.contains("segment 0 of a pose robot lacks"), "{e}");
        let pose = SegmentView {
            orientations: [0.0f64, 0.0, 0.0, 1.0].repeat(10).iter().flat_map(|v| v.to_le_bytes()).collect(),
            angular_velocities: vec![0u8; 8 * 30].into(),
            angular_accelerations: vec![0u8; 8 * 30].into(),
            ..seg(0, 0.0, 10)
        };
        assert!(l.push(&pose, T0 - 0.01).is_ok());
        let short = SegmentView { angular_velocities: vec![0u8; 8 * 29].into(), ..pose.clone() };
        assert!(l.push(&short, T0).is_err());
        assert!(Ledger::new(T0 + 1.0).push(&seg(0, 0.0, 10), T0).is_ok(), "a position robot needs none");
    }

    #[test]
    fn a_robot_without_segments_expects_from_its_schedule() {
        assert_eq!(Ledger::new(T0 + 2.0).finish(T0 + 0.5, 1000.0), (1500, 0));
        let mut l = Ledger::new(T0);
        let e = l.push(&SegmentView { dt: DT, ..seg(0, 0.0, 10) }, T0).map(|_| ());
        assert_eq!(e, Ok(()));
        let e = l.push(&SegmentView { start_unix_s: 0.0, ..seg(1, 0.01, 10) }, T0).unwrap_err();
        assert!(e.contains("not real-time"), "{e}");
    }
}
