//! What a simulation measured: `report.json` and its figures.

use std::collections::BTreeMap;
use std::path::Path;

use dmp::{Agent, Trajectory};
use dmp_plot::{Event, PlotInput, PoseTrace, Series, render_svg};
use dmp_proto::v1;
use serde::Serialize;

use super::profile::{Peaks, finite_differences};
use super::robot::{Executed, check};
use super::world::{Body, SolidShape, point3};
use crate::error::SimError;

/// A robot ends at its goal when its last setpoint is this close (metres) and the server said GOAL_REACHED.
pub(crate) const GOAL_TOLERANCE_M: f64 = 1e-2;

/// Clearance at or below this (metres) is a contact.
pub(crate) const CONTACT_M: f64 = 1e-9;

/// One robot's figures.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct RobotReport {
    /// At the goal (within `GOAL_TOLERANCE_M`) and the last segment said GOAL_REACHED.
    pub reached_goal: bool,
    /// Distance from the last setpoint to the goal, metres.
    pub final_error_m: f64,
    /// Status of the last segment.
    pub final_status: String,
    /// Smallest distance between the robot's body and each obstacle's true shape (or other robot's body), metres;
    /// 0 is a contact.
    pub min_clearance_m: BTreeMap<String, f64>,
    /// Obstacles or robots touched.
    pub collisions: Vec<String>,
    /// Largest acceleration norm of the executed setpoints.
    pub peak_acceleration: f64,
    /// Largest speed of the executed setpoints.
    pub peak_speed: f64,
    /// Largest jerk norm of the executed setpoints (differences of consecutive accelerations).
    pub peak_jerk: f64,
    /// Peak speed, acceleration and jerk as finite differences of the executed positions (what the profile is
    /// checked on).
    pub finite_difference_peaks: Peaks,
    /// The robot's limit profile (put in its robot record before the run; unset: none).
    pub profile: Option<dmp::Limits>,
    /// Setpoints over the profile, as finite differences of the executed positions (expected 0).
    pub limit_violations: u64,
    /// Setpoints that arrived after their time (real time only).
    pub late_setpoints: u64,
    /// Steps where the robot had to jump to a superseding segment that arrived late (a consequence of the late
    /// setpoints; left out of `discontinuities`, `limit_violations` and the peaks).
    pub late_splices: u64,
    /// Setpoints executed.
    pub setpoints: u64,
    /// Segments read.
    pub segments: u64,
    /// Steps breaking the continuity bounds (`sim::robot`).
    pub discontinuities: u64,
    /// Time of the first discontinuous step, seconds of the run.
    pub first_discontinuity_s: Option<f64>,
    /// NaN or infinite values.
    pub non_finite: u64,
    /// Duration of the run, seconds.
    pub duration_s: f64,
    /// A pose run's orientation figures (`pose.rs`); none for a position run.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pose: Option<PoseReport>,
}

/// A pose robot's orientation figures.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct PoseReport {
    /// Angle between the last executed orientation and the goal orientation, degrees.
    pub final_orientation_error_deg: f64,
    /// The goal orientation, `[x, y, z, w]`.
    pub goal_orientation: [f64; 4],
    /// Largest rotation away from the first executed orientation, degrees.
    pub max_turn_from_start_deg: f64,
    /// Largest angular speed, finite differences of the executed orientations, rad/s.
    pub peak_angular_speed: f64,
    /// Largest angular acceleration (second differences), rad/s².
    pub peak_angular_acceleration: f64,
    /// Largest angular jerk (third differences), rad/s³.
    pub peak_angular_jerk: f64,
    /// Largest angular speed the server streamed (its `angular_velocities`), rad/s.
    pub streamed_peak_angular_speed: f64,
    /// Setpoints over the profile's angular limits (also counted in the robot's `limit_violations`).
    pub angular_limit_violations: u64,
    /// The true shape whose clearance `min_clearance_m` gives (the held tool, posed at every setpoint).
    pub body: String,
    /// Smallest clearance of that shape to any true obstacle, metres.
    pub min_body_clearance_m: f64,
}

