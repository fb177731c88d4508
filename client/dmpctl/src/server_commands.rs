//! The commands of `dmpctl` that talk to the server (gRPC, or Zenoh for `scene --via zenoh`); each returns what to
//! print on standard output. Argument types are the `args` module's.

use std::path::Path;
use std::time::Duration;

use dmp_client::grpc::{DmpClient, SessionSender, record_primitive};
use dmp_client::setpoints::Setpoints;
use dmp_client::zenoh_pub::ObstaclePublisher;
use dmp_proto::keys::obstacle_key;
use dmp_proto::learning::learn_parameters_to_proto;
use dmp_proto::obstacle_json::{JsonObstacle, obstacle_to_json};
use dmp_proto::v1;
use serde_json::{Value, json};

use crate::args::{LearnArgs, LearnSource, PlanArgs, StreamArgs, Via};
use crate::demo_csv::load_demonstration_csv;
use crate::error::DmpctlError;
use crate::outputs::{to_json, trajectory_csv, write_file};
use crate::primitive_json::record_json;
use crate::scenario_file::load_scenario;
use crate::scene_confirm::Confirmation;
use crate::server_info::print_warnings;
use crate::stream_controls::{Command, Schedule, read_stdin};

/// How long `scene ... --via zenoh` waits for the server's subscriber.
pub(crate) const ZENOH_SUBSCRIBER_WAIT: Duration = Duration::from_secs(5);

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> DmpctlError + '_ {
    move |source| DmpctlError::Io { path: path.to_path_buf(), source }
}

/// `learn`: one demonstration (a scenario's, or a CSV file's) to the next version of `(robot, name)`.
pub(crate) async fn learn(client: &DmpClient, a: &LearnArgs) -> Result<String, DmpctlError> {
    let (t, x, q, mut params) = match &a.source {
        LearnSource { scenario: Some(path), .. } => {
            let s = load_scenario(path)?;
            (s.demonstration.t, s.demonstration.x, s.demonstration.q, learn_parameters_to_proto(&s.dmp))
        }
        LearnSource { csv: Some(path), .. } => {
            let d = load_demonstration_csv(path)?;
            (d.t, d.x, d.q, v1::LearnParameters::default())
        }
        _ => return Err(DmpctlError::argument("--scenario / --csv", "give one of them")),
    };
    if let Some(n) = a.n_basis {
        params.n_basis = n;
    }
    if let Some(k) = &a.k {
        params.k = k.0.clone();
    }
    if let Some(d) = &a.d {
        params.d = d.0.clone();
    }
    if let Some(alpha) = a.alpha {
        params.alpha = alpha;
    }
    let samples = t.len();
    let r = client.learn_pose(&a.robot, &a.name, &t, &x, &q, params).await?;
    let p = record_primitive(&r)?;
    let n = p.position_dim();
    let mut out = json!({
        "robot_id": r.robot_id,
        "name": r.name,
        "version": r.version,
        "samples": samples,
        "dim": n,
        "n_basis": p.n_basis,
        "tau": p.tau,
        "start": p.start[..n],
        "goal": p.goal[..n],
    });
    if let (Some(chart), Some(o)) = (dmp::orientation::pose::chart_of(&p).ok().flatten(), out.as_object_mut())
    {
        let q = |v: &[f64]| {
            let y = nalgebra::Vector3::from_column_slice(&v[n..]);
            dmp::orientation::quaternion::to_xyzw(&dmp::orientation::pose::from_chart(&chart, &y))
        };
        o.insert("start_orientation".into(), json!(q(&p.start)));
        o.insert("goal_orientation".into(), json!(q(&p.goal)));
    }
    Ok(to_json(&out))
}

