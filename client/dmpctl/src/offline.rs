//! The offline half of `dmpctl`: running and timing scenarios with the engine in-process.

use std::path::Path;
use std::time::Instant;

use dmp::metrics::Metrics;
use dmp::scenario::{Prepared, ScenarioOutcome};
use dmp_plot::{PlotInput, render_svg};
use serde::Serialize;

use crate::error::DmpctlError;
use crate::outputs::{to_json, trajectory_csv, write_file};
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
    write_outputs(&prepared, &free.trajectory, &adapted.trajectory, &metrics, out)?;
    Ok(RunSummary { metrics, notes: Vec::new() })
}

/// Writes the three files of a run.
pub fn write_outputs(
    p: &Prepared,
    free: &dmp::Trajectory,
    adapted: &dmp::Trajectory,
    metrics: &Metrics,
    out: &Path,
) -> Result<(), DmpctlError> {
    write_file(out, "trajectory.csv", trajectory_csv(adapted).as_bytes())?;
    write_file(out, "metrics.json", to_json(metrics).as_bytes())?;
    let svg = render_svg(&PlotInput {
        title: &p.name,
        demonstration: p.demonstration.positions(),
        // Drawn from the start of the rollouts on (the plot shifts them to start there, at 0).
        demonstration_t: Some(p.demonstration.times()),
        free,
        adapted,
        goal: Some(&p.motion.goal),
        obstacles: &p.scene.obstacles,
        robots: &p.scene.agents,
        obstacle_time: f64::NAN,
        solids: &[],
        method: p.scene.avoidance.method.name(),
        clearance: None,
        events: &[],
    })?;
    write_file(out, "plot.svg", svg.as_bytes())
}

/// The JSON line of `scenario bench`.
#[derive(Debug, Clone, Serialize)]
pub struct BenchReport {
    /// The scenario's name.
    pub scenario: String,
    /// Median over repeats of steps per second of the avoidance rollout.
    pub steps_per_second: f64,
    /// Steps per rollout.
    pub steps: usize,
    /// Number of timed rollouts.
    pub repeats: usize,
    /// Median wall time of one rollout.
    pub median_seconds: f64,
    /// Fastest rollout.
    pub min_seconds: f64,
    /// Slowest rollout.
    pub max_seconds: f64,
    /// Obstacles in the scene.
    pub obstacles: usize,
    /// The avoidance method.
    pub method: String,
}

/// Times the scenario's avoidance rollout `repeats` times (after one untimed warm-up run).
pub fn bench_scenario(path: &Path, repeats: usize) -> Result<BenchReport, DmpctlError> {
    let p = prepare_scenario(path)?;
    let repeats = repeats.max(1);
    let mut seconds = Vec::with_capacity(repeats);
    for i in 0..=repeats {
        let field = p.field().map_err(invalid(path))?;
        let started = Instant::now();
        let r = dmp::rollout(&p.primitive, &p.motion, &field, p.dt, p.steps).map_err(invalid(path))?;
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
