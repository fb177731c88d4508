//! How a run ended, for the robot and its operator ([`v1::Verdict`]): the [`Judge`] of a run records, stretch by
//! stretch, what its verdict depends on (the contacts with the true shapes, the stalls, the braking, the last status),
//! forgetting what a later stretch supersedes; [`verdict`] says, at the run's last segment, whether the goal was
//! reached and if not why, in one line for a person.
//!
//! The order: a collision beats everything (a setpoint inside an obstacle is never a good run, even one that arrived
//! afterwards); then arriving (the goal reached), a stop on request, and for a run whose time ran out: held before an
//! obstacle (BLOCKED at the end), stalled at rest away from the goal (a local minimum), braked to rest within the
//! limits, or plainly out of time.

use dmp::execution::Stretch;
use dmp::field::Contact;
use dmp::{Execution, LimitAction, Outcome};
use dmp_proto::v1;
use nalgebra::UnitQuaternion;

/// What a run's verdict depends on, recorded as its stretches are computed. A stretch supersedes what was recorded
/// from its start time on (a rollback in real time).
#[derive(Debug, Clone, Default)]
pub(crate) struct Judge {
    /// The first contact with each obstacle or robot: its id, whether it is a robot, and the run time.
    collisions: Vec<Touch>,
    /// Stalls: (run time since which the robot was at rest, its distance to the goal).
    stalls: Vec<(f64, f64)>,
    /// Run times at which a stretch braked to rest within the limits.
    braking: Vec<f64>,
    /// Smallest clearance reported by a segment, with its start time.
    clearances: Vec<(f64, f64)>,
    /// The status of the last stretch.
    last_status: Option<v1::SegmentStatus>,
    /// The last point was braking, or held at rest, before the safety distance.
    blocked: bool,
    /// How the run's time is bounded, for the reason of a run that ran out of it ("at 3 tau").
    end_label: String,
    /// A pose run: the chart of its orientation dimensions (for the angle to the goal orientation).
    chart: Option<UnitQuaternion<f64>>,
}

/// A contact with an obstacle or another robot.
#[derive(Debug, Clone)]
struct Touch {
    id: String,
    robot: bool,
    t: f64,
}

/// How a run ended, besides collisions (from the outcome of its last stretch).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Ending {
    /// Every robot at its goal and at rest.
    GoalReached,
    /// Stopped on request.
    Stopped,
    /// Its time ran out (max duration, 3 tau, the plan's duration).
    OutOfTime,
}

impl Ending {
    /// The ending of a run whose last stretch came to `outcome`, when that outcome ends it.
    pub(crate) fn of(outcome: Outcome) -> Option<Self> {
        match outcome {
            Outcome::GoalReached => Some(Ending::GoalReached),
            Outcome::Stopped => Some(Ending::Stopped),
            Outcome::EndTime => Some(Ending::OutOfTime),
            Outcome::Running | Outcome::Holding | Outcome::Stalled | Outcome::Collision => None,
        }
    }
}

impl Judge {
    /// A judge for a run whose time is bounded as `end_label` says (e.g. "at 3 tau"), with a pose run's `chart`.
    pub(crate) fn new(end_label: impl Into<String>, chart: Option<UnitQuaternion<f64>>) -> Self {
        Self { end_label: end_label.into(), chart, ..Self::default() }
    }

    /// Records what the stretch `p` of the run `e` came to, with the status its segments carry; what was recorded
    /// from its start on is forgotten first (those points are superseded).
    pub(crate) fn observe(&mut self, e: &Execution, p: &Stretch, status: v1::SegmentStatus) {
        let dt = e.dt();
        let from = p.start_time - 0.5 * dt;
        self.collisions.retain(|c| c.t < from);
        self.stalls.retain(|s| s.0 < from);
        self.braking.retain(|t| *t < from);
        self.clearances.retain(|c| c.0 < from);
        let field = e.field();
        for &(k, c) in &p.contacts {
            let (id, robot) = match c {
                Contact::Obstacle { obstacle, .. } => {
                    (field.scene().obstacles.get(obstacle).map(|o| o.id().to_owned()), false)
                }
                Contact::Robot { other, .. } => (field.agents().get(other).map(|a| a.id.clone()), true),
            };
            if let Some(id) = id {
                self.touch(id, robot, p.start_time + k as f64 * dt);
            }
        }
        if let Some(&(k, _)) = p.cell_mate_contacts.iter().min_by_key(|(k, _)| *k) {
            // The engine names the cell-mates it touched (not by index): those touched so far that are neither an
            // obstacle of the run nor one of its members.
            let t = p.start_time + k as f64 * dt;
            let mates: Vec<String> = e
                .touched()
                .iter()
                .filter(|id| {
                    !field.scene().obstacles.iter().any(|o| o.id() == id.as_str())
                        && !field.agents().iter().any(|a| &a.id == *id)
                })
                .cloned()
                .collect();
            if mates.is_empty() {
                self.touch("another robot of the cell".into(), true, t);
            }
            for id in mates {
                self.touch(id, true, t);
            }
        }
        for (_, s) in &p.stalls {
            self.stalls.push((s.since, s.distance));
        }
        if p.limit == LimitAction::Braking {
            self.braking.push(p.start_time);
        }
        self.blocked = e.is_blocked();
        self.last_status = Some(status);
    }