/// `list`: one line per primitive of the robot.
pub(crate) async fn list(client: &DmpClient, robot: &str) -> Result<String, DmpctlError> {
    let records = client.list(robot).await?;
    if records.is_empty() {
        return Ok(format!("robot `{robot}` has no primitives"));
    }
    let lines: Vec<String> = records
        .iter()
        .map(|r| {
            let (dim, n, tau) = r.primitive.as_ref().map_or((0, 0, 0.0), |p| (p.dim, p.n_basis, p.tau));
            format!(
                "{}\tv{}\tdim {dim}\tN {n}\ttau {tau} s\tcreated {}",
                r.name,
                r.version,
                readable_time(r.created_unix_ms.max(0) as u64)
            )
        })
        .collect();
    Ok(lines.join("\n"))
}

/// `robots`: one line per robot that has primitives (`sim.panda  2 primitives  updated 2026-11-26T06:51:00Z`).
pub(crate) async fn robots(client: &DmpClient) -> Result<String, DmpctlError> {
    let robots = client.list_robots().await?;
    if robots.is_empty() {
        return Ok("no robot has primitives (that this client may read)".into());
    }
    let width = robots.iter().map(|r| r.robot_id.len()).max().unwrap_or(0);
    let lines: Vec<String> = robots
        .iter()
        .map(|r| {
            let n = format!("{} primitive{}", r.primitives, if r.primitives == 1 { "" } else { "s" });
            let updated = readable_time(r.updated_unix_ms.max(0) as u64);
            format!("{:width$}  {n:>14}  updated {updated}", r.robot_id)
        })
        .collect();
    Ok(lines.join("\n"))
}

/// A time in Unix milliseconds as RFC 3339 UTC, to the second (`2026-11-26T06:51:00Z`).
pub(crate) fn readable_time(unix_ms: u64) -> String {
    let t = std::time::UNIX_EPOCH + Duration::from_millis(unix_ms);
    humantime::format_rfc3339_seconds(t).to_string()
}

/// `show`: the record as JSON (the primitive in the engine's serde form).
pub(crate) async fn show(
    client: &DmpClient,
    robot: &str,
    name: &str,
    version: u64,
) -> Result<String, DmpctlError> {
    Ok(to_json(&record_json(&client.get(robot, name, version).await?)?))
}

/// `delete`: every version of `(robot, name)`.
pub(crate) async fn delete(client: &DmpClient, robot: &str, name: &str) -> Result<String, DmpctlError> {
    let n = client.delete(robot, name).await?;
    Ok(format!("deleted {n} version{} of {robot}/{name}", if n == 1 { "" } else { "s" }))
}

/// `plan`: the whole trajectory, written to `DIR/trajectory.csv`, and its figure to `DIR/plot.svg`.
pub(crate) async fn plan(client: &DmpClient, a: &PlanArgs) -> Result<String, DmpctlError> {
    let request = v1::PlanRequest {
        motion: Some(a.motion.spec()),
        dt: a.dt.unwrap_or(0.0),
        duration: a.duration.unwrap_or(0.0),
    };
    let r = client.plan(request).await?;
    let stale = r.trajectory.as_ref().is_some_and(|t| t.scene_stale);
    print_warnings(&r.warnings, stale, &mut false);
    let seg = r.trajectory.ok_or_else(|| DmpctlError::protocol("the plan has no trajectory".into()))?;
    let mut s = Setpoints::new();
    s.push(&seg)?;
    let traj = s.trajectory().ok_or_else(|| DmpctlError::protocol("the plan has no points".into()))?;
    write_file(&a.out, "trajectory.csv", trajectory_csv(traj).as_bytes())?;
    let record = crate::run_record::RunRecord::plan(&seg, r.limits.as_ref());
    crate::server_plot::write_plot(client, &a.motion, "plan", traj, seg.dt, &record, &a.out).await;
    let collisions = if r.collisions.is_empty() { "none".to_string() } else { r.collisions.join(", ") };
    let verdict = r.verdict.as_ref();
    let mut warnings = crate::warning_tally::WarningTally::default();
    warnings.add(&r.warnings);
    let line = format!(
        "{}/{}: {} points over {} s (dt {}), scene version {}, collisions: {collisions}, stalled: {}, warnings: {}, \
         {}, {}; wrote {}",
        a.motion.robot,
        a.motion.name,
        traj.len(),
        traj.t.last().copied().unwrap_or(0.0),
        seg.dt,
        seg.scene_version,
        r.stalled,
        warnings.words(),
        verdict_words(verdict),
        limits_words(record.limits.as_ref()),
        a.out.join("trajectory.csv").display()
    );
    let mut problems = verdict_problems(verdict, a.allow_collision);
    if verdict.is_none() && !r.collisions.is_empty() && !a.allow_collision {
        problems.push(format!("collision with {collisions} (--allow-collision if it is meant to)"));
    }
    gate(line, problems)
}

