//! The offline half of `dmpctl`: running and timing scenarios with the engine in-process.

use std::path::Path;
use std::time::Instant;

use dmp::metrics::Metrics;
use dmp::scenario::{Prepared, ScenarioOutcome};
use dmp_plot::{PlotInput, PoseTrace, Series, render_svg};
use serde::Serialize;

use crate::error::DmpctlError;
use crate::outputs::{pose_trajectory_csv, positions_of, to_json, trajectory_csv, write_file};
use crate::scenario_file::prepare_scenario;

/// What `scenario run` produced.
#[derive(Debug, Clone)]
pub struct RunSummary {
    /// The metrics written to `metrics.json`.
    pub metrics: Metrics,
    /// Remarks worth printing (e.g. where a run through the server departs from the offline one).
    pub notes: Vec<String>,
}

fn invalid(path: &Path) -> impl FnOnce(dmp::DmpError) -> DmpctlError + '_ {
    move |source| DmpctlError::Invalid { path: path.to_path_buf(), source }
}

/// Runs the scenario at `path` and writes `trajectory.csv`, `metrics.json` and `plot.svg` into `out`.
pub fn run_scenario(path: &Path, out: &Path) -> Result<RunSummary, DmpctlError> {
    let started = Instant::now();
    let prepared = prepare_scenario(path)?;
    let ScenarioOutcome { free, adapted, mut metrics } =
        dmp::scenario::run(&prepared).map_err(invalid(path))?;
    metrics.compute_seconds = started.elapsed().as_secs_f64();
    write_outputs(&prepared, &free, &adapted, &metrics, out)?;
    Ok(RunSummary { metrics, notes: Vec::new() })
}

/// Writes the three files of a run (a pose run's `trajectory.csv` has its orientations after the positions; its
/// plot draws the positions).
pub(crate) fn write_outputs(
    p: &Prepared,
    free: &dmp::Rollout,
    adapted: &dmp::Rollout,
    metrics: &Metrics,
    out: &Path,
) -> Result<(), DmpctlError> {
    let csv = match &p.pose {
        None => trajectory_csv(&adapted.trajectory),
        Some(_) => pose_trajectory_csv(&adapted.trajectory, &adapted.orientations),
    };
    write_file(out, "trajectory.csv", csv.as_bytes())?;
    let quaternions = |r: &dmp::Rollout| -> Vec<[f64; 4]> {
        r.orientations.q.chunks_exact(4).map(|q| [q[0], q[1], q[2], q[3]]).collect()
    };
    let (orientations, free_orientations) = (quaternions(adapted), quaternions(free));
    let tool_surface = tool_surface(p);
    let pose = p.pose.as_ref().map(|_| PoseTrace {
        orientations: &orientations,
        free_orientations: &free_orientations,
        tool_surface: &tool_surface,
    });
    let tool_clearance = tool_clearance(p, adapted);
    let (free, adapted) = (positions_of(p, &free.trajectory), positions_of(p, &adapted.trajectory));
    let (free, adapted) = (free.as_ref(), adapted.as_ref());
    write_file(out, "metrics.json", to_json(metrics).as_bytes())?;
    let svg = render_svg(&PlotInput {
        title: &p.name,
        demonstration: p.demonstration.positions(),
        // Drawn from the start of the rollouts on (the plot shifts them to start there, at 0).
        demonstration_t: Some(p.demonstration.times()),
        free,
        adapted,
        goal: Some(&p.motion.goal[..p.position_dim()]),
        obstacles: &p.scene.obstacles,
        // A pose scenario's one robot is no group.
        robots: if p.pose.is_some() { &[] } else { &p.scene.agents },
        // A held tool is outlined where it is turned furthest from its start orientation, besides the evenly spaced
        // times.
        obstacle_time: most_turned(&adapted.t, &orientations),
        solids: &[],
        method: p.scene.avoidance.method.name(),
        // A held tool: its surface's clearance, not the controlled point's.
        clearance: tool_clearance.as_ref().map(std::slice::from_ref),
        events: &[],
        pose,
    })?;
    write_file(out, "plot.svg", svg.as_bytes())
}

/// Samples of the held tool's surface in the tool frame, for its outline in the plot (none without a tool).
fn tool_surface(p: &Prepared) -> Vec<[f64; 3]> {
    let Some(tool) = p.pose.as_ref().and_then(|pose| pose.tool.as_ref()) else { return Vec::new() };
    let offset = tool.offset();
    dmp::tool::ControlPoints::Surface { count: TOOL_OUTLINE_SAMPLES }
        .sample(tool.shape())
        .into_iter()
        .map(|r| [r.x + offset.x, r.y + offset.y, r.z + offset.z])
        .collect()
}

