//! Obstacles a run leaves out, and why: those of another dimension than its robots', and those whose term made a
//! step not finite (dropped for the rest of the run, so that one bad obstacle never ends it). Each is reported once
//! in the next [`super::Stretch`].

use std::collections::{BTreeMap, BTreeSet};

use super::diagnosis::Diagnosis;
use super::{Execution, cell_mate_field};
use crate::field::{RepulsiveField, Scene};
use crate::isopotential::Shape;
use crate::obstacle::Obstacle;

/// An obstacle (or another robot of the cell) that a run does not avoid, and why.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct IgnoredObstacle {
    /// The obstacle's id (a robot's id for a cell-mate).
    pub id: String,
    /// Why it is left out.
    pub reason: String,
}

/// What a run leaves out.
#[derive(Debug, Default)]
pub(super) struct Ignored {
    /// Obstacles dropped for a term that was not finite, by id, with the shape they had: the same id with another
    /// shape is a new version of the obstacle and is avoided again.
    obstacles: BTreeMap<String, Shape>,
    /// Cell-mates dropped, by id, with their footprints.
    robots: BTreeMap<String, Shape>,
    /// Ids of the obstacles of another dimension in the last scene (each reported when it enters).
    other_dim: BTreeSet<String>,
    /// Not yet handed out.
    pending: Vec<IgnoredObstacle>,
}

impl Ignored {
    /// True when `o` (this version of it) was dropped.
    pub(super) fn is_dropped(&self, o: &Obstacle) -> bool {
        self.obstacles.get(o.id()) == Some(o.shape())
    }

    /// True when the cell-mate `id` with this footprint was dropped.
    pub(super) fn is_dropped_robot(&self, id: &str, footprint: &Shape) -> bool {
        self.robots.get(id) == Some(footprint)
    }

    /// Notes the obstacles of another dimension than `sub` in a new scene: those that were not there before are
    /// reported.
    pub(super) fn set_other_dim<'a>(&mut self, others: impl IntoIterator<Item = &'a Obstacle>, sub: usize) {
        let mut now = BTreeSet::new();
        for o in others {
            if !self.other_dim.contains(o.id()) && !now.contains(o.id()) {
                self.pending.push(IgnoredObstacle {
                    id: o.id().to_string(),
                    reason: format!("it has {} dimensions, but the robot moves in {sub}", o.dim()),
                });
            }
            now.insert(o.id().to_string());
        }
        self.other_dim = now;
    }

    /// The reports not yet handed out.
    pub(super) fn take_pending(&mut self) -> Vec<IgnoredObstacle> {
        std::mem::take(&mut self.pending)
    }
}

impl Execution {
    /// Drops, for the rest of the run, the obstacles and cell-mates that `d` found (or, when it found none, every
    /// obstacle and cell-mate: the step was not finite with them and no single term was), and reports them. False
    /// when there was nothing to drop: the step is not finite without any obstacle.
    pub(super) fn drop_culprits(&mut self, d: &Diagnosis) -> bool {
        let (all_obstacles, all_robots);
        let (obstacles, robots, reason): (&[usize], &[usize], String) = if d.obstacles.is_empty()
            && d.robots.is_empty()
        {
            all_obstacles = (0..self.field.scene().obstacles.len()).collect::<Vec<_>>();
            all_robots = (0..self.cell_mates.scene().obstacles.len()).collect::<Vec<_>>();
            let reason = "the robot's step was not finite with it, and no single obstacle's term was: every \
                              obstacle is dropped for the rest of this run"
                .to_string();
            (&all_obstacles, &all_robots, reason)
        } else {
            let reason = format!(
                "its repulsive term is not finite at the robot's state at t = {:.3} s: dropped for the rest of \
                     this run",
                d.t
            );
            (&d.obstacles, &d.robots, reason)
        };
        if obstacles.is_empty() && robots.is_empty() {
            return false;
        }
        let dim = self.primitive.dim;
        if !obstacles.is_empty() {
            let mut scene: Scene = self.field.scene().clone();
            let mut kept = Vec::with_capacity(scene.obstacles.len());
            for (i, o) in scene.obstacles.drain(..).enumerate() {
                if obstacles.contains(&i) {
                    self.ignored
                        .pending
                        .push(IgnoredObstacle { id: o.id().to_string(), reason: reason.clone() });
                    self.ignored.obstacles.insert(o.id().to_string(), o.shape().clone());
                } else {
                    kept.push(o);
                }
            }
            scene.obstacles = kept;
            match RepulsiveField::new(scene, dim).and_then(|f| f.keeping_off(self.keep_off())) {
                Ok(f) => self.field = f,
                Err(_) => return false,
            }
        }
        if !robots.is_empty() {
            let mut kept = Vec::new();
            for (i, o) in self.cell_mates.scene().obstacles.iter().enumerate() {
                if robots.contains(&i) {
                    self.ignored
                        .pending
                        .push(IgnoredObstacle { id: o.id().to_string(), reason: reason.clone() });
                    self.ignored.robots.insert(o.id().to_string(), o.shape().clone());
                } else {
                    kept.push(o.clone());
                }
            }
            let agents = self.field.agents().to_vec();
            match cell_mate_field(&agents, self.cell_mate_avoidance, kept, dim) {
                Ok(f) => self.cell_mates = f,
                Err(_) => return false,
            }
        }
        // The acceleration at knot0 was computed under the old field; the fields being replaced may hold the
        // culprits too.
        self.acc0_current = false;
        self.blend.clear();
        true
    }
}

