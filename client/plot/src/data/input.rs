//! What to draw: the runs, the obstacles and robots, and what happened over time, as the caller hands them in.

use dmp::{Agent, Obstacle, Trajectory};

use super::pose::PoseTrace;
use super::solid::Solid;

/// What to draw: one scenario run, with its demonstration, obstacles, robots and events.
#[derive(Debug, Clone, Copy)]
pub struct PlotInput<'a> {
    /// Figure title.
    pub title: &'a str,
    /// The demonstration's positions, a row per sample, `d` columns (the full DMP dimension).
    pub demonstration: &'a [Vec<f64>],
    /// The demonstration's sample times, one per row of [`Self::demonstration`], used in plots against time;
    /// shifted so that the first sample is drawn at the start of the rollouts. `None`: the rows are spread evenly
    /// over the obstacle-free rollout's time span (and the legend says the time is rescaled).
    pub demonstration_t: Option<&'a [f64]>,
    /// The obstacle-free rollout; its first row is drawn as the start.
    pub free: &'a Trajectory,
    /// The rollout with avoidance.
    pub adapted: &'a Trajectory,
    /// The goal of the rollouts, `d` entries, drawn as the goal marker. `None`: the last row of the obstacle-free
    /// rollout is drawn as the goal.
    pub goal: Option<&'a [f64]>,
    /// Obstacles in robot space (each of a robot's dimension).
    pub obstacles: &'a [Obstacle],
    /// Robots sharing the DMP; empty for one robot owning every dimension.
    pub robots: &'a [Agent],
    /// A time worth marking when obstacles or robots move (e.g. when two robots are closest): moving obstacles and
    /// robot footprints are outlined at it and at evenly spaced times of the run. Not finite: only the latter.
    pub obstacle_time: f64,
    /// The true shapes of the obstacles (what a contact is measured against). Empty: each obstacle of
    /// [`Self::obstacles`] is its own true shape (the scenario format, where the superquadric is the obstacle).
    pub solids: &'a [Solid],
    /// The avoidance method of the adapted run, as the scenario format names it (`none`, `dynamic_volumetric`, ...):
    /// the legend says which run avoided what. `none` is labelled as a run without avoidance.
    pub method: &'a str,
    /// Clearance of each robot to the nearest obstacle over time, as the caller measured it (e.g. with the robot's
    /// body), in the order of the robots (one series for a single robot). `None`: the distance from the robot's
    /// controlled point to the nearest true shape present, along the adapted trajectory.
    pub clearance: Option<&'a [Series]>,
    /// What happened during the run, drawn as vertical lines in the time strip.
    pub events: &'a [Event],
    /// A pose run's orientations (a panel of the time strip) and held tool (outlined along the path at the marked
    /// times); `None` for a position run. Only for a robot moving in 3-D.
    pub pose: Option<PoseTrace<'a>>,
}

/// Values over time, such as a robot's clearance to the nearest obstacle.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Series {
    /// Times, seconds.
    pub t: Vec<f64>,
    /// One value per time.
    pub v: Vec<f64>,
}

/// Something that happened at a time of the run: an obstacle appears or goes, the goal changes, a new scene version.
#[derive(Debug, Clone, PartialEq)]
pub struct Event {
    /// Time, seconds (the trajectories' clock).
    pub t: f64,
    /// What, short (drawn beside the line).
    pub label: String,
}

impl Event {
    /// An event at time `t` (seconds), labelled `label`.
    pub fn new(t: f64, label: impl Into<String>) -> Self {
        Self { t, label: label.into() }
    }
}
