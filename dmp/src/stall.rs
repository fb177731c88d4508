//! Stall detection: the paper admits local minima (section 3); a robot that stops far from its goal is reported.

/// When a robot counts as stalled.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StallConfig {
    /// Speed `|dx/dt|` below which the robot counts as stopped.
    pub(crate) speed_tol: f64,
    /// Distance to the goal within which stopping is arriving, not stalling.
    pub(crate) goal_tol: f64,
    /// How long it must stay stopped away from its goal.
    pub window: f64,
}

impl Default for StallConfig {
    fn default() -> Self {
        Self { speed_tol: 1e-3, goal_tol: 1e-2, window: 0.25 }
    }
}

/// A stall: the robot stopped at `since` and was still stopped at `detected_at`, `distance` from its goal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stall {
    /// When it stopped.
    pub since: f64,
    /// When the window elapsed.
    pub detected_at: f64,
    /// Distance to the goal then.
    pub distance: f64,
}

/// Watches one robot (the dimensions it owns).
#[derive(Debug, Clone, PartialEq)]
pub struct StallDetector {
    config: StallConfig,
    dims: Vec<usize>,
    since: Option<f64>,
    reported: bool,
}

impl StallDetector {
    /// Watches the dimensions `dims` of the state.
    pub fn new(config: StallConfig, dims: Vec<usize>) -> Self {
        Self { config, dims, since: None, reported: false }
    }

    /// Feeds one state; returns the stall the first time the window elapses (once per stop).
    pub fn update(&mut self, t: f64, x: &[f64], xd: &[f64], goal: &[f64]) -> Option<Stall> {
        let speed = self.dims.iter().map(|&i| xd[i] * xd[i]).sum::<f64>().sqrt();
        let distance = self.dims.iter().map(|&i| (x[i] - goal[i]).powi(2)).sum::<f64>().sqrt();
        if speed >= self.config.speed_tol || distance <= self.config.goal_tol {
            self.since = None;
            self.reported = false;
            return None;
        }
        let since = *self.since.get_or_insert(t);
        if !self.reported && t - since >= self.config.window {
            self.reported = true;
            return Some(Stall { since, detected_at: t, distance });
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_robot_stopped_away_from_its_goal_is_reported_once() {
        let mut d = StallDetector::new(StallConfig::default(), vec![0, 1]);
        let goal = [1.0, 0.0];
        let mut hits = 0;
        for k in 0..1000 {
            let t = k as f64 * 1e-3;
            if d.update(t, &[0.5, 0.0], &[0.0, 0.0], &goal).is_some() {
                hits += 1;
                assert!((t - 0.25).abs() < 1e-9);
            }
        }
        assert_eq!(hits, 1);
        // Arrived: never a stall.
        let mut d = StallDetector::new(StallConfig::default(), vec![0, 1]);
        assert!((0..1000).all(|k| d.update(k as f64 * 1e-3, &goal, &[0.0, 0.0], &goal).is_none()));
    }
}
