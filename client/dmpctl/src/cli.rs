//! The `dmpctl` command line's dispatcher: runs a parsed [`Cli`] (the binary only parses and calls [`run`]). The
//! flags and commands themselves are the `args` module's.
//!
//! Offline: `scenario run FILE --out DIR` (without `--server`) and `scenario bench`. Everything else talks to the
//! server at `--server` (gRPC), or publishes over Zenoh (`scene ... --via zenoh`).

use std::path::{Path, PathBuf};

use dmp_client::ClientError;
use dmp_client::grpc::{DEFAULT_SERVER, DmpClient};
use dmp_client::tls_probe::https_hint;
use dmp_sim::robots::robot::segments_read;

pub use crate::args::Cli;
use crate::args::{Command, RobotCommand, ScenarioCommand, SceneCommand, TOKEN_ENV};
use crate::error::DmpctlError;
use crate::offline::{RunSummary, bench_scenario, run_scenario};
use crate::outputs::to_json;
use crate::place::{resolve_place, resolve_server};
use crate::progress::Progress;
use crate::robot_commands;
use crate::scenario_file::load_scenario;
use crate::scenario_through_server::{self, robot_ids, run_scenario_through_server};
use crate::server_commands::{self, ZenohArgs};
use crate::server_info;
use crate::tools::{self, until_interrupted};

/// Runs a parsed command line; returns what to print on standard output. Offline commands run on this thread;
/// the others on a multi-threaded tokio runtime (Zenoh needs one).
pub fn run(cli: Cli) -> Result<String, DmpctlError> {
    match (&cli.command, &cli.server) {
        (Command::Scenario(ScenarioCommand::Run { file, out, allow_collision, .. }), None) => {
            offline_run(file, out, *allow_collision)
        }
        (Command::Scenario(ScenarioCommand::Bench { file, repeat }), _) => bench(file, *repeat),
        (command, _) => {
            let mut builder = tokio::runtime::Builder::new_multi_thread();
            if let Command::Load(a) = command {
                // Checked with the other flags once running; the runtime needs at least one.
                builder.worker_threads(a.threads.max(1));
            }
            builder
                .enable_all()
                .build()
                .map_err(|source| DmpctlError::Io { path: PathBuf::from("(tokio runtime)"), source })?
                .block_on(run_async(cli))
        }
    }
}

/// Runs a parsed command line inside a multi-threaded tokio runtime.
pub async fn run_async(cli: Cli) -> Result<String, DmpctlError> {
    // On the heap: the commands' futures together are larger than a test thread's or a worker's stack allows in
    // a debug build.
    Box::pin(dispatch(cli)).await
}

async fn dispatch(cli: Cli) -> Result<String, DmpctlError> {
    let options =
        cli.connect.options(std::env::var(TOKEN_ENV).ok(), |w| eprintln!("dmpctl: warning: {w}"))?;
    let default_server = if options.tls.is_some() { "https://127.0.0.1:50051" } else { DEFAULT_SERVER };
    let server = resolve_server(&cli, default_server).await;
    let result = Box::pin(dispatch_to(&cli, &server, &options)).await;
    match result {
        Err(DmpctlError::Client(e)) if e.is_transport_failure() => match https_hint(&server).await {
            Some(hint) => Err(DmpctlError::Client(ClientError::Connect { url: server, message: hint })),
            None => Err(DmpctlError::Client(e)),
        },
        other => other,
    }
}

