//! The SPEC's metrics of a rollout against its obstacle-free twin.

use std::collections::BTreeMap;

use serde::Serialize;

use crate::distance::signed_distance_world;
use crate::isopotential::Isopotential;
use crate::obstacle::WorldEval;
use crate::rollout::Rollout;
use crate::scenario::Prepared;

/// Distance to the goal under which the goal counts as reached (`time_to_goal`).
pub const GOAL_TOLERANCE: f64 = 0.01;

/// Per-obstacle figures.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ObstacleMetrics {
    /// Smallest isopotential value met.
    #[serde(rename = "min_C")]
    pub min_c: f64,
    /// Smallest signed Euclidean distance to the true surface (negative inside).
    pub min_distance: f64,
    /// Whether any robot entered it.
    pub collision: bool,
}

/// Per-robot figures (scenarios with robots).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RobotMetrics {
    /// Largest deviation from the obstacle-free path.
    pub eps_max: f64,
    /// Largest acceleration norm.
    pub acc_max: f64,
    /// Distance to its goal at the end.
    pub final_goal_distance: f64,
    /// First time within [`GOAL_TOLERANCE`] of its goal.
    pub time_to_goal: Option<f64>,
}

/// Per-pair figures (scenarios with robots).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PairMetrics {
    /// Smallest distance between the two centres.
    pub min_center_distance: f64,
    /// Smallest value of either footprint's isopotential at the other's centre.
    #[serde(rename = "min_C")]
    pub min_c: f64,
    /// Whether a centre entered the other's footprint.
    pub collision: bool,
}

/// A pose scenario's orientation figures.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PoseMetrics {
    /// Angle between the orientation at the end and the goal orientation, degrees.
    pub final_orientation_error_deg: f64,
    /// Largest angle between the orientation and the obstacle-free run's at the same time, degrees: how far the
    /// obstacles (through a held tool) turned the robot.
    pub max_turn_from_free_deg: f64,
    /// Largest angular speed `|ω|`, rad/s.
    pub angular_speed_max: f64,
    /// Largest angular acceleration `|ω̇|`, rad/s².
    pub angular_acc_max: f64,
    /// With a tool: the rows at which a control point was inside an obstacle (inflated by the tool's reach for axis
    /// samples), 0 when the tool kept its distance.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tool_contact_rows: Option<usize>,
    /// With a tool: per obstacle, the smallest clearance of the tool's surface to the obstacle's (negative: inside),
    /// sampled ([`TOOL_SURFACE_SAMPLES`] surface points, every [`TOOL_CLEARANCE_STRIDE`] rows).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tool_min_distance: Option<BTreeMap<String, f64>>,
}

/// Surface samples of a held tool for [`PoseMetrics::tool_min_distance`].
pub const TOOL_SURFACE_SAMPLES: usize = 500;
/// Rows between two measurements of [`PoseMetrics::tool_min_distance`] (and the last row).
pub const TOOL_CLEARANCE_STRIDE: usize = 10;

/// A detected stall.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StallMetrics {
    /// The robot.
    pub robot: String,
    /// When it stopped.
    pub since: f64,
    /// Its distance to the goal.
    pub distance: f64,
}

/// The metrics of `metrics.json` (SPEC.md, "Outputs").
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Metrics {
    /// Number of integration steps.
    pub steps: usize,
    /// Fixed step.
    pub dt: f64,
    /// Physical duration.
    pub duration: f64,
    /// No NaN or infinity anywhere in the trajectory.
    pub finite: bool,
    /// Time spent computing (set by the caller, who owns the clock).
    pub compute_seconds: f64,
    /// Largest `|x_free(t) - x(t)|`.
    pub eps_max: f64,
    /// Mean of the same.
    pub eps_mean: f64,
    /// Largest acceleration norm.
    pub acc_max: f64,
    /// Largest acceleration norm over `t >= 0.1 duration`.
    pub acc_max_after_10pct: f64,
    /// Mean acceleration norm.
    pub acc_mean: f64,
    /// `|x(T) - g|`.
    pub final_goal_distance: f64,
    /// First `t` with `|x - g| <= 0.01`.
    pub time_to_goal: Option<f64>,
    /// Any obstacle or robot pair touched.
    pub collision: bool,
    /// Per obstacle.
    pub obstacles: BTreeMap<String, ObstacleMetrics>,
    /// Per robot, when the scenario has robots.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub robots: Option<BTreeMap<String, RobotMetrics>>,
    /// Per pair `"a-b"`, when the scenario has robots.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub robot_pairs: Option<BTreeMap<String, PairMetrics>>,
    /// Robots that stopped away from their goal (local minima).
    pub stalls: Vec<StallMetrics>,
    /// A pose scenario's orientation figures (the other figures are of the positions).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pose: Option<PoseMetrics>,
}