/// The report of a simulation.
#[derive(Debug, Clone, Serialize, PartialEq, Default)]
pub struct SimReport {
    /// Which simulation.
    pub sim: String,
    /// Wall-clock pacing.
    pub realtime: bool,
    /// Some robot touched an obstacle's true shape or another robot.
    pub collision: bool,
    /// Per robot (one id per robot and run).
    pub robots: BTreeMap<String, RobotReport>,
    /// Figures specific to a simulation (named `<robot>/<what>`, SI units).
    pub metrics: BTreeMap<String, f64>,
    /// The figures written, relative to the output folder.
    pub plots: Vec<String>,
    /// What the set-up was (geometry, gains).
    pub notes: Vec<String>,
    /// The Cartesian limits every robot must stay within, if the simulation has them.
    pub limits: Option<CartesianLimits>,
}

/// The Cartesian limits every robot of a simulation must stay within: a row of `report.html`'s table, and checks
/// of the peaks (not [`dmp::Limits`], the profile the server keeps).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CartesianLimits {
    /// Speed, m/s.
    pub speed: f64,
    /// Acceleration, m/s².
    pub acceleration: f64,
    /// Jerk, m/s³.
    pub jerk: f64,
}

impl SimReport {
    /// An empty report.
    pub(crate) fn new(sim: &str, realtime: bool) -> Self {
        Self { sim: sim.into(), realtime, ..Default::default() }
    }

    /// Adds a robot.
    pub(crate) fn add(&mut self, id: &str, r: RobotReport) {
        self.collision |= !r.collisions.is_empty();
        self.robots.insert(id.into(), r);
    }

    /// Everything wrong: goals missed, contacts, discontinuities, non-finite values (empty: all good).
    pub fn problems(&self) -> Vec<String> {
        self.problems_allowing(false)
    }

    /// How many robots and how many runs the report holds: its entries are `<robot>/<run>`, so that one arm that
    /// makes three motions is one robot and three runs.
    pub fn robots_and_runs(&self) -> (usize, usize) {
        let robots: std::collections::BTreeSet<&str> =
            self.robots.keys().map(|k| k.split_once('/').map_or(k.as_str(), |(robot, _)| robot)).collect();
        (robots.len(), self.robots.len())
    }

    /// [`SimReport::problems`], leaving out the collisions when `allow_collision` (a run meant to collide).
    pub fn problems_allowing(&self, allow_collision: bool) -> Vec<String> {
        let mut p = Vec::new();
        for (id, r) in &self.robots {
            if !r.reached_goal {
                let turn = r.pose.as_ref().map_or(String::new(), |o| {
                    format!(", {:.3}° from the goal orientation", o.final_orientation_error_deg)
                });
                p.push(format!(
                    "{id}: goal not reached ({} m away{turn}, {})",
                    r.final_error_m, r.final_status
                ));
            }
            if !allow_collision {
                for c in &r.collisions {
                    p.push(format!("{id}: touches {c}"));
                }
            }
            if r.discontinuities > 0 {
                p.push(format!("{id}: {} discontinuous steps", r.discontinuities));
            }
            if r.non_finite > 0 {
                p.push(format!("{id}: {} non-finite values", r.non_finite));
            }
            if r.limit_violations > 0 {
                p.push(format!("{id}: {} setpoints over its limit profile", r.limit_violations));
            }
            if r.setpoints == 0 {
                p.push(format!("{id}: no setpoints"));
            }
        }
        p
    }

    /// Writes `report.json` in `dir` (`report.html` is its page, [`super::html::write_html`]).
    pub(crate) fn write_json(&self, dir: &Path) -> Result<(), SimError> {
        let path = dir.join("report.json");
        let text = serde_json::to_string_pretty(self).map_err(|e| SimError::Plot(e.to_string()))?;
        std::fs::write(&path, text + "\n").map_err(|source| SimError::Io { path, source })
    }
}

/// Row `k` of the positions.
pub(crate) fn position(t: &Trajectory, k: usize) -> &[f64] {
    let d = t.dim();
    &t.x[k * d..(k + 1) * d]
}

/// The row of `t` at time `time` (the nearest at or after it; the last one past the end).
fn row_at(t: &Trajectory, time: f64) -> Option<usize> {
    if t.is_empty() {
        return None;
    }
    Some(t.t.partition_point(|&s| s < time - 1e-9).min(t.len() - 1))
}

