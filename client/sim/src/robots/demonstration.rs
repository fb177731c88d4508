//! Synthetic demonstrations, as a person would give them: a straight line driven at constant speed between smooth
//! ramps (a mobile base), and a minimum-jerk reach with an optional lift (an arm).

/// Fraction of the way covered at time `t` by a drive of `duration` seconds that cruises at constant speed between
/// two ramps of `ramp_s` (at most half the duration). On a ramp the speed follows `6u^5 - 15u^4 + 10u^3`,
/// `u = t / ramp_s`, so the acceleration is continuous and zero at both ends of the ramp (peak acceleration
/// `1.875 v / ramp_s` for the cruise speed `v`).
pub(crate) fn ramped_way(t: f64, duration: f64, ramp_s: f64) -> f64 {
    let ramp = ramp_s.min(0.5 * duration);
    let v = 1.0 / (duration - ramp);
    let up = |t: f64| {
        if t <= 0.0 {
            0.0
        } else if t < ramp {
            let u = t / ramp;
            v * ramp * u.powi(4) * (u * u - 3.0 * u + 2.5)
        } else {
            v * (t - 0.5 * ramp)
        }
    };
    if t >= duration {
        1.0
    } else if t <= 0.5 * duration {
        up(t)
    } else {
        1.0 - up(duration - t)
    }
}

/// The time at which a drive of [`ramped_way`] has covered the fraction `way` of its length.
pub(crate) fn ramped_time_at(way: f64, duration: f64, ramp_s: f64) -> f64 {
    let (mut lo, mut hi) = (0.0, duration);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if ramped_way(mid, duration, ramp_s) < way {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Duration of a ramped drive of `length` metres cruising at `speed`.
pub(crate) const fn ramped_duration(length: f64, speed: f64, ramp_s: f64) -> f64 {
    length / speed + ramp_s
}

/// A synthetic demonstration: the straight line from `start` to `goal` driven as [`ramped_way`], sampled every
/// `dt` (times, rows).
pub(crate) fn ramped_line(
    start: &[f64],
    goal: &[f64],
    duration: f64,
    ramp_s: f64,
    dt: f64,
) -> (Vec<f64>, Vec<Vec<f64>>) {
    let n = (duration / dt).round().max(2.0) as usize;
    let t: Vec<f64> = (0..=n).map(|k| duration * k as f64 / n as f64).collect();
    let rows = t
        .iter()
        .map(|&t| {
            let w = ramped_way(t, duration, ramp_s);
            start.iter().zip(goal).map(|(a, b)| a + w * (b - a)).collect()
        })
        .collect();
    (t, rows)
}

/// A minimum-jerk reach from `start` to `goal` in `duration` seconds, sampled every `dt` (times, rows): the way
/// covered follows `10u^3 - 15u^4 + 6u^5`, `u = t / duration` (at rest at both ends, peak speed `1.875 L / duration`
/// and peak acceleration `5.77 L / duration^2` over a length `L`), and the last coordinate (`z`) is raised by
/// `lift * 16u^2 (1 - u)^2` (the full lift half way).
pub(crate) fn min_jerk(
    start: &[f64],
    goal: &[f64],
    duration: f64,
    lift: f64,
    dt: f64,
) -> (Vec<f64>, Vec<Vec<f64>>) {
    let n = (duration / dt).round().max(2.0) as usize;
    let last = start.len().saturating_sub(1);
    let mut t = Vec::with_capacity(n + 1);
    let mut rows = Vec::with_capacity(n + 1);
    for k in 0..=n {
        let u = k as f64 / n as f64;
        let s = u * u * u * (10.0 - 15.0 * u + 6.0 * u * u);
        let up = 16.0 * u * u * (1.0 - u) * (1.0 - u) * lift;
        let row: Vec<f64> = (0..start.len())
            .map(|i| start[i] + (goal[i] - start[i]) * s + if i == last { up } else { 0.0 })
            .collect();
        t.push(u * duration);
        rows.push(row);
    }
    (t, rows)
}

/// The orientations of a minimum-jerk turn from `start` to `goal` (`[x, y, z, w]`) at the times of [`min_jerk`]
/// of the same `duration` and `dt`: the angle covered follows `10u^3 - 15u^4 + 6u^5` about one fixed axis.
pub(crate) fn min_jerk_turn(start: &[f64; 4], goal: &[f64; 4], duration: f64, dt: f64) -> Vec<[f64; 4]> {
    let n = (duration / dt).round().max(2.0) as usize;
    (0..=n)
        .map(|k| {
            let u = k as f64 / n as f64;
            super::pose::slerp(start, goal, u * u * u * (10.0 - 15.0 * u + 6.0 * u * u))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramped_drive() {
        let (d, r) = (5.0, 1.0);
        assert_eq!(ramped_way(0.0, d, r), 0.0);
        assert_eq!(ramped_way(d, d, r), 1.0);
        assert!((ramped_way(0.5 * d, d, r) - 0.5).abs() < 1e-12);
        // Cruise speed 1 / (d - r) of the way per second, reached at the end of the ramp.
        let v = (ramped_way(2.0, d, r) - ramped_way(1.5, d, r)) / 0.5;
        assert!((v - 0.25).abs() < 1e-12, "{v}");
        // Continuous at the end of the ramp.
        assert!((ramped_way(r - 1e-9, d, r) - ramped_way(r + 1e-9, d, r)).abs() < 1e-8);
        let t = ramped_time_at(0.3, d, r);
        assert!((ramped_way(t, d, r) - 0.3).abs() < 1e-12);
    }

    #[test]
    fn minimum_jerk_starts_and_ends_at_rest_with_its_peaks() {
        let (l, d) = (0.5, 2.0);
        let (t, rows) = min_jerk(&[0.0, 0.0], &[l, 0.0], d, 0.1, 1e-3);
        assert_eq!((t.len(), rows.len()), (2001, 2001));
        assert_eq!(rows[0], vec![0.0, 0.0]);
        assert!((rows[2000][0] - l).abs() < 1e-15 && rows[2000][1].abs() < 1e-15);
        // The full lift half way; speeds and accelerations by finite differences.
        assert!((rows[1000][1] - 0.1).abs() < 1e-12);
        let x: Vec<f64> = rows.iter().map(|r| r[0]).collect();
        let v: Vec<f64> = x.windows(2).map(|w| (w[1] - w[0]) / 1e-3).collect();
        let a: Vec<f64> = v.windows(2).map(|w| (w[1] - w[0]) / 1e-3).collect();
        let vmax = v.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let amax = a.iter().fold(0.0f64, |m, a| m.max(a.abs()));
        assert!((vmax - 1.875 * l / d).abs() < 1e-3, "{vmax}");
        assert!((amax - 5.7735 * l / (d * d)).abs() < 1e-3, "{amax}");
        assert!(v[0].abs() < 1e-5 && v[v.len() - 1].abs() < 1e-5);
    }
}