/// The outcome's name without its prefix (`GOAL_REACHED`).
fn outcome_name(v: &v1::Verdict) -> &'static str {
    let name = v1::Outcome::try_from(v.outcome).map_or("UNKNOWN", |o| o.as_str_name());
    name.strip_prefix("OUTCOME_").unwrap_or(name)
}

/// The verdict in the summary line: `verdict GOAL_REACHED (reached the goal ...)`.
fn verdict_words(v: Option<&v1::Verdict>) -> String {
    match v {
        Some(v) => format!("verdict {} ({})", outcome_name(v), v.reason),
        None => "no verdict".to_string(),
    }
}

/// The limits in force in the summary line: `limits (server default): 1 m/s, 5 m/s^2, ..., margin 0.01 m`, a field
/// without a limit as `no max_jerk`.
fn limits_words(l: Option<&v1::LimitsInForce>) -> String {
    let Some(l) = l else { return "limits in force not reported".to_string() };
    let b = l.limits.unwrap_or_default();
    let fields = [
        ("max_speed", b.max_speed, "m/s"),
        ("max_acceleration", b.max_acceleration, "m/s^2"),
        ("max_jerk", b.max_jerk, "m/s^3"),
        ("max_angular_speed", b.max_angular_speed, "rad/s"),
        ("max_angular_acceleration", b.max_angular_acceleration, "rad/s^2"),
        ("max_angular_jerk", b.max_angular_jerk, "rad/s^3"),
    ];
    let bounds: Vec<String> = fields
        .iter()
        .map(|(name, v, unit)| if *v > 0.0 { format!("{v} {unit}") } else { format!("no {name}") })
        .collect();
    let margin = if l.margin > 0.0 { format!("margin {} m", l.margin) } else { "no margin".to_string() };
    format!("limits ({}): {}, {margin}", l.profile, bounds.join(", "))
}

/// What is wrong with a run that ended with verdict `v`, as `scenario run` and `sim` judge theirs: a collision
/// (unless `allow_collision`), or any ending but the goal reached: a stall, a missed goal, a braking stop, a run
/// blocked or out of time. No verdict at all is a problem too (the run's end is unknown).
fn verdict_problems(v: Option<&v1::Verdict>, allow_collision: bool) -> Vec<String> {
    let Some(v) = v else {
        return vec!["the run ended without a verdict (the server did not say how it ended)".to_string()];
    };
    let outcome = v1::Outcome::try_from(v.outcome).unwrap_or(v1::Outcome::Unspecified);
    let mut problems = Vec::new();
    if !v.collisions.is_empty() || outcome == v1::Outcome::Collision {
        if !allow_collision {
            problems.push(format!("{} (--allow-collision if it is meant to)", v.reason));
        }
        if !v.goal_reached {
            problems.push(format!(
                "goal not reached ({:.3e} m away at the end{})",
                v.goal_distance,
                angle_words(v)
            ));
        }
    } else if outcome != v1::Outcome::GoalReached || !v.goal_reached {
        problems.push(format!("goal not reached: {} ({})", v.reason, outcome_name(v)));
    }
    problems
}

/// `, 1.2° from the goal orientation` for a pose run, else nothing.
fn angle_words(v: &v1::Verdict) -> String {
    if v.goal_angle > 0.0 {
        format!(", {:.3}° from the goal orientation", v.goal_angle.to_degrees())
    } else {
        String::new()
    }
}