#[cfg(test)]
mod tests {
    use super::super::{CellMateAvoidance, Outcome, Stepping};
    use super::*;
    use crate::avoidance::{Avoidance, Method, StaticVolumetric};
    use crate::integrate::Motion;
    use crate::isopotential::Superquadric;
    use crate::primitive::Primitive;

    fn reach_primitive() -> Primitive {
        Primitive::straight_line(20, 4.0, vec![1000.0; 2], None, 1.0, vec![0.0; 2], vec![1.0, 0.5]).unwrap()
    }

    fn avoidance() -> Avoidance {
        Avoidance::new(Method::StaticVolumetric(StaticVolumetric { a: 0.1, eta: 1.0 }))
    }

    /// A 2-D reach avoiding `obstacles` with the static volumetric potential.
    fn reach(obstacles: Vec<Obstacle>, stepping: Stepping) -> Execution {
        let p = reach_primitive();
        let scene = Scene::with_obstacles(obstacles, avoidance(), 0);
        super::super::tests::alone(&p, scene, stepping, 200)
    }

    fn disc(id: &str, a: f64, center: Vec<f64>) -> Obstacle {
        let d = center.len();
        Obstacle::new(
            id,
            Shape::Superquadric(Superquadric::ellipsoid(vec![a; d]).unwrap()),
            center,
            None,
            None,
        )
        .unwrap()
    }

    /// Semi-axes of 1e-300 far away: `C` overflows, and the static volumetric term is `0 * inf`.
    fn hostile(id: &str) -> Obstacle {
        disc(id, 1e-300, vec![50.0, 50.0])
    }

    /// Advances to the end (at most `stretches` of 10 points): every position, and every report.
    fn run_out(e: &mut Execution, stretches: usize) -> (Vec<f64>, Vec<IgnoredObstacle>, Outcome) {
        let (mut x, mut ignored, mut outcome) = (Vec::new(), Vec::new(), Outcome::Running);
        for _ in 0..stretches {
            let s = e.advance(10).unwrap();
            assert!(s.x.iter().chain(&s.xd).chain(&s.xdd).all(|v| v.is_finite()));
            x.extend(s.x);
            ignored.extend(s.ignored);
            outcome = s.outcome;
            if outcome.is_final() {
                break;
            }
        }
        (x, ignored, outcome)
    }

    fn bits(v: &[f64]) -> Vec<u64> {
        v.iter().map(|x| x.to_bits()).collect()
    }

    #[test]
    fn an_obstacle_whose_term_is_not_finite_is_dropped_and_reported_once() {
        for stepping in [
            Stepping::rk4(1e-3),
            Stepping { dt: 1e-3, step_points: 5, tolerance: None },
            Stepping { dt: 1e-3, step_points: 30, tolerance: Some(3e-6) },
        ] {
            let (want, none, _) = run_out(&mut reach(Vec::new(), stepping), 300);
            assert!(none.is_empty());
            let (got, ignored, outcome) = run_out(&mut reach(vec![hostile("bad")], stepping), 300);
            assert_eq!(outcome, Outcome::GoalReached, "{stepping:?}");
            assert_eq!(ignored.len(), 1, "{ignored:?}");
            assert_eq!(ignored[0].id, "bad");
            assert!(ignored[0].reason.contains("not finite"), "{}", ignored[0].reason);
            // Dropped before the first point: the run is the one without it, bit for bit.
            assert!(bits(&got) == bits(&want), "{stepping:?}: not the run without it");
        }
    }