/// Runs the command against `server`.
async fn dispatch_to(
    cli: &Cli,
    server: &str,
    options: &dmp_client::connect::ConnectOptions,
) -> Result<String, DmpctlError> {
    let server = server.to_string();
    // Local inputs first: a bad file is refused before the server is asked anything.
    let obstacles = match &cli.command {
        Command::Scene(SceneCommand::Put { file, ttl, .. }) => server_commands::read_obstacles(file, *ttl)?,
        _ => Vec::new(),
    };
    let place = resolve_place(cli, &server, options).await?;
    let zenoh = ZenohArgs {
        cell: place.zenoh_cell().to_owned(),
        connect: place.zenoh_connect.clone(),
        config_file: cli.zenoh_config.clone(),
    };
    let connect = || async {
        Ok::<_, DmpctlError>(DmpClient::connect_with(&server, options).await?.with_cell(place.grpc_cell()))
    };
    match &cli.command {
        Command::Scenario(ScenarioCommand::Run { file, out, allow_collision, keep }) => match &cli.server {
            None => offline_run(file, out, *allow_collision),
            Some(url) => {
                let client = connect().await?;
                // The robots to clean up after Ctrl-C (an unreadable file stores nothing).
                let robots = load_scenario(file).map(|s| robot_ids(&s)).unwrap_or_default();
                let clean_up = async {
                    let n = scenario_through_server::clean_up(&client, &robots).await?;
                    Ok(tools::deleted(n, &robots))
                };
                let run = run_scenario_through_server(&client, file, out, *keep);
                let progress = Progress::new(format!("scenario run {}", file.display()));
                let n = plural(robots.len(), "robot");
                let status = || format!("{n} through {url}");
                let summary = until_interrupted(run, (!keep).then_some(clean_up), &progress, status).await?;
                for n in &summary.notes {
                    eprintln!("dmpctl: note: {n}");
                }
                let line = format!("{} (through {url})", summary_line(file, &summary, out));
                gate(line, scenario_problems(&summary, *allow_collision))
            }
        },
        Command::Scenario(ScenarioCommand::Bench { file, repeat }) => bench(file, *repeat),
        // Boxed, as the other large commands: one future per command, not the largest of all on the stack.
        Command::Learn(a) => Box::pin(server_commands::learn(&connect().await?, a)).await,
        Command::Robots => server_commands::robots(&connect().await?).await,
        Command::List { robot } => server_commands::list(&connect().await?, robot).await,
        Command::Show { robot, name, version } => {
            server_commands::show(&connect().await?, robot, name, *version).await
        }
        Command::Delete { robot, name } => server_commands::delete(&connect().await?, robot, name).await,
        Command::Plan(a) => server_commands::plan(&connect().await?, a).await,
        Command::Stream(a) => server_commands::stream(&connect().await?, a).await,
        Command::Scene(SceneCommand::Put { via, wait, .. }) => {
            server_commands::scene_put(connect, &zenoh, &obstacles, *via, *wait).await
        }
        Command::Scene(SceneCommand::Delete { id, via }) => {
            server_commands::scene_delete(connect, &zenoh, id, *via).await
        }
        Command::Info => Ok(to_json(&server_info::info_json(&connect().await?.info().await?))),
        Command::Stats => Ok(to_json(&server_info::stats_json(&connect().await?.stats().await?))),
        Command::Health => server_info::health(&connect().await?).await,
        Command::Scene(SceneCommand::List) => server_commands::scene_list(&connect().await?).await,
        Command::Robot(RobotCommand::Put { id, limits, footprint, tool }) => {
            // Local inputs first: a bad file is refused before the server is asked anything.
            let limits = limits.as_deref().map(robot_commands::read_limits).transpose()?;
            let tool = tool.as_deref().map(robot_commands::read_tool).transpose()?;
            let record =
                robot_commands::record(id, limits.as_ref(), footprint.as_ref().map(|f| &f.0[..]), tool);
            robot_commands::put(&connect().await?, record).await
        }
        Command::Robot(RobotCommand::Show { id }) => robot_commands::show(&connect().await?, id).await,
        Command::Robot(RobotCommand::Delete { id }) => robot_commands::delete(&connect().await?, id).await,
        Command::Load(a) => {
            let run = async { Ok(dmp_sim::load::run_with(a, &server, &place.zenoh_connect, options).await?) };
            let clean_up = async {
                dmp_sim::load::clean_up(a, &server, &place.zenoh_connect, options).await?;
                Ok("deleted the robots' primitives and the cells' fixed obstacles".to_string())
            };
            let progress = Progress::new("load");
            let status = || format!("{} streaming", plural(a.robots, "robot"));
            let report = until_interrupted(run, (!a.keep).then_some(clean_up), &progress, status).await?;
            Ok(to_json(&report))
        }
        Command::Sim(a) => {
            let zenoh_config = cli.zenoh_config.as_deref();
            let cell = place.zenoh_cell();
            let run = async {
                let sim =
                    dmp_sim::robots::run_sim(a, &server, options, cell, &place.zenoh_connect, zenoh_config);
                Ok(sim.await?)
            };
            let clean_up = async {
                let n = dmp_sim::robots::clean_up(&connect().await?.with_cell(cell), a.name).await?;
                Ok(tools::deleted(n, &a.name.robot_ids()))
            };
            let progress = Progress::new(format!("sim {}", a.name.as_str()));
            let robots = plural(a.name.robot_ids().len(), "robot");
            let status = || format!("{robots}, {}", plural(segments_read() as usize, "segment"));
            let report = until_interrupted(run, (!a.keep).then_some(clean_up), &progress, status).await?;
            let mut problems = report.problems_allowing(a.allow_collision);
            // Late setpoints fail the run too (a real robot would have executed stale ones).
            for (id, r) in &report.robots {
                if r.late_setpoints > 0 {
                    problems.push(format!("{id}: {} late setpoints", r.late_setpoints));
                }
            }
            let (robots, runs) = report.robots_and_runs();
            let line = format!(
                "{}: {}, {}, collision: {}, {}; wrote {}",
                report.sim,
                plural(robots, "robot"),
                plural(runs, "run"),
                report.collision,
                if problems.is_empty() { "no problem".to_string() } else { problems.join("; ") },
                a.out.display()
            );
            gate(line, problems)
        }
    }
}