/// `line` when nothing went wrong, else [`DmpctlError::Problems`] (exit code 3, the problems on stderr).
fn gate(line: String, problems: Vec<String>) -> Result<String, DmpctlError> {
    if problems.is_empty() { Ok(line) } else { Err(DmpctlError::Problems { summary: line, problems }) }
}

/// Real time: the rows of `seg` whose time had passed on the wall clock when it arrived (a robot would have
/// executed older setpoints in their place), as `sim` counts them.
fn late_rows(seg: &v1::Segment, now_unix_s: f64) -> usize {
    if seg.start_unix_s <= 0.0 || seg.dim == 0 {
        return 0;
    }
    let rows = seg.positions.len() / seg.dim as usize;
    (0..rows).filter(|&k| seg.start_unix_s + k as f64 * seg.dt < now_unix_s).count()
}

/// The status name of a segment.
pub(crate) fn status_name(seg: &v1::Segment) -> &'static str {
    v1::SegmentStatus::try_from(seg.status).map_or("UNKNOWN", |s| s.as_str_name())
}

/// The stderr line of a segment.
pub(crate) fn segment_line(seg: &v1::Segment) -> String {
    let points = if seg.dim == 0 { 0 } else { seg.positions.len() / seg.dim as usize };
    format!(
        "segment {} t {:.4} s points {} status {} scene_version {}",
        seg.sequence,
        seg.start_time,
        points,
        status_name(seg),
        seg.scene_version
    )
}

