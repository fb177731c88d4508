//! The world of the load: cells of robots whose paths cross, and five fixed obstacles per cell.
//!
//! Every cell is the same picture (cells are separate scenes, so they may share coordinates). Its `m` robots start
//! on a circle of radius `START_RADIUS` at angles `2 pi i / m`, and go to the far side, turned by `SKEW`: ten
//! chords that all pass 0.12 m from the centre, so every robot meets its nine cell-mates (as moving obstacles,
//! each a ball of radius [`FOOTPRINT_RADIUS`]) near the centre, turning the same way round. In 3-D the robots also
//! climb from `z = 0` to `z = CLIMB`. The fixed obstacles are spheres on a ring of radius `OBSTACLE_RING`,
//! between the starts, in the robots' way.
//!
//! The primitive is a null-weight DMP (a straight line driven by the phase) with a soft spring
//! (`STIFFNESS`): a critically damped leg to a new goal takes about `9.2 tau / sqrt(K)` = 1.8 tau to settle
//! within 1 mm, so a robot retargeted every `tau` seconds never arrives (a run ends when the goal is reached at
//! rest; a goal change does not restart the phase).

use std::f64::consts::PI;

use dmp_proto::v1;

use crate::error::SimError;

/// Radius of the circle the robots start on, metres.
pub(crate) const START_RADIUS: f64 = 0.6;
/// A goal is the start's antipode turned by this angle, radians (no head-on pairs: no symmetric deadlock).
pub(crate) const SKEW: f64 = 0.4;
/// 3-D: height of the first goal, metres (the second goal is the start).
pub(crate) const CLIMB: f64 = 0.2;
/// A robot's footprint: a ball of this radius, metres.
pub const FOOTPRINT_RADIUS: f64 = 0.1;
/// Fixed obstacles per cell.
pub const FIXED_OBSTACLES: usize = 5;
/// Radius of a fixed obstacle (a sphere), metres.
pub const OBSTACLE_RADIUS: f64 = 0.06;
/// Distance of the fixed obstacles from the cell's centre, metres.
pub(crate) const OBSTACLE_RING: f64 = 0.3;
/// How far a scene update moves an obstacle, metres.
pub(crate) const OBSTACLE_SHIFT: f64 = 0.02;
/// The primitive's stiffness K (every dimension); damping is critical.
pub(crate) const STIFFNESS: f64 = 25.0;
/// The primitive's N (N + 1 Gaussians, all weights zero).
pub(crate) const N_BASIS: usize = 50;
/// The primitive's canonical decay.
pub(crate) const ALPHA: f64 = 4.0;
/// The primitive's name (one per robot).
pub(crate) const PRIMITIVE: &str = "load";

/// One robot of the load.
#[derive(Debug, Clone, PartialEq)]
pub struct RobotPlan {
    /// Its id: `<prefix>.c<cell>.r<k>` (`robot_id`).
    pub id: String,
    /// Index of its cell.
    pub cell: usize,
    /// Its start.
    pub start: Vec<f64>,
    /// The two goals it alternates between: the far side first, then its start.
    pub goals: [Vec<f64>; 2],
}

/// The name of cell `c`.
pub fn cell_name(prefix: &str, c: usize) -> String {
    format!("{prefix}-{c}")
}

/// The id of robot `k` of cell `c`: `<prefix>.c<c>.r<k>` (`load.c3.r7`). The load's robots are its own, named
/// apart from any real robot's (`.` is allowed in robot ids, `[A-Za-z0-9_.-]`), and deleted when it ends.
pub(crate) fn robot_id(prefix: &str, c: usize, k: usize) -> String {
    format!("{prefix}.c{c}.r{k}")
}

/// Cells for `robots` robots in cells of `cell_size`.
pub(crate) fn cell_count(robots: usize, cell_size: usize) -> usize {
    robots.div_ceil(cell_size.max(1))
}

fn point(dim: usize, angle: f64, radius: f64, z: f64) -> Vec<f64> {
    let mut p = vec![radius * angle.cos(), radius * angle.sin()];
    if dim == 3 {
        p.push(z);
    }
    p
}

