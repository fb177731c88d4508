//! The served run's accuracy in the load's own situation (`dmpctl load`, `dmp_sim::load`): a robot of a load cell, streamed with the server's adaptive step
//! (Dormand–Prince 5(4), at most 30 ms, tolerance 3e-6: what `dmpctl load` asks for by default) or a fixed RK4 step
//! of 5 ms (`--integration-tolerance 0 --integration-step-s 0.005`), with quintic Hermite output at 1 kHz, stays within
//! 1e-3 of the engine's RK4 at 1 ms, past the cell's five fixed obstacles and its nine cell-mates, with the server's
//! default avoidance for both and a new goal halfway. The cell-mates drive their own primitives (without avoiding
//! anything, so that their motion is the same in both runs) and are seen as the server sees them: a state every
//! refill (`stream::refill`, from `MIN_REFILL` with few streams to `MAX_REFILL` with many: both are checked),
//! extrapolated with its velocity in between; and as in the server, no knot is placed past the end of a refill.
//!
//! The deviations measured are in BENCHMARKS.md.

use std::time::Duration;

use dmp::Stepping;
use dmp::execution::{CellMate, IntegrationCost};
use dmp::field::Agent;
use dmp_sim::load::layout::{self, FOOTPRINT_RADIUS, OBSTACLE_RADIUS};
use dmp_sim::load::{DEFAULT_INTEGRATION_STEP_S, DEFAULT_INTEGRATION_TOLERANCE};

use super::pacing::{MAX_REFILL, MIN_REFILL};
use super::served_run::{RunAvoidance, ServedRun};
use crate::config::Defaults;

const TAU: f64 = 2.0;
const DT: f64 = 1e-3;
/// The load's default: the adaptive step, at most 30 ms.
const ADAPTIVE: (usize, Option<f64>) = (30, Some(DEFAULT_INTEGRATION_TOLERANCE));
// The step this test checks is the load's default.
const _: () = assert!(DEFAULT_INTEGRATION_STEP_S == ADAPTIVE.0 as f64 * DT);
/// A fixed RK4 step of 5 ms.
const FIXED: (usize, Option<f64>) = (5, None);
/// Seconds simulated: two legs of `tau`, the second to the robot's start.
const DURATION: f64 = 2.0 * TAU;

/// A cell-mate: its free motion at 1 ms (to its far goal, then back at `tau`), and its id.
struct Mate {
    id: String,
    x: Vec<f64>,
    xd: Vec<f64>,
}

impl Mate {
    fn new(r: &layout::RobotPlan) -> Self {
        let primitive = layout::primitive(r, TAU).unwrap();
        let mut integrator = dmp::Integrator::new(&primitive).unwrap();
        let mut motion = dmp::Motion { start: r.start.clone(), goal: r.goals[0].clone(), tau: TAU };
        let mut state = dmp::State::at_rest(&r.start);
        let mut acc = vec![0.0; 3];
        let (mut x, mut xd) = (Vec::new(), Vec::new());
        let steps = (DURATION / DT).round() as usize;
        for k in 0..=steps {
            if k == (TAU / DT) as usize {
                motion.goal = r.goals[1].clone();
            }
            x.extend_from_slice(&state.x);
            xd.extend_from_slice(&state.xd);
            integrator.step(&motion, &mut dmp::NoPerturbation, &mut state, DT, &mut acc);
        }
        Self { id: r.id.clone(), x, xd }
    }

    /// Its state at output point `k`, seen just now.
    fn seen_at<'a>(&'a self, k: usize, footprint: &'a dmp::Shape) -> CellMate<'a> {
        CellMate {
            id: &self.id,
            footprint,
            position: &self.x[3 * k..3 * k + 3],
            velocity: &self.xd[3 * k..3 * k + 3],
            age: 0.0,
        }
    }
}

fn ball(r: f64) -> dmp::Shape {
    dmp::Shape::Superquadric(dmp::Superquadric::ellipsoid(vec![r; 3]).unwrap())
}