/// The clearance of a held tool's surface to the nearest obstacle over the adapted run, sampled
/// ([`TOOL_CLEARANCE_SAMPLES`] surface points every [`TOOL_CLEARANCE_STRIDE`] rows); `None` without a tool.
fn tool_clearance(p: &Prepared, adapted: &dmp::Rollout) -> Option<Series> {
    use nalgebra::{Quaternion, UnitQuaternion, Vector3};
    let tool = p.pose.as_ref()?.tool.as_ref()?;
    let samples = dmp::tool::surface_samples(tool, TOOL_CLEARANCE_SAMPLES);
    let (traj, q) = (&adapted.trajectory, &adapted.orientations.q);
    let mut series = Series::default();
    for k in (0..traj.len().min(q.len() / 4)).step_by(TOOL_CLEARANCE_STRIDE) {
        let x = Vector3::from_column_slice(&traj.position(k)[..3]);
        let r = UnitQuaternion::new_normalize(Quaternion::new(
            q[4 * k + 3],
            q[4 * k],
            q[4 * k + 1],
            q[4 * k + 2],
        ));
        let d = p
            .scene
            .obstacles
            .iter()
            .map(|o| dmp::tool::sampled_clearance(&samples, &x, &r, o, traj.t[k]))
            .fold(f64::INFINITY, f64::min);
        series.t.push(traj.t[k]);
        series.v.push(d);
    }
    Some(series)
}

/// The time at which the orientation is furthest from the first (not finite without orientations).
fn most_turned(t: &[f64], orientations: &[[f64; 4]]) -> f64 {
    let Some(q0) = orientations.first() else { return f64::NAN };
    let dot = |q: &[f64; 4]| q.iter().zip(q0).map(|(a, b)| a * b).sum::<f64>().abs();
    orientations
        .iter()
        .zip(t)
        .min_by(|(a, _), (b, _)| dot(a).total_cmp(&dot(b)))
        .map_or(f64::NAN, |(_, t)| *t)
}

/// Surface samples of a held tool for its clearance in the plot.
const TOOL_CLEARANCE_SAMPLES: usize = 200;
/// Rows between two points of a held tool's clearance in the plot.
const TOOL_CLEARANCE_STRIDE: usize = 20;

/// Surface samples of a held tool drawn in the plot (before projection and convex hull).
const TOOL_OUTLINE_SAMPLES: usize = 2000;

/// The JSON line of `scenario bench`.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct BenchReport {
    /// The scenario's name.
    pub(crate) scenario: String,
    /// Median over repeats of steps per second of the avoidance rollout.
    pub(crate) steps_per_second: f64,
    /// Steps per rollout.
    pub(crate) steps: usize,
    /// Number of timed rollouts.
    pub(crate) repeats: usize,
    /// Median wall time of one rollout.
    pub(crate) median_seconds: f64,
    /// Fastest rollout.
    pub(crate) min_seconds: f64,
    /// Slowest rollout.
    pub(crate) max_seconds: f64,
    /// Obstacles in the scene.
    pub(crate) obstacles: usize,
    /// The avoidance method.
    pub(crate) method: String,
}

/// Times the scenario's avoidance rollout `repeats` times (after one untimed warm-up run).
pub(crate) fn bench_scenario(path: &Path, repeats: usize) -> Result<BenchReport, DmpctlError> {
    let p = prepare_scenario(path)?;
    let repeats = repeats.max(1);
    let mut seconds = Vec::with_capacity(repeats);
    for i in 0..=repeats {
        let field = p.field().map_err(invalid(path))?;
        let started = Instant::now();
        let r = p.roll_out(&field).map_err(invalid(path))?;
        let elapsed = started.elapsed().as_secs_f64();
        std::hint::black_box(&r);
        if i > 0 {
            seconds.push(elapsed);
        }
    }
    seconds.sort_by(f64::total_cmp);
    let median = if repeats % 2 == 1 {
        seconds[repeats / 2]
    } else {
        0.5 * (seconds[repeats / 2 - 1] + seconds[repeats / 2])
    };
    Ok(BenchReport {
        scenario: p.name.clone(),
        steps_per_second: p.steps as f64 / median,
        steps: p.steps,
        repeats,
        median_seconds: median,
        min_seconds: seconds[0],
        max_seconds: seconds[repeats - 1],
        obstacles: p.scene.obstacles.len(),
        method: p.scene.avoidance.method.name().to_string(),
    })
}