/// Another robot, for the robot-robot clearance.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Other<'a> {
    /// Its id.
    pub(crate) id: &'a str,
    /// What it executed (same times).
    pub(crate) traj: &'a Trajectory,
    /// Its body around its controlled point.
    pub(crate) body: &'a Body,
    /// Its orientations, 4 per row of `traj` (a pose robot, or one holding its orientation); none: not turned.
    pub(crate) orientations: Option<&'a [f64]>,
}

/// The distance of `body` at `p` to `o`: turned by row `k` of the orientations `q` of a pose run.
fn posed_distance(body: &Body, p: parry3d_f64::math::Vector, q: Option<&[f64]>, k: usize, o: &Body) -> f64 {
    match q.and_then(|q| q.get(4 * k..4 * k + 4)) {
        Some(q) => body.distance_posed(p, q, o),
        None => body.distance(p, o, parry3d_f64::math::Vector::ZERO),
    }
}

/// Measures one robot: goal, checks, its setpoints against its limit `profile` (none: [`dmp::Limits::NONE`]),
/// and clearance of `body` (around the controlled point) against the obstacles present at each time and the other
/// robots at the same time. A pose run's body turns with its orientations (its clearance is its true shape's); its
/// orientation figures are added by [`super::pose::add_pose`].
pub(crate) fn measure(
    exec: &Executed,
    dt: f64,
    goal: &[f64],
    profile: Option<&dmp::Limits>,
    body: &Body,
    obstacles: &[Body],
    others: &[Other<'_>],
) -> RobotReport {
    let traj = &exec.traj;
    let checks = check(traj, dt, &exec.late_splices);
    let (finite_difference_peaks, limit_violations) =
        finite_differences(traj, profile.unwrap_or(&dmp::Limits::NONE), &exec.late_splices);
    let mut min: BTreeMap<String, f64> = BTreeMap::new();
    for o in obstacles {
        min.insert(o.id.clone(), f64::INFINITY);
    }
    for o in others {
        min.insert(o.id.into(), f64::INFINITY);
    }
    let q = exec.orientations.as_ref().map(|o| o.q.as_slice());
    for k in 0..traj.len() {
        let t = traj.t[k];
        let p = point3(position(traj, k));
        for o in obstacles.iter().filter(|o| o.present_at(t)) {
            let d = posed_distance(body, p, q, k, o);
            let m = min.get_mut(&o.id).expect("inserted above");
            *m = m.min(d);
        }
        for o in others {
            if let Some(j) = row_at(o.traj, t) {
                let mine = q.and_then(|q| q.get(4 * k..4 * k + 4));
                let theirs = o.orientations.and_then(|q| q.get(4 * j..4 * j + 4));
                let d = body.distance_carried((p, mine), o.body, (point3(position(o.traj, j)), theirs));
                let m = min.get_mut(o.id).expect("inserted above");
                *m = m.min(d);
            }
        }
    }
    let final_error_m = if traj.is_empty() {
        f64::INFINITY
    } else {
        let end = position(traj, traj.len() - 1);
        end.iter().zip(goal).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt()
    };
    let collisions = min.iter().filter(|(_, d)| **d <= CONTACT_M).map(|(id, _)| id.clone()).collect();
    RobotReport {
        reached_goal: final_error_m <= GOAL_TOLERANCE_M
            && exec.final_status == v1::SegmentStatus::GoalReached,
        final_error_m,
        final_status: exec.final_status.as_str_name().to_string(),
        min_clearance_m: min,
        collisions,
        peak_acceleration: checks.peak_acceleration,
        peak_speed: checks.peak_speed,
        peak_jerk: checks.peak_jerk,
        finite_difference_peaks,
        profile: profile.copied(),
        limit_violations,
        late_setpoints: exec.late_setpoints,
        late_splices: checks.late_steps,
        setpoints: traj.len() as u64,
        segments: exec.segments,
        discontinuities: checks.discontinuities,
        first_discontinuity_s: checks.first_discontinuity_s,
        non_finite: checks.non_finite,
        duration_s: traj.t.last().copied().unwrap_or(0.0) - traj.t.first().copied().unwrap_or(0.0),
        pose: None,
    }
}

/// One figure in the paper's style.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Figure<'a> {
    /// Title.
    pub(crate) title: &'a str,
    /// Start and goal of the straight line (drawn as the "demonstration").
    pub(crate) line: (&'a [f64], &'a [f64]),
    /// Obstacle-free rollout.
    pub(crate) free: &'a Trajectory,
    /// What the robot executed.
    pub(crate) adapted: &'a Trajectory,
    /// The obstacles the planner sees (superquadrics, inflated).
    pub(crate) obstacles: &'a [dmp::Obstacle],
    /// Robots sharing the DMP (empty: one).
    pub(crate) robots: &'a [Agent],
    /// When to draw moving obstacles and footprints.
    pub(crate) time: f64,
    /// The true world: the obstacles' real shapes, drawn under the superquadrics the planner sees.
    pub(crate) world: &'a [Body],
    /// Point clouds a perception node saw, drawn with the true shapes.
    pub(crate) seen: &'a [dmp_plot::Solid],
    /// The robot's body, for a single robot: its clearance to the world over time is measured with it (else the
    /// figure measures from the controlled point).
    pub(crate) body: Option<&'a Body>,
    /// The avoidance method of the run (its name in the scenario format).
    pub(crate) method: &'a str,
    /// What happened during the run.
    pub(crate) events: &'a [Event],
    /// A pose run's orientations and its held shape: a panel of the rotation from the start, the shape's outline
    /// along the path, and the clearance of the turned body.
    pub(crate) pose: Option<PoseTrace<'a>>,
}