/// `stream`: executes, prints a line per segment on stderr (unless `--quiet`), writes the setpoints in force to `DIR/trajectory.csv`
/// and their figure to `DIR/plot.svg`.
/// Ctrl-C ends the stream early and still writes what was received.
pub(crate) async fn stream(client: &DmpClient, a: &StreamArgs) -> Result<String, DmpctlError> {
    use tokio_stream::StreamExt;
    let pacing = if a.realtime { v1::Pacing::Realtime } else { v1::Pacing::AsFastAsRead };
    let request = v1::ExecuteRequest {
        motion: Some(a.motion.spec()),
        dt: a.dt.unwrap_or(0.0),
        segment_s: a.segment.unwrap_or(0.0),
        pacing: pacing as i32,
        lookahead_s: a.lookahead.unwrap_or(0.0),
        max_duration_s: a.max_duration.unwrap_or(0.0),
        integration_step_s: 0.0,
        integration_tolerance: 0.0,
        take_over: false,
    };
    let mut schedule = Schedule::new(&a.goal_at, &a.tau_at, a.stop_at);
    // Changes need a session; a stream without any is the plain Execute call.
    let (session, mut segments) = if schedule.is_empty() && !a.stdin {
        (None, client.execute(request).await?)
    } else {
        let (sender, segments) = client.session(request).await?.into_parts();
        (Some(sender), segments)
    };
    let mut typed = if a.stdin { Some(read_stdin()) } else { None };
    let mut stopped = false;
    let mut s = Setpoints::new();
    let mut interrupted = false;
    let mut stale = false;
    let mut arrived = 0.0;
    let mut versions = crate::run_record::RunRecord::default();
    let mut warnings = crate::warning_tally::WarningTally::default();
    let (mut verdict, mut late, mut collision_segments) = (None, 0usize, 0usize);
    let ctrl_c = tokio::signal::ctrl_c();
    tokio::pin!(ctrl_c);
    let progress = crate::progress::Progress::new(format!("stream {}", a.motion.robot));
    loop {
        tokio::select! {
            next = segments.next() => match next {
                None => break,
                Some(seg) => {
                    let seg = seg?;
                    late += late_rows(&seg, unix_now());
                    if !a.quiet {
                        progress.println(&segment_line(&seg));
                    }
                    warnings.add(&seg.warnings);
                    if seg.status == v1::SegmentStatus::Collision as i32 {
                        collision_segments += 1;
                    }
                    if seg.verdict.is_some() {
                        // A later one supersedes it (real time: a change after the run had ended).
                        verdict = seg.verdict.clone();
                    }
                    progress.tick(format!("{} segments, t = {:.3} s", s.segments() + 1, seg.start_time));
                    print_warnings(&seg.warnings, seg.scene_stale, &mut stale);
                    arrived = seg.goal_reached_time;
                    s.push(&seg)?;
                    versions.see(&seg);
                    if let Some(session) = &session {
                        for (at, c) in schedule.due(seg.start_time) {
                            progress.println(&format!("dmpctl: at t = {at} s (segment at {:.4} s): {}", seg.start_time, c.words()));
                            stopped |= c == Command::Stop;
                            send_command(session, &c).await;
                        }
                    }
                }
            },
            Some(c) = async { typed.as_mut()?.recv().await }, if typed.is_some() => {
                if let Some(session) = &session {
                    progress.println(&format!("dmpctl: from stdin: {}", c.words()));
                    stopped |= c == Command::Stop;
                    send_command(session, &c).await;
                }
            }
            _ = &mut ctrl_c => {
                interrupted = true;
                break;
            }
        }
    }
    drop(segments);
    drop(session);
    let status = match s.last_status() {
        None => "none".to_string(),
        Some(v1::SegmentStatus::GoalReached) => {
            format!("GOAL_REACHED (at the goal and at rest since t = {arrived} s)")
        }
        Some(st) => st.as_str_name().to_string(),
    };
    let n = s.segments();
    let traj = s.into_trajectory();
    if traj.is_empty() {
        return Err(DmpctlError::protocol(format!("the stream ended after {n} segments without any point")));
    }
    write_file(&a.out, "trajectory.csv", trajectory_csv(&traj).as_bytes())?;
    let dt = a.dt.unwrap_or(if traj.len() > 1 { traj.t[1] - traj.t[0] } else { 1e-3 });
    crate::server_plot::write_plot(client, &a.motion, "stream", &traj, dt, &versions, &a.out).await;
    let collisions = match verdict.as_ref().map(|v| v.collisions.join(", ")) {
        Some(c) if !c.is_empty() => c,
        _ if collision_segments > 0 => "yes".to_string(),
        _ => "none".to_string(),
    };
    let line = format!(
        "{}/{}: {n} segments{}, {} setpoints in force up to t = {} s, last status {status}, collisions: \
         {collisions} ({collision_segments} COLLISION segments), warnings: {}, late setpoints: {late}, {}, {}; \
         wrote {}",
        a.motion.robot,
        a.motion.name,
        if interrupted { " (interrupted)" } else { "" },
        traj.len(),
        traj.t.last().copied().unwrap_or(0.0),
        warnings.words(),
        verdict_words(verdict.as_ref()),
        limits_words(versions.limits.as_ref()),
        a.out.join("trajectory.csv").display()
    );
    // Ctrl-C and a stop command are stops the user asked for: how the run would have ended is not judged, what it
    // did is.
    let asked_to_stop = stopped
        && verdict
            .as_ref()
            .is_some_and(|v| v.outcome == v1::Outcome::Stopped as i32 && v.collisions.is_empty());
    let mut problems = if interrupted || asked_to_stop {
        Vec::new()
    } else {
        verdict_problems(verdict.as_ref(), a.allow_collision)
    };
    if (interrupted || verdict.is_none()) && collision_segments > 0 && !a.allow_collision {
        problems.push(format!(
            "{collision_segments} segments in COLLISION (--allow-collision if it is meant to)"
        ));
    }
    if late > 0 {
        problems.push(format!("{late} late setpoints"));
    }
    gate(line, problems)
}

/// Sends a change to the running stream; one that cannot be sent (the run has just ended) is said on stderr.
async fn send_command(session: &SessionSender, c: &Command) {
    if let Err(e) = c.send(session).await {
        eprintln!("dmpctl: `{}` not sent: {e}", c.words());
    }
}

/// The wall clock, Unix seconds.
fn unix_now() -> f64 {
    std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0.0, |d| d.as_secs_f64())
}

