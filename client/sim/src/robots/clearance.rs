//! Clearance along whole runs at 1 kHz without a distance query per row, and the helpers of robots that share one
//! phase (their rows side by side, their closest approach).

use dmp::Trajectory;

use super::report::{CONTACT_M, Other, RobotReport, measure, position};
use super::robot::Executed;
use super::world::{Body, point3};

/// Euclidean distance between two points.
pub(crate) fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>().sqrt()
}

/// Trajectories of the same times side by side (the shared DMP's rows).
pub(crate) fn side_by_side(parts: &[&Trajectory]) -> Trajectory {
    let n = parts.iter().map(|p| p.len()).min().unwrap_or(0);
    let d: usize = parts.iter().map(|p| p.dim()).sum();
    let mut out = Trajectory::with_capacity(d, n);
    let (mut x, mut xd, mut xdd) = (Vec::with_capacity(d), Vec::with_capacity(d), Vec::with_capacity(d));
    for k in 0..n {
        x.clear();
        xd.clear();
        xdd.clear();
        for p in parts {
            x.extend_from_slice(p.position(k));
            xd.extend_from_slice(p.velocity(k));
            xdd.extend_from_slice(p.acceleration(k));
        }
        out.push(parts[0].t[k], &x, &xd, &xdd);
    }
    out
}

/// Strides of the successive scans of [`clearance`], the last one every row.
pub(crate) const STRIDES: [usize; 3] = [50, 10, 1];

/// The smallest distance between `body` along `traj` and `other` (fixed, or moving along `other_traj`, row by
/// row), exactly as a scan of every row would give it, with far fewer distance queries: a scan every
/// `STRIDES[0]` rows, then finer scans only around the samples that could hide a smaller value. A distance
/// changes from one row to the next by at most the two bodies' displacements (`lipschitz`), so the rows within
/// `s` of a sample `d` are at least `d - s lipschitz` away.
pub(crate) fn clearance(
    traj: &Trajectory,
    body: &Body,
    other: &Body,
    other_traj: Option<&Trajectory>,
) -> f64 {
    let n = other_traj.map_or(traj.len(), |o| o.len().min(traj.len()));
    if n == 0 {
        return f64::INFINITY;
    }
    let at = |k: usize| {
        let offset = other_traj.map_or(parry3d_f64::math::Vector::ZERO, |o| point3(position(o, k)));
        body.distance(point3(position(traj, k)), other, offset)
    };
    let step = |t: &Trajectory, k: usize| distance(position(t, k), position(t, k + 1));
    let lipschitz =
        (0..n - 1).map(|k| step(traj, k) + other_traj.map_or(0.0, |o| step(o, k))).fold(0.0, f64::max);
    let mut best = f64::INFINITY;
    // Row ranges (inclusive) still to scan.
    let mut windows = vec![(0, n - 1)];
    for s in STRIDES {
        let mut samples = Vec::new();
        for &(lo, hi) in &windows {
            samples.extend((lo..=hi).step_by(s).chain(std::iter::once(hi)).map(|k| (k, at(k))));
        }
        best = samples.iter().map(|x| x.1).fold(best, f64::min);
        let mut next: Vec<(usize, usize)> = Vec::new();
        for (k, d) in samples {
            if d - s as f64 * lipschitz <= best {
                let w = (k.saturating_sub(s), (k + s).min(n - 1));
                match next.last_mut() {
                    Some(last) if w.0 <= last.1 + 1 => last.1 = last.1.max(w.1),
                    _ => next.push(w),
                }
            }
        }
        windows = next;
    }
    best
}

/// [`measure`] (rows `dt` apart) with [`clearance`]: the same report, with far fewer distance queries at 1 kHz.
/// The other robots' rows have the same times (one group).
pub(crate) fn measure_fast(
    exec: &Executed,
    dt: f64,
    goal: &[f64],
    profile: Option<&dmp::Limits>,
    body: &Body,
    obstacles: &[Body],
    others: &[Other<'_>],
) -> RobotReport {
    let mut r = measure(exec, dt, goal, profile, body, &[], &[]);
    for o in obstacles {
        r.min_clearance_m.insert(o.id.clone(), clearance(&exec.traj, body, o, None));
    }
    for o in others {
        r.min_clearance_m.insert(o.id.into(), clearance(&exec.traj, body, o.body, Some(o.traj)));
    }
    r.collisions =
        r.min_clearance_m.iter().filter(|(_, d)| **d <= CONTACT_M).map(|(id, _)| id.clone()).collect();
    r
}

/// The time at which two of `trajs` (of the same times) have their controlled points closest, and that distance.
pub(crate) fn closest_approach(trajs: &[&Trajectory]) -> (f64, f64) {
    let mut best = (0.0, f64::INFINITY);
    let n = trajs.iter().map(|t| t.len()).min().unwrap_or(0);
    for k in 0..n {
        for (i, a) in trajs.iter().enumerate() {
            for b in &trajs[i + 1..] {
                let d = distance(position(a, k), position(b, k));
                if d < best.1 {
                    best = (a.t[k], d);
                }
            }
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robots::world::{SolidShape, robot_body};

    #[test]
    fn clearance_is_the_exact_minimum() {
        // A youBot weaving past a cube and another youBot: the refined scan equals the scan of every row.
        let n = 2001;
        let mut a = Trajectory::with_capacity(2, n);
        let mut b = Trajectory::with_capacity(2, n);
        for k in 0..n {
            let t = k as f64 * 1e-3;
            let xa = [t, 0.3 * (3.0 * t).sin()];
            let xb = [2.0 - t, 0.5 + 0.2 * (5.0 * t).cos()];
            a.push(t, &xa, &[0.0; 2], &[0.0; 2]);
            b.push(t, &xb, &[0.0; 2], &[0.0; 2]);
        }
        let body = robot_body("a", SolidShape::rectangle(0.29, 0.19));
        let other = robot_body("b", SolidShape::rectangle(0.29, 0.19));
        let cube = Body::new("cube", SolidShape::rectangle(0.2, 0.2), &[1.0, -0.7]);
        let brute = |o: &Body, t: Option<&Trajectory>| {
            (0..n)
                .map(|k| {
                    let off = t.map_or(parry3d_f64::math::Vector::ZERO, |t| point3(position(t, k)));
                    body.distance(point3(position(&a, k)), o, off)
                })
                .fold(f64::INFINITY, f64::min)
        };
        assert_eq!(clearance(&a, &body, &cube, None), brute(&cube, None));
        assert_eq!(clearance(&a, &body, &other, Some(&b)), brute(&other, Some(&b)));
    }

    #[test]
    fn closest_approach_of_three() {
        let mut t = [
            Trajectory::with_capacity(2, 3),
            Trajectory::with_capacity(2, 3),
            Trajectory::with_capacity(2, 3),
        ];
        for k in 0..3 {
            let s = k as f64;
            t[0].push(s, &[s, 0.0], &[0.0; 2], &[0.0; 2]);
            t[1].push(s, &[2.0, 0.0], &[0.0; 2], &[0.0; 2]);
            t[2].push(s, &[5.0, 3.0 - s], &[0.0; 2], &[0.0; 2]);
        }
        // Rows 1: 0 and 1 are 1 apart; row 2: 0 and 1 are 0 apart.
        assert_eq!(closest_approach(&[&t[0], &t[1], &t[2]]), (2.0, 0.0));
        let both = side_by_side(&[&t[0], &t[2]]);
        assert_eq!((both.dim(), both.len()), (4, 3));
        assert_eq!(both.position(1), &[1.0, 0.0, 5.0, 2.0]);
    }
}