/// The positions of robot `me` of a load cell over [`DURATION`] with RK4 at `step_points` ms, or the adaptive
/// step of at most `step_points` ms with `tolerance`, the cell-mates seen every `refill`; the smallest distance
/// from it to a cell-mate's centre, the largest from where it would be without anything to avoid, and the
/// integration's work.
fn run(
    me: usize,
    (step_points, tolerance): (usize, Option<f64>),
    refill: Duration,
) -> (Vec<f64>, f64, f64, IntegrationCost) {
    let robots = layout::robots(10, 10, 3, "acc");
    let robot = &robots[me];
    let primitive = layout::primitive(robot, TAU).unwrap();
    let defaults = Defaults::default();
    let fixed = (0..layout::FIXED_OBSTACLES)
        .map(|k| {
            let o = layout::fixed_obstacle(3, k, 0.0);
            dmp::Obstacle::new(o.id, ball(OBSTACLE_RADIUS), o.center, None, None).unwrap()
        })
        .collect();
    let avoidance = RunAvoidance {
        obstacles: (defaults.avoidance, 50),
        robots: (defaults.robot_avoidance, 50),
        extra: fixed,
        ignore_scene: true,
    };
    let member = Agent { id: robot.id.clone(), dims: vec![0, 1, 2], footprint: Some(ball(FOOTPRINT_RADIUS)) };
    let motion = dmp::Motion { start: robot.start.clone(), goal: robot.goals[0].clone(), tau: TAU };
    let stepping = Stepping { dt: DT, step_points, tolerance };
    let members = vec![(member, Some(layout::footprint(3)))];
    let mut run = ServedRun::new(primitive, motion, members, avoidance, stepping, 100).unwrap();
    let execution = &mut run.execution;
    let mate_footprint = ball(FOOTPRINT_RADIUS);
    let mates: Vec<Mate> = robots.iter().filter(|r| r.id != robot.id).map(Mate::new).collect();
    let mut x = Vec::new();
    let steps = (DURATION / DT).round() as usize;
    while x.len() / 3 < steps {
        let k = x.len() / 3;
        if k == (TAU / DT) as usize {
            execution.set_goal(robot.goals[1].clone()).unwrap();
        }
        // A cell-mate's state is read once per refill of the stream (the server's cadence).
        let refill_points = (refill.as_secs_f64() / DT).round() as usize;
        if k % refill_points == 0 {
            let t = k as f64 * DT;
            execution.set_cell_mates(mates.iter().map(|m| m.seen_at(k, &mate_footprint))).unwrap();
            execution.limit_knots_to(t + refill_points as f64 * DT);
        }
        x.extend(execution.advance(10).unwrap().x);
    }
    let mut closest = f64::INFINITY;
    for (k, p) in x.chunks_exact(3).enumerate() {
        for m in &mates {
            let d: f64 = (0..3).map(|i| (p[i] - m.x[3 * k + i]).powi(2)).sum();
            closest = closest.min(d.sqrt());
        }
    }
    let free = Mate::new(robot).x;
    let detour = x
        .chunks_exact(3)
        .zip(free.chunks_exact(3))
        .map(|(a, b)| a.iter().zip(b).map(|(p, q)| (p - q).powi(2)).sum::<f64>().sqrt())
        .fold(0.0, f64::max);
    (x, closest, detour, execution.cost())
}

#[test]
fn a_load_robot_with_the_adaptive_step_or_a_5ms_step_stays_within_1e3_of_rk4_at_1ms() {
    let mut worst_all = [0.0f64; 2];
    for refill in [MIN_REFILL, MAX_REFILL] {
        for me in [0, 3, 7] {
            let (reference, closest, detour, _) = run(me, (1, None), refill);
            // The avoidance is at work: the cell-mates push the robot far off its own straight line.
            assert!(detour > 0.1, "robot {me} hardly avoided anything ({detour} m)");
            let mut evaluations = [0; 2];
            for (k, step) in [ADAPTIVE, FIXED].into_iter().enumerate() {
                let (coarse, _, _, work) = run(me, step, refill);
                assert_eq!(reference.len(), coarse.len());
                let worst = reference.iter().zip(&coarse).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
                println!(
                    "refill {refill:?}, robot {me}, step {step:?}: largest deviation from RK4 at 1 ms \
                     {worst:.3e}, {work:?}, closest cell-mate {closest:.3} m, detour {detour:.3} m"
                );
                assert!(worst <= 1e-3, "robot {me}, {step:?}, refill {refill:?}: {worst}");
                assert!(worst > 0.0, "a coarse step is not the 1 ms rollout itself");
                worst_all[k] = worst_all[k].max(worst);
                evaluations[k] = work.evaluations;
            }
            // What the adaptive step is for: at least twice fewer evaluations of the field than RK4 at 5 ms.
            assert!(2 * evaluations[0] < evaluations[1], "robot {me}: {evaluations:?}");
        }
    }
    println!("largest deviation over the robots: adaptive {:.3e}, 5 ms {:.3e}", worst_all[0], worst_all[1]);
}