/// Reads the obstacles of `path`: one JSON obstacle, or a file (e.g. a scenario) whose `obstacles` are all taken.
/// Every obstacle is validated with the engine; `ttl_s` replaces each one's time to live. Errors name the file and
/// the field.
pub(crate) fn read_obstacles(path: &Path, ttl_s: Option<f64>) -> Result<Vec<JsonObstacle>, DmpctlError> {
    let text = std::fs::read_to_string(path).map_err(io(path))?;
    crate::obstacle_file::obstacles_of(&text, path, ttl_s)
}

/// Zenoh settings of the command line.
#[derive(Debug, Clone)]
pub(crate) struct ZenohArgs {
    /// The cell.
    pub(crate) cell: String,
    /// Endpoints to connect to.
    pub(crate) connect: Vec<String>,
    /// A stock Zenoh configuration file to open the session with (TLS, credentials).
    pub(crate) config_file: Option<std::path::PathBuf>,
}

async fn publisher(z: &ZenohArgs) -> Result<ObstaclePublisher, DmpctlError> {
    let p = match &z.config_file {
        Some(file) => ObstaclePublisher::open_from_file(&z.cell, file, &z.connect).await?,
        None => ObstaclePublisher::open(&z.cell, &z.connect, &[]).await?,
    };
    p.wait_for_subscriber(ZENOH_SUBSCRIBER_WAIT).await?;
    Ok(p)
}

/// `scene put FILE`, with the file's obstacles read and checked ([`read_obstacles`]).
pub(crate) async fn scene_put<F: Future<Output = Result<DmpClient, DmpctlError>>>(
    connect: impl FnOnce() -> F,
    z: &ZenohArgs,
    obstacles: &[JsonObstacle],
    via: Via,
    wait_s: f64,
) -> Result<String, DmpctlError> {
    let mut lines = Vec::with_capacity(obstacles.len());
    match via {
        Via::Grpc => {
            let client = connect().await?;
            for o in obstacles {
                let c = client.put_obstacle(o.to_proto()).await?;
                lines.push(format!("put `{}`: scene version {}", o.spec.id, c.scene_version));
            }
        }
        Via::Zenoh => {
            // The watch opens first: a change that comes before it was open would be missed.
            let confirmation = if wait_s > 0.0 {
                let wait = Duration::try_from_secs_f64(wait_s)
                    .map_err(|_| DmpctlError::argument("--wait-s", "too long"))?;
                Some(Confirmation::open(connect().await?, wait).await?)
            } else {
                None
            };
            let p = publisher(z).await?;
            for o in obstacles {
                p.put_obstacle(o).await?;
                lines.push(format!("published `{}` on {}", o.spec.id, obstacle_key(&z.cell, &o.spec.id)));
            }
            if let Some(c) = confirmation {
                let version = c.wait(obstacles).await;
                p.close().await?;
                lines.push(format!("the server's scene shows them: scene version {}", version?));
            } else {
                p.close().await?;
            }
        }
    }
    Ok(lines.join("\n"))
}

/// `scene delete ID`.
pub(crate) async fn scene_delete<F: Future<Output = Result<DmpClient, DmpctlError>>>(
    connect: impl FnOnce() -> F,
    z: &ZenohArgs,
    id: &str,
    via: Via,
) -> Result<String, DmpctlError> {
    match via {
        Via::Grpc => {
            let c = connect().await?.delete_obstacle(id).await?;
            Ok(if c.changed {
                format!("deleted `{id}`: scene version {}", c.scene_version)
            } else {
                format!("no obstacle `{id}` in the scene (version {})", c.scene_version)
            })
        }
        Via::Zenoh => {
            let p = publisher(z).await?;
            p.delete(id).await?;
            p.close().await?;
            Ok(format!("published the deletion of {}", obstacle_key(&z.cell, id)))
        }
    }
}