/// `1 robot`, `3 robots`.
fn plural(n: usize, what: &str) -> String {
    format!("{n} {what}{}", if n == 1 { "" } else { "s" })
}

fn summary_line(file: &Path, summary: &RunSummary, out: &Path) -> String {
    let m = &summary.metrics;
    format!(
        "{}: {} steps in {:.3} s, collision: {}, eps_max {:.4}, final goal distance {:.2e}; wrote {}",
        file.display(),
        m.steps,
        m.compute_seconds,
        m.collision,
        m.eps_max,
        m.final_goal_distance,
        out.display()
    )
}

fn offline_run(file: &Path, out: &Path, allow_collision: bool) -> Result<String, DmpctlError> {
    let progress = Progress::new(format!("scenario run {}", file.display()));
    progress.set_message("rolling out");
    let summary = run_scenario(file, out);
    drop(progress);
    let summary = summary?;
    gate(summary_line(file, &summary, out), scenario_problems(&summary, allow_collision))
}

/// What went wrong in a scenario run that completed: a collision (unless allowed), a stall, non-finite values, or
/// a goal not reached (within 1 cm, `time_to_goal`).
fn scenario_problems(summary: &RunSummary, allow_collision: bool) -> Vec<String> {
    let m = &summary.metrics;
    let mut problems = Vec::new();
    if m.collision && !allow_collision {
        problems.push("collision (--allow-collision if it is meant to)".to_string());
    }
    for s in &m.stalls {
        problems
            .push(format!("{} stalled at t = {:.3} s, {:.3} m from its goal", s.robot, s.since, s.distance));
    }
    if !m.finite {
        problems.push("non-finite values in the trajectory".into());
    }
    if m.time_to_goal.is_none() {
        problems.push(format!("goal not reached ({:.3e} m away at the end)", m.final_goal_distance));
    }
    problems
}

/// `line` when nothing went wrong, else [`DmpctlError::Problems`] (exit code 3).
fn gate(line: String, problems: Vec<String>) -> Result<String, DmpctlError> {
    if problems.is_empty() { Ok(line) } else { Err(DmpctlError::Problems { summary: line, problems }) }
}

fn bench(file: &Path, repeat: usize) -> Result<String, DmpctlError> {
    let progress = Progress::new(format!("scenario bench {}", file.display()));
    progress.set_message(format!("{} timed rollouts", repeat));
    let report = bench_scenario(file, repeat);
    drop(progress);
    let report = report?;
    Ok(serde_json::to_string(&report).unwrap_or_else(|_| to_json(&report)))
}

#[cfg(test)]
mod tests;