fn dist(a: &[f64], b: &[f64], dims: &[usize]) -> f64 {
    dims.iter().map(|&i| (a[i] - b[i]).powi(2)).sum::<f64>().sqrt()
}

fn norm(a: &[f64], dims: &[usize]) -> f64 {
    dims.iter().map(|&i| a[i] * a[i]).sum::<f64>().sqrt()
}

/// Deviation, acceleration and goal figures over the dimensions `dims`:
/// `(eps_max, eps_mean, acc_max, acc_max_after_10pct, acc_mean, final_goal_distance, time_to_goal)`.
type Motion7 = (f64, f64, f64, f64, f64, f64, Option<f64>);

fn motion_figures(p: &Prepared, free: &Rollout, adapted: &Rollout, dims: &[usize]) -> Motion7 {
    let (tf, ta) = (&free.trajectory, &adapted.trajectory);
    let n = ta.len();
    let (mut eps_max, mut eps_sum, mut acc_max, mut acc_late, mut acc_sum) =
        (0.0f64, 0.0, 0.0f64, 0.0f64, 0.0);
    let mut time_to_goal = None;
    for k in 0..n {
        let eps = dist(tf.position(k), ta.position(k), dims);
        eps_max = eps_max.max(eps);
        eps_sum += eps;
        let a = norm(ta.acceleration(k), dims);
        acc_max = acc_max.max(a);
        acc_sum += a;
        if ta.t[k] >= 0.1 * p.duration - 1e-12 {
            acc_late = acc_late.max(a);
        }
        if time_to_goal.is_none() && dist(ta.position(k), &p.motion.goal, dims) <= GOAL_TOLERANCE {
            time_to_goal = Some(ta.t[k]);
        }
    }
    let final_goal = dist(ta.position(n - 1), &p.motion.goal, dims);
    (eps_max, eps_sum / n as f64, acc_max, acc_late, acc_sum / n as f64, final_goal, time_to_goal)
}

/// Computes the metrics of `adapted` against `free` for the prepared scenario `p`.
pub fn metrics(p: &Prepared, free: &Rollout, adapted: &Rollout) -> crate::Result<Metrics> {
    let ta = &adapted.trajectory;
    let field = p.field()?;
    let agents = field.agents().to_vec();
    let all: Vec<usize> = (0..p.position_dim()).collect();
    let (eps_max, eps_mean, acc_max, acc_max_after_10pct, acc_mean, final_goal_distance, time_to_goal) =
        motion_figures(p, free, adapted, &all);

    let sub = field.agent_dim();
    let mut eval = WorldEval::new(sub);
    let mut center = vec![0.0; sub];
    let mut xa = vec![0.0; sub];
    let mut obstacles = BTreeMap::new();
    for o in &p.scene.obstacles {
        let (mut min_c, mut min_d) = (f64::INFINITY, f64::INFINITY);
        for k in 0..ta.len() {
            o.center_at(ta.t[k], &mut center);
            for a in &agents {
                for (j, &d) in a.dims.iter().enumerate() {
                    xa[j] = ta.position(k)[d];
                }
                min_c = min_c.min(eval.value(o.shape(), o.rotation(), &center, &xa));
                min_d = min_d.min(signed_distance_world(o, &xa, ta.t[k]));
            }
        }
        obstacles.insert(
            o.id().to_string(),
            ObstacleMetrics { min_c, min_distance: min_d, collision: min_c <= 0.0 },
        );
    }
    let mut collision = obstacles.values().any(|o| o.collision);

    let (mut robots, mut robot_pairs) = (None, None);
    // A pose scenario's one robot is no group.
    if p.pose.is_none() && !p.scene.agents.is_empty() {
        let mut per_robot = BTreeMap::new();
        for a in &agents {
            let (eps_max, _, acc_max, _, _, final_goal_distance, time_to_goal) =
                motion_figures(p, free, adapted, &a.dims);
            per_robot
                .insert(a.id.clone(), RobotMetrics { eps_max, acc_max, final_goal_distance, time_to_goal });
        }
        let mut pairs = BTreeMap::new();
        let mut xb = vec![0.0; sub];
        for (i, a) in agents.iter().enumerate() {
            for b in &agents[i + 1..] {
                let (mut min_cd, mut min_c) = (f64::INFINITY, f64::INFINITY);
                for k in 0..ta.len() {
                    let x = ta.position(k);
                    for j in 0..sub {
                        xa[j] = x[a.dims[j]];
                        xb[j] = x[b.dims[j]];
                    }
                    min_cd = min_cd.min(xa.iter().zip(&xb).map(|(u, v)| (u - v).powi(2)).sum::<f64>().sqrt());
                    if let Some(f) = &b.footprint {
                        let y: Vec<f64> = xa.iter().zip(&xb).map(|(u, v)| u - v).collect();
                        min_c = min_c.min(f.value(&y));
                    }
                    if let Some(f) = &a.footprint {
                        let y: Vec<f64> = xb.iter().zip(&xa).map(|(u, v)| u - v).collect();
                        min_c = min_c.min(f.value(&y));
                    }
                }
                let collision = min_c <= 0.0;
                pairs.insert(
                    format!("{}-{}", a.id, b.id),
                    PairMetrics { min_center_distance: min_cd, min_c, collision },
                );
            }
        }
        collision |= pairs.values().any(|p: &PairMetrics| p.collision);
        robots = Some(per_robot);
        robot_pairs = Some(pairs);
    }
    let stalls = adapted
        .stalls
        .iter()
        .map(|(i, s)| StallMetrics { robot: agents[*i].id.clone(), since: s.since, distance: s.distance })
        .collect();
    Ok(Metrics {
        steps: p.steps,
        dt: p.dt,
        duration: p.duration,
        finite: ta.is_finite(),
        compute_seconds: 0.0,
        eps_max,
        eps_mean,
        acc_max,
        acc_max_after_10pct,
        acc_mean,
        final_goal_distance,
        time_to_goal,
        collision,
        obstacles,
        robots,
        robot_pairs,
        stalls,
        pose: pose_figures(p, free, adapted),
    })
}