/// `scene list`: the scene as JSON.
pub(crate) async fn scene_list(client: &DmpClient) -> Result<String, DmpctlError> {
    let s = client.list_obstacles().await?;
    let obstacles: Vec<Value> = s.obstacles.iter().map(obstacle_to_json).collect();
    Ok(to_json(&json!({"scene_version": s.scene_version, "obstacles": obstacles})))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::server_info::warning_line;

    #[test]
    fn times_read_as_rfc_3339() {
        assert_eq!(readable_time(0), "1970-01-01T00:00:00Z");
        assert_eq!(readable_time(1_795_000_000_123), "2026-11-18T11:06:40Z");
    }

    #[test]
    fn a_warning_reads_as_its_kind_obstacle_field_and_reason() {
        let w = v1::Warning {
            kind: v1::warning::Kind::ObstacleIgnored as i32,
            field: "superquadric.exponents[0]".into(),
            reason: "too large for this robot".into(),
            obstacle_id: "crate".into(),
        };
        assert_eq!(
            warning_line(&w),
            "warning: OBSTACLE_IGNORED (obstacle `crate`) superquadric.exponents[0]: too large for this robot"
        );
    }

    fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn obstacle_files_hold_one_obstacle_or_a_list() {
        let dir = tempfile::tempdir().unwrap();
        let one = write(
            dir.path(),
            "one.json",
            r#"{"id": "a", "center": [0, 0], "semi_axes": [1, 1], "ttl_s": 3}"#,
        );
        let o = read_obstacles(&one, None).unwrap();
        assert_eq!((o.len(), o[0].ttl_s), (1, 3.0));
        assert_eq!(read_obstacles(&one, Some(0.5)).unwrap()[0].ttl_s, 0.5);
        let scenario = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../scenarios/paper-one-obstacle/static_point.json");
        let o = read_obstacles(&scenario, None).unwrap();
        assert!(!o.is_empty());

        let bad = write(
            dir.path(),
            "bad.json",
            r#"{"obstacles": [{"id": "a", "center": [0, 0], "semi_axes": [1, 1]},
                              {"id": "b", "center": [0, 0], "semi_axes": [1, 0]}]}"#,
        );
        let e = read_obstacles(&bad, None).unwrap_err();
        assert!(e.is_bad_input() && e.to_string().contains("obstacles[1].semi_axes[1]"), "{e}");
        let bad =
            write(dir.path(), "bad2.json", r#"{"id": "a", "center": [0, 0], "semi_axes": [1, 1], "ttl": 1}"#);
        let e = read_obstacles(&bad, None).unwrap_err();
        assert!(e.is_bad_input() && e.to_string().contains("ttl"), "{e}");
        let e = read_obstacles(&one, Some(-1.0)).unwrap_err();
        assert!(e.to_string().contains("ttl_s"), "{e}");
        let e = read_obstacles(&dir.path().join("missing.json"), None).unwrap_err();
        assert!(!e.is_bad_input());
    }

    #[test]
    fn segment_lines_name_sequence_status_and_scene_version() {
        let seg = v1::Segment {
            sequence: 7,
            start_time: 0.07,
            dt: 0.001,
            dim: 2,
            positions: vec![0.0; 20],
            status: v1::SegmentStatus::GoalReached as i32,
            scene_version: 3,
            ..Default::default()
        };
        assert_eq!(segment_line(&seg), "segment 7 t 0.0700 s points 10 status GOAL_REACHED scene_version 3");
    }

    #[test]
    fn the_limits_in_force_name_their_profile_and_the_fields_without_a_limit() {
        let l = v1::LimitsInForce {
            limits: Some(v1::Limits {
                max_speed: 1.0,
                max_acceleration: 5.0,
                max_jerk: 0.0,
                max_angular_speed: 2.0,
                max_angular_acceleration: 10.0,
                max_angular_jerk: 100.0,
            }),
            profile: "request + server default".into(),
            unlimited: vec!["max_jerk".into()],
            margin: 0.01,
        };
        assert_eq!(
            limits_words(Some(&l)),
            "limits (request + server default): 1 m/s, 5 m/s^2, no max_jerk, 2 rad/s, 10 rad/s^2, 100 rad/s^3, \
             margin 0.01 m"
        );
        assert_eq!(limits_words(None), "limits in force not reported");
    }
}