/// A body of the world as the figure's true shape, in the robot's `sub` dimensions.
fn plot_solid(b: &Body, sub: usize) -> dmp_plot::Solid {
    let shape = match b.solid() {
        SolidShape::Ball { radius } => dmp_plot::SolidShape::Ball { radius },
        SolidShape::Cuboid { half } => dmp_plot::SolidShape::Box { half: half[..sub].to_vec() },
        SolidShape::CylinderZ { radius, half_height } => {
            dmp_plot::SolidShape::CylinderZ { radius, half_height }
        }
        SolidShape::Point => dmp_plot::SolidShape::Points(vec![vec![0.0; sub]]),
    };
    let mut s = dmp_plot::Solid::new(b.id.clone(), shape, b.center()[..sub].to_vec());
    s.from = b.from;
    s.until = b.until;
    s
}

/// Clearance of `body` (around the controlled point, turned by the orientations `q` of a pose run) to the nearest
/// body of `world` present, along `traj`.
fn clearance_series(traj: &Trajectory, q: Option<&[f64]>, body: &Body, world: &[Body]) -> Series {
    let mut s = Series { t: traj.t.clone(), v: Vec::with_capacity(traj.len()) };
    for k in 0..traj.len() {
        let p = point3(position(traj, k));
        let t = traj.t[k];
        let d = world
            .iter()
            .filter(|o| o.present_at(t))
            .map(|o| posed_distance(body, p, q, k, o))
            .fold(f64::INFINITY, f64::min);
        s.v.push(d);
    }
    s
}

/// Renders `fig` to `dir/name`.
pub(crate) fn write_figure(dir: &Path, name: &str, fig: &Figure<'_>) -> Result<(), SimError> {
    let demo = vec![fig.line.0.to_vec(), fig.line.1.to_vec()];
    let sub = fig.robots.first().map_or(fig.line.0.len(), |r| r.dims.len()).min(3);
    let mut solids: Vec<dmp_plot::Solid> = fig.world.iter().map(|b| plot_solid(b, sub)).collect();
    solids.extend(fig.seen.iter().cloned());
    let clearance = match fig.body {
        Some(body) if fig.robots.len() <= 1 => {
            let q: Option<Vec<f64>> = fig.pose.map(|p| p.orientations.iter().flatten().copied().collect());
            Some(vec![clearance_series(fig.adapted, q.as_deref(), body, fig.world)])
        }
        _ => None,
    };
    let input = PlotInput {
        title: fig.title,
        demonstration: &demo,
        demonstration_t: None,
        free: fig.free,
        adapted: fig.adapted,
        goal: Some(fig.line.1),
        obstacles: fig.obstacles,
        robots: fig.robots,
        obstacle_time: fig.time,
        solids: &solids,
        method: fig.method,
        clearance: clearance.as_deref(),
        events: fig.events,
        pose: fig.pose,
    };
    let svg = render_svg(&input).map_err(|e| SimError::Plot(e.to_string()))?;
    let path = dir.join(name);
    std::fs::write(&path, svg).map_err(|source| SimError::Io { path, source })
}
