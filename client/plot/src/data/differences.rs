//! Speed, acceleration and jerk as a robot judges them: backward finite differences of the setpoints at the output
//! rate (jerk = third difference / dt³), the norm over a robot's position dimensions, or, for a pose run, of the
//! orientation's rotation vector between consecutive setpoints.

use dmp::Trajectory;

use super::decimate::peaks;
use super::geometry::P2;

/// The `order`-th (1: speed, 2: acceleration, 3: jerk) backward difference of `rows` (a vector per time of `t`),
/// divided by dt^order, its norm against time, peak-decimated. Where a step is not positive the curve is broken.
fn differenced(t: &[f64], mut rows: Vec<Vec<f64>>, order: usize) -> Vec<P2> {
    let mut times = t.to_vec();
    for _ in 0..order {
        let next: Vec<Vec<f64>> = rows
            .windows(2)
            .zip(times.windows(2))
            .map(|(r, s)| {
                let dt = s[1] - s[0];
                r[1].iter().zip(&r[0]).map(|(b, a)| if dt > 0.0 { (b - a) / dt } else { f64::NAN }).collect()
            })
            .collect();
        rows = next;
        times.remove(0);
    }
    let pts: Vec<P2> =
        times.iter().zip(&rows).map(|(t, r)| (*t, r.iter().map(|v| v * v).sum::<f64>().sqrt())).collect();
    peaks(&pts)
}

/// The `order`-th finite difference of the positions `dims` of `tr`, against time.
pub(crate) fn linear(tr: &Trajectory, dims: &[usize], order: usize) -> Vec<P2> {
    let rows = (0..tr.len()).map(|k| dims.iter().map(|&d| tr.position(k)[d]).collect()).collect();
    differenced(&tr.t, rows, order)
}

/// The `order`-th finite difference of the orientations `q` (`[x, y, z, w]`, one per time of `t`) against time:
/// order 1 is the angular speed `|2 log(q_k q_{k-1}^*)| / dt` (rad/s), higher orders difference those angular
/// velocities (world frame).
pub(crate) fn angular(t: &[f64], q: &[[f64; 4]], order: usize) -> Vec<P2> {
    let n = t.len().min(q.len());
    if n < 2 || order == 0 {
        return Vec::new();
    }
    // The rotation vector from each orientation to the next, as a rate: the first differences.
    let mut omega: Vec<Vec<f64>> = Vec::with_capacity(n - 1);
    for k in 1..n {
        let dt = t[k] - t[k - 1];
        let r = rotation_vector(&q[k - 1], &q[k]);
        omega.push(r.iter().map(|v| if dt > 0.0 { v / dt } else { f64::NAN }).collect());
    }
    differenced(&t[1..n], omega, order - 1)
}

/// The rotation vector (axis times angle, world frame) turning `a` into `b`: `2 log(b a^*)`, the short way.
fn rotation_vector(a: &[f64; 4], b: &[f64; 4]) -> [f64; 3] {
    // r = b * conj(a), quaternions [x, y, z, w].
    let (ax, ay, az, aw) = (-a[0], -a[1], -a[2], a[3]);
    let (bx, by, bz, bw) = (b[0], b[1], b[2], b[3]);
    let mut r = [
        bw * ax + bx * aw + by * az - bz * ay,
        bw * ay - bx * az + by * aw + bz * ax,
        bw * az + bx * ay - by * ax + bz * aw,
        bw * aw - bx * ax - by * ay - bz * az,
    ];
    if r[3] < 0.0 {
        r = r.map(|v| -v);
    }
    let s = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
    if s < 1e-300 {
        return [0.0; 3];
    }
    let angle = 2.0 * s.atan2(r[3]);
    [r[0] / s * angle, r[1] / s * angle, r[2] / s * angle]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cubic_has_a_constant_jerk_and_a_steady_turn_a_constant_angular_speed() {
        // x = t³ at 1 ms: jerk 6 everywhere.
        let mut tr = Trajectory::with_capacity(1, 101);
        for k in 0..=100 {
            let t = k as f64 * 1e-3;
            tr.push(t, &[t * t * t], &[0.0], &[0.0]);
        }
        let j = linear(&tr, &[0], 3);
        assert_eq!(j.len(), 98);
        assert!(j.iter().all(|p| (p.1 - 6.0).abs() < 1e-3), "{:?}", &j[..3]);
        // A turn about z at 2 rad/s.
        let t: Vec<f64> = (0..50).map(|k| k as f64 * 0.01).collect();
        let q: Vec<[f64; 4]> = t.iter().map(|t| [0.0, 0.0, (t).sin(), (t).cos()]).collect();
        let w = angular(&t, &q, 1);
        assert!(w.iter().all(|p| (p.1 - 2.0).abs() < 1e-9), "{:?}", &w[..3]);
        assert!(angular(&t, &q, 2).iter().all(|p| p.1 < 1e-6));
    }
}
