//! The figure of a motion the server planned or streamed (`plan`, `stream`): `plot.svg` beside `trajectory.csv`,
//! with the obstacle-free plan of the same motion, the cell's obstacles (their true shapes, their safety margins and
//! the isopotentials the server avoids), the limits in force and, for a stream, the scene versions as events; and
//! beside it what the run reported of them ([`RunRecord::write`]).

use std::path::Path;

use dmp::Trajectory;
use dmp_client::DmpClient;
use dmp_client::setpoints::Setpoints;
use dmp_plot::{PlotInput, Solid, SolidShape, render_svg_with};
use dmp_proto::avoidance::avoidance_to_proto;
use dmp_proto::obstacle::obstacle_to_engine;
use dmp_proto::v1;

use crate::args::MotionArgs;
use crate::error::DmpctlError;
use crate::outputs::write_file;
use crate::run_record::RunRecord;

/// The true shape of a scene obstacle: its solid, or its superquadric without the margin.
fn true_shape(o: &v1::Obstacle) -> Option<Solid> {
    use v1::obstacle::Shape as S;
    use v1::solid_primitive::Type;
    let shape = match &o.shape {
        Some(S::Solid(s)) => match (Type::try_from(s.r#type).ok()?, s.dimensions.as_slice()) {
            (Type::Box, [x, y, z]) => SolidShape::Box { half: vec![x / 2.0, y / 2.0, z / 2.0] },
            (Type::Sphere, [r]) => SolidShape::Ball { radius: *r },
            (Type::Cylinder, [h, r]) => SolidShape::CylinderZ { radius: *r, half_height: h / 2.0 },
            _ => return None,
        },
        _ => SolidShape::Superquadric(obstacle_to_engine(&v1::Obstacle { margin: 0.0, ..o.clone() }).ok()?),
    };
    let mut s = Solid::new(o.id.clone(), shape, o.center.clone());
    s.velocity = o.velocity.clone();
    Some(s)
}

/// Writes `out/plot.svg` of `traj`, executed for `motion` with step `dt`, and what `record` holds of the limits and
/// clearances (`limits.json`, `clearance.csv`). What fails here is a warning on stderr: the trajectory is already
/// written.
pub(crate) async fn write_plot(
    client: &DmpClient,
    motion: &MotionArgs,
    what: &str,
    traj: &Trajectory,
    dt: f64,
    record: &RunRecord,
    out: &Path,
) {
    if let Err(e) = record.write(out) {
        eprintln!("warning: the limits and clearances not written: {e}");
    }
    if let Err(e) = try_write_plot(client, motion, what, traj, dt, record, out).await {
        eprintln!("warning: plot.svg not written: {e}");
    }
}

async fn try_write_plot(
    client: &DmpClient,
    motion: &MotionArgs,
    what: &str,
    traj: &Trajectory,
    dt: f64,
    record: &RunRecord,
    out: &Path,
) -> Result<(), DmpctlError> {
    let mut spec = motion.spec();
    spec.avoidance = Some(avoidance_to_proto(&dmp::Avoidance::NONE, 0));
    spec.ignore_scene = true;
    let duration = traj.t.last().copied().unwrap_or(0.0) - traj.t.first().copied().unwrap_or(0.0);
    let plan = client.plan(v1::PlanRequest { motion: Some(spec), dt, duration: duration.max(dt) }).await?;
    let seg =
        plan.trajectory.ok_or_else(|| DmpctlError::protocol("the free plan has no trajectory".into()))?;
    let mut s = Setpoints::new();
    s.push(&seg)?;
    let free = s.into_trajectory();
    let scene = if motion.ignore_scene { Vec::new() } else { client.list_obstacles().await?.obstacles };
    let scene: Vec<&v1::Obstacle> = scene.iter().filter(|o| o.center.len() == traj.dim()).collect();
    let obstacles: Vec<dmp::Obstacle> = scene.iter().filter_map(|o| obstacle_to_engine(o).ok()).collect();
    let solids: Vec<Solid> = scene.iter().filter_map(|o| true_shape(o)).collect();
    let method = motion.avoidance.as_ref().map_or("", |a| a.method.name());
    let title = format!("{}/{}: {what}", motion.robot, motion.name);
    let goal = motion.goal.as_ref().map(|g| g.0.clone());
    let safety = record.safety(&scene);
    let svg = render_svg_with(
        &PlotInput {
            title: &title,
            demonstration: &[],
            demonstration_t: None,
            free: &free,
            adapted: traj,
            goal: goal.as_deref(),
            obstacles: &obstacles,
            robots: &[],
            obstacle_time: f64::NAN,
            // Every obstacle's true shape, or none: a missing one would be taken for its isopotential.
            solids: if solids.len() == obstacles.len() { &solids } else { &[] },
            method,
            clearance: None,
            events: &record.events,
            pose: None,
        },
        &safety,
    )?;
    write_file(out, "plot.svg", svg.as_bytes())
}