/// The robots, cell by cell (the last cell may have fewer).
pub fn robots(count: usize, cell_size: usize, dim: usize, prefix: &str) -> Vec<RobotPlan> {
    let cell_size = cell_size.max(1);
    (0..count)
        .map(|i| {
            let (cell, k) = (i / cell_size, i % cell_size);
            let mates = cell_size.min(count - cell * cell_size);
            let angle = 2.0 * PI * k as f64 / mates as f64;
            let start = point(dim, angle, START_RADIUS, 0.0);
            let far = point(dim, angle + PI + SKEW, START_RADIUS, CLIMB);
            RobotPlan { id: robot_id(prefix, cell, k), cell, start: start.clone(), goals: [far, start] }
        })
        .collect()
}

/// The primitive of a robot: from its start to its first goal in `tau` seconds.
pub fn primitive(robot: &RobotPlan, tau: f64) -> Result<dmp::Primitive, SimError> {
    let dim = robot.start.len();
    dmp::Primitive::straight_line(
        N_BASIS,
        ALPHA,
        vec![STIFFNESS; dim],
        None,
        tau,
        robot.start.clone(),
        robot.goals[0].clone(),
    )
    .map_err(|e| SimError::argument("--tau", format!("no primitive for {}: {e}", robot.id)))
}

/// A robot's footprint.
pub fn footprint(dim: usize) -> v1::Superquadric {
    v1::Superquadric { semi_axes: vec![FOOTPRINT_RADIUS; dim], exponents: Vec::new() }
}

/// The id of fixed obstacle `k`.
pub(crate) fn obstacle_id(k: usize) -> String {
    format!("fixed-{k}")
}

/// Fixed obstacle `k` of a cell, moved by `shift` metres along y.
pub fn fixed_obstacle(dim: usize, k: usize, shift: f64) -> v1::Obstacle {
    let angle = 2.0 * PI * k as f64 / FIXED_OBSTACLES as f64 + PI / 10.0;
    let mut center = point(dim, angle, OBSTACLE_RING, 0.5 * CLIMB);
    center[1] += shift;
    v1::Obstacle {
        id: obstacle_id(k),
        shape: Some(v1::obstacle::Shape::Superquadric(v1::Superquadric {
            semi_axes: vec![OBSTACLE_RADIUS; dim],
            exponents: Vec::new(),
        })),
        center,
        ..Default::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dist(a: &[f64], b: &[f64]) -> f64 {
        a.iter().zip(b).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt()
    }

    #[test]
    fn cells_of_ten_start_apart_and_cross_near_the_centre() {
        assert_eq!(cell_count(25, 10), 3);
        let all = robots(25, 10, 3, "load");
        assert_eq!(all.len(), 25);
        assert_eq!((all[24].id.as_str(), all[24].cell), ("load.c2.r4", 2));
        for cell in 0..3 {
            let mates: Vec<&RobotPlan> = all.iter().filter(|r| r.cell == cell).collect();
            for (i, a) in mates.iter().enumerate() {
                assert_eq!(a.start.len(), 3);
                assert_eq!(a.goals[1], a.start);
                // The path's closest approach to the centre (in the plane) is START_RADIUS cos((PI + SKEW) / 2).
                let mid: Vec<f64> = (0..2).map(|j| 0.5 * (a.start[j] + a.goals[0][j])).collect();
                assert!(dist(&mid, &[0.0, 0.0]) < 0.15, "{}: {mid:?}", a.id);
                for b in &mates[i + 1..] {
                    assert!(dist(&a.start, &b.start) > 3.0 * FOOTPRINT_RADIUS, "{} {}", a.id, b.id);
                }
                for k in 0..FIXED_OBSTACLES {
                    let o = fixed_obstacle(3, k, 0.0);
                    let clear = FOOTPRINT_RADIUS + OBSTACLE_RADIUS;
                    assert!(dist(&o.center, &a.start) > clear && dist(&o.center, &a.goals[0]) > clear);
                }
            }
        }
        let p = primitive(&all[0], 2.0).unwrap();
        assert_eq!((p.dim, p.tau), (3, 2.0));
        assert_eq!(robots(3, 10, 2, "x")[1].start.len(), 2);
        assert_eq!(fixed_obstacle(2, 1, OBSTACLE_SHIFT).center.len(), 2);
    }
}