    /// Records a segment's smallest clearance (its start time, the clearance).
    pub(crate) fn observe_clearance(&mut self, start_time: f64, clearance: Option<f64>) {
        if let Some(c) = clearance.filter(|c| c.is_finite()) {
            self.clearances.push((start_time, c));
        }
    }

    fn touch(&mut self, id: String, robot: bool, t: f64) {
        if !self.collisions.iter().any(|c| c.id == id) {
            self.collisions.push(Touch { id, robot, t });
        }
    }

    /// The obstacles and robots touched so far, by id, in the order they were first touched.
    pub(crate) fn collisions(&self) -> Vec<String> {
        self.collisions.iter().map(|c| c.id.clone()).collect()
    }
}

/// Where the run ended: the largest distance to the goal over the members and a pose run's angle to the goal
/// orientation, read from the last point of each member's segment in `batch`.
fn distance_left(e: &Execution, chart: Option<&UnitQuaternion<f64>>, batch: &[v1::Segment]) -> (f64, f64) {
    let goal = &e.motion().goal;
    let mut distance: f64 = 0.0;
    let mut angle: f64 = 0.0;
    for (m, s) in e.members().iter().zip(batch) {
        let d = s.dim as usize;
        if d == 0 || s.positions.len() < d {
            continue;
        }
        let last = &s.positions[s.positions.len() - d..];
        let dist2: f64 =
            m.dims.iter().zip(last).map(|(&i, x)| (x - goal.get(i).copied().unwrap_or(*x)).powi(2)).sum();
        distance = distance.max(dist2.sqrt());
        if let (Some(chart), Some(q)) = (chart, s.orientations.rchunks_exact(4).next()) {
            let n = goal.len().saturating_sub(3);
            if goal.len() >= 3 {
                let y = nalgebra::Vector3::from_column_slice(&goal[n..]);
                let target = dmp::orientation::pose::from_chart(chart, &y);
                if let Ok(q) =
                    dmp::orientation::quaternion::from_xyzw("orientation", [q[0], q[1], q[2], q[3]])
                {
                    angle = angle.max(dmp::orientation::quaternion::angle_between(&q, &target));
                }
            }
        }
    }
    (distance, angle)
}

/// "0.142 m short of the goal" (and a pose run's angle).
fn short_of(distance: f64, angle: f64, pose: bool) -> String {
    if pose {
        format!("{distance:.3} m and {:.2}° short of the goal", angle.to_degrees())
    } else {
        format!("{distance:.3} m short of the goal")
    }
}

/// The verdict on a run `e` judged by `judge` that ended as `ending` with the segments `batch` (one per member):
/// what [`v1::Segment::verdict`] and [`v1::PlanResponse::verdict`] carry.
pub(crate) fn verdict(e: &Execution, judge: &Judge, batch: &[v1::Segment], ending: Ending) -> v1::Verdict {
    use v1::Outcome as O;
    let (goal_distance, goal_angle) = distance_left(e, judge.chart.as_ref(), batch);
    let pose = judge.chart.is_some();
    let goal_reached = ending == Ending::GoalReached || (ending == Ending::OutOfTime && e.arrived());
    let end = batch.first().map(|s| {
        s.start_time + s.dt * (s.positions.len() / (s.dim.max(1) as usize)).saturating_sub(1) as f64
    });
    let end = end.unwrap_or_else(|| e.time());
    let short = short_of(goal_distance, goal_angle, pose);
    let label = if judge.end_label.is_empty() { "at the end of its time" } else { judge.end_label.as_str() };
    let (outcome, reason) = if let Some(first) = judge.collisions.first() {
        let what = |c: &Touch| {
            format!("{} '{}' at t = {:.3} s", if c.robot { "robot" } else { "obstacle" }, c.id, c.t)
        };
        let mut reason = format!("collision with {}", what(first));
        for c in &judge.collisions[1..] {
            reason.push_str(&format!(", then {}", what(c)));
        }
        if goal_reached {
            reason.push_str("; then reached the goal");
        } else {
            reason.push_str(&format!("; ended {short}"));
        }
        (O::Collision, reason)
    } else if goal_reached {
        let since = e.goal_met_since().unwrap_or(end);
        (O::GoalReached, format!("reached the goal (at rest within the tolerance since t = {since:.3} s)"))
    } else if ending == Ending::Stopped {
        (O::Stopped, format!("stopped on request at t = {end:.3} s, {short}"))
    } else if judge.blocked || judge.last_status == Some(v1::SegmentStatus::Blocked) {
        (O::Blocked, format!("held before an obstacle's safety distance until the end, {short} {label}"))
    } else if let Some(&(since, _)) = judge.stalls.last().filter(|_| e.at_rest()) {
        (
            O::Stalled,
            format!("stalled at t = {since:.3} s (a local minimum of the field); ended {short} {label}"),
        )
    } else if let Some(&t) = judge
        .braking
        .last()
        .filter(|_| e.at_rest() || judge.last_status == Some(v1::SegmentStatus::LimitBraking))
    {
        (O::Braked, format!("braked to rest within the limits at t = {t:.3} s; ended {short} {label}"))
    } else {
        (O::OutOfTime, format!("ended {short} {label} (out of time)"))
    };
    v1::Verdict {
        outcome: outcome as i32,
        goal_reached,
        reason,
        goal_distance,
        goal_angle,
        min_clearance: judge.clearances.iter().map(|c| c.1).reduce(f64::min),
        collisions: judge.collisions(),
    }
}