    #[test]
    fn a_dropped_obstacle_stays_out_until_a_new_version_replaces_it() {
        let good = disc("good", 0.1, vec![0.5, 0.1]);
        let mut e = reach(Vec::new(), Stepping::rk4(1e-3));
        e.advance(100).unwrap();
        let bad = hostile("bad");
        e.set_obstacles([(&bad, 0.0), (&good, 0.0)]).unwrap();
        let s = e.advance(10).unwrap();
        assert_eq!(s.ignored.iter().map(|i| i.id.as_str()).collect::<Vec<_>>(), ["bad"]);
        assert_eq!(e.field().scene().obstacles.len(), 1, "the good one is still avoided");
        // The same version again: still out, not reported again.
        e.set_obstacles([(&bad, 0.0), (&good, 0.0)]).unwrap();
        assert!(e.advance(10).unwrap().ignored.is_empty());
        assert_eq!(e.field().scene().obstacles.len(), 1);
        // A new version with a sane shape is avoided again.
        let fixed = disc("bad", 0.05, vec![-0.5, 0.5]);
        e.set_obstacles([(&fixed, 0.0), (&good, 0.0)]).unwrap();
        assert!(e.advance(10).unwrap().ignored.is_empty());
        assert_eq!(e.field().scene().obstacles.len(), 2);
        let (_, ignored, outcome) = run_out(&mut e, 400);
        assert!(ignored.is_empty());
        assert!(matches!(outcome, Outcome::GoalReached), "{outcome:?}");
    }

    #[test]
    fn obstacles_of_another_dimension_are_reported_when_they_enter() {
        let ball = disc("ball", 0.1, vec![0.5, 0.5, 0.5]);
        let mut e = reach(Vec::new(), Stepping::rk4(1e-3));
        e.set_obstacles([(&ball, 0.0)]).unwrap();
        let s = e.advance(10).unwrap();
        assert_eq!(s.ignored.len(), 1);
        assert_eq!(s.ignored[0].id, "ball");
        assert!(
            s.ignored[0].reason.contains("3 dimensions, but the robot moves in 2"),
            "{}",
            s.ignored[0].reason
        );
        e.set_obstacles([(&ball, 0.0)]).unwrap();
        assert!(e.advance(10).unwrap().ignored.is_empty(), "reported once while it stays");
        e.set_obstacles(std::iter::empty()).unwrap();
        e.set_obstacles([(&ball, 0.0)]).unwrap();
        assert_eq!(e.advance(10).unwrap().ignored.len(), 1, "reported again when it enters again");
    }

    #[test]
    fn a_cell_mate_whose_term_is_not_finite_is_dropped() {
        let p = reach_primitive();
        let mates = CellMateAvoidance { method: avoidance(), point_samples: 0 };
        let mut e =
            Execution::new(p.clone(), Motion::of(&p), Scene::empty(), mates, Stepping::rk4(1e-3), 200)
                .unwrap();
        let tiny = Shape::Superquadric(Superquadric::ellipsoid(vec![1e-300; 2]).unwrap());
        let mate = super::super::CellMate {
            id: "ghost",
            footprint: &tiny,
            position: &[40.0, -40.0],
            velocity: &[0.0, 0.0],
            age: 0.0,
        };
        e.set_cell_mates([mate]).unwrap();
        let (_, ignored, outcome) = run_out(&mut e, 300);
        assert_eq!(outcome, Outcome::GoalReached);
        assert_eq!(ignored.iter().map(|i| i.id.as_str()).collect::<Vec<_>>(), ["ghost"]);
        // Seen again: still left out.
        e.set_cell_mates([mate]).unwrap();
        assert!(e.advance(1).unwrap().ignored.is_empty());
    }

    #[test]
    fn a_step_that_is_not_finite_without_obstacles_is_still_an_error() {
        let mut p = reach_primitive();
        p.weights[0].fill(1e308);
        let mut e = super::super::tests::alone(&p, Scene::empty(), Stepping::rk4(1e-3), 10);
        let diverged = (0..100).find_map(|_| e.advance(10).err());
        assert!(matches!(diverged, Some(crate::DmpError::Diverged { .. })), "{diverged:?}");
    }
}