/// The orientation figures of a pose scenario.
fn pose_figures(p: &Prepared, free: &Rollout, adapted: &Rollout) -> Option<PoseMetrics> {
    use crate::orientation::pose::from_chart;
    use crate::orientation::quaternion::angle_between;
    use nalgebra::{Quaternion, UnitQuaternion, Vector3};
    let pose = p.pose.as_ref()?;
    let n = p.position_dim();
    let goal = from_chart(&pose.chart, &Vector3::from_column_slice(&p.motion.goal[n..n + 3]));
    let q = |r: &Rollout, k: usize| {
        let v = &r.orientations.q[4 * k..4 * k + 4];
        UnitQuaternion::new_normalize(Quaternion::new(v[3], v[0], v[1], v[2]))
    };
    let rows = adapted.orientations.q.len() / 4;
    let max_turn = (0..rows.min(free.orientations.q.len() / 4))
        .map(|k| angle_between(&q(adapted, k), &q(free, k)))
        .fold(0.0, f64::max);
    let peak =
        |v: &[f64]| v.chunks_exact(3).map(|w| Vector3::from_column_slice(w).norm()).fold(0.0, f64::max);
    let contact_rows = {
        let mut rows: Vec<usize> = adapted.contacts.iter().map(|(k, _)| *k).collect();
        rows.dedup();
        rows.len()
    };
    Some(PoseMetrics {
        final_orientation_error_deg: rows
            .checked_sub(1)
            .map_or(f64::NAN, |last| angle_between(&q(adapted, last), &goal).to_degrees()),
        max_turn_from_free_deg: max_turn.to_degrees(),
        angular_speed_max: peak(&adapted.orientations.omega),
        angular_acc_max: peak(&adapted.orientations.omega_dot),
        tool_contact_rows: pose.tool.as_ref().map(|_| contact_rows),
        tool_min_distance: pose.tool.as_ref().map(|tool| {
            let samples = crate::tool::surface_samples(tool, TOOL_SURFACE_SAMPLES);
            let ta = &adapted.trajectory;
            let n = rows.min(ta.len());
            let mut rows: Vec<usize> = (0..n).step_by(TOOL_CLEARANCE_STRIDE).collect();
            if n > 0 && rows.last() != Some(&(n - 1)) {
                rows.push(n - 1);
            }
            // A row can only lower the minimum where the frame's origin is within the samples' reach of it.
            let reach = samples.iter().map(|s| s.norm()).fold(0.0, f64::max);
            p.scene
                .obstacles
                .iter()
                .map(|o| {
                    let mut d = f64::INFINITY;
                    for &k in &rows {
                        let x = Vector3::from_column_slice(&ta.position(k)[..3]);
                        if signed_distance_world(o, x.as_slice(), ta.t[k]) - reach >= d {
                            continue;
                        }
                        d = d.min(crate::tool::sampled_clearance(&samples, &x, &q(adapted, k), o, ta.t[k]));
                    }
                    (o.id().to_string(), d)
                })
                .collect()
        }),
    })
}
