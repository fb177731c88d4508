//! Changes without jumps, and limits that are always kept: a goal change is filtered, obstacles that appear are
//! blended in, and no setpoint exceeds the robot's profile, measured as backward finite differences of the
//! positions at the output rate over everything handed out (superseded points left out, as a robot sees them).

use std::sync::LazyLock;

use dmp::execution::CellMateAvoidance;
use dmp::{
    Avoidance, Demonstration, Execution, LearnConfig, Limits, Motion, Outcome, Primitive, Scene, Stepping,
    learn,
};
use proptest::prelude::*;
use proptest::test_runner::RngSeed;

use crate::fixtures::{config, dist, dynamic_volumetric, ellipsoid};

const DT: f64 = 1e-3;

/// A minimum-jerk reach of 2 s from (0.3, 0, 0.4) to (0.6, 0.2, 0.5), sampled at 1 kHz, learned with the paper's
/// settings.
static REACH: LazyLock<Primitive> = LazyLock::new(|| reach_of([0.3, 0.2, 0.1], 2.0));

/// A minimum-jerk reach of `seconds` by `way` from (0.3, 0, 0.4), sampled at 1 kHz, learned with the paper's
/// settings.
fn reach_of(way: [f64; 3], seconds: f64) -> Primitive {
    let a = [0.3, 0.0, 0.4];
    let n = (seconds / 1e-3).round() as usize;
    let t: Vec<f64> = (0..=n).map(|k| k as f64 * 1e-3).collect();
    let x = t
        .iter()
        .map(|&t| {
            let u = t / seconds;
            let c = u * u * u * (10.0 - 15.0 * u + 6.0 * u * u);
            (0..3).map(|i| a[i] + way[i] * c).collect()
        })
        .collect();
    learn(&Demonstration::new(t, x).unwrap(), &LearnConfig::paper()).unwrap()
}

/// What the robot received: the points kept, `dim` each, from time zero, one output step apart.
#[derive(Default)]
struct Received {
    x: Vec<f64>,
    /// The accelerations handed out with the points.
    xdd: Vec<f64>,
    /// The obstacle that appeared: the index of the first point after it, its centre and radius.
    appeared: Option<(usize, Vec<f64>, f64)>,
}

impl Received {
    /// Drops the points at or after `t` (superseded), then appends `stretch`.
    fn supersede(&mut self, t: f64, x: &[f64], dim: usize) {
        let keep = ((t / DT).round() as usize) * dim;
        self.x.truncate(keep);
        self.x.extend_from_slice(x);
    }

    /// The same for the accelerations.
    fn supersede_acc(&mut self, t: f64, xdd: &[f64], dim: usize) {
        self.xdd.truncate(((t / DT).round() as usize) * dim);
        self.xdd.extend_from_slice(xdd);
    }

    /// The largest jerk of the accelerations handed out (their differences), dimensions `0..dim`.
    fn reported_jerk(&self, dim: usize) -> f64 {
        self.xdd
            .chunks_exact(dim)
            .collect::<Vec<_>>()
            .windows(2)
            .map(|w| w[1].iter().zip(w[0]).map(|(b, a)| ((b - a) / DT).powi(2)).sum::<f64>().sqrt())
            .fold(0.0, f64::max)
    }

    /// Peak speed, acceleration and jerk of dimensions `dims` as backward differences, the robot at rest at its
    /// first point before it.
    fn peaks(&self, dim: usize, dims: std::ops::Range<usize>) -> [f64; 3] {
        let n = self.x.len() / dim;
        let p = |k: isize| -> Vec<f64> {
            let k = k.max(0) as usize;
            dims.clone().map(|i| self.x[k * dim + i]).collect()
        };
        let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        let mut peak = [0.0f64; 3];
        for k in 0..n as isize {
            let (p0, p1, p2, p3) = (p(k), p(k - 1), p(k - 2), p(k - 3));
            let d = p0.len();
            let v: Vec<f64> = (0..d).map(|i| (p0[i] - p1[i]) / DT).collect();
            let a: Vec<f64> = (0..d).map(|i| (p0[i] - 2.0 * p1[i] + p2[i]) / (DT * DT)).collect();
            let j: Vec<f64> =
                (0..d).map(|i| (p0[i] - 3.0 * p1[i] + 3.0 * p2[i] - p3[i]) / (DT * DT * DT)).collect();
            for (m, q) in peak.iter_mut().zip([norm(&v), norm(&a), norm(&j)]) {
                *m = m.max(q);
            }
        }
        peak
    }
}

fn run(p: &Primitive, scene: Scene, stepping: Stepping) -> Execution {
    Execution::new(p.clone(), Motion::of(p), scene, CellMateAvoidance::NONE, stepping, 5000).unwrap()
}

/// The reach streamed at 1 kHz in 10 ms segments, its goal moved by 0.3 m at 0.8 s; the points received and the
/// last outcome.
fn reach_with_goal_change(limits: Option<Limits>, alpha: Option<f64>) -> (Received, Outcome, Execution) {
    let p = &*REACH;
    let mut e = run(p, Scene::empty(), Stepping::rk4(DT));
    if let Some(l) = limits {
        e.set_limits(l, false).unwrap();
    }
    if let Some(a) = alpha {
        e.set_goal_filter(a).unwrap();
    }
    let mut got = Received::default();
    let mut outcome = Outcome::Running;
    for seg in 0..800 {
        if seg == 80 {
            let g: Vec<f64> = p.goal.iter().zip([0.0, 0.3, 0.0]).map(|(g, d)| g + d).collect();
            e.set_goal(g).unwrap();
        }
        let s = e.advance(10).unwrap();
        got.supersede(s.start_time, &s.x, 3);
        outcome = s.outcome;
        if outcome.is_final() {
            break;
        }
    }
    (got, outcome, e)
}

#[test]
fn an_unfiltered_goal_change_jumps_and_the_filter_and_the_limits_keep_the_panda_profile() {
    let l = Limits::PANDA;
    let (step, _, _) = reach_with_goal_change(None, Some(0.0));
    let [v, a, j] = step.peaks(3, 0..3);
    eprintln!("goal step, no filter, no limits: {v:.3} m/s, {a:.1} m/s², {j:.0} m/s³");
    assert!(a > 2.0 * l.max_acceleration && j > 2.0 * l.max_jerk, "the problem of the issue: {a} {j}");

    let (filtered, _, _) = reach_with_goal_change(None, None);
    let [v, a, j] = filtered.peaks(3, 0..3);
    eprintln!("goal filtered (default alpha_g), no limits: {v:.3} m/s, {a:.2} m/s², {j:.1} m/s³");

    let (limited, outcome, e) = reach_with_goal_change(Some(l), None);
    let [v, a, j] = limited.peaks(3, 0..3);
    eprintln!(
        "goal filtered, Panda limits: {v:.3} m/s, {a:.2} m/s², {j:.1} m/s³; tau scale {}",
        e.tau_scale()
    );
    assert!(v <= l.max_speed && a <= l.max_acceleration && j <= l.max_jerk, "{v} {a} {j}");
    assert_eq!(outcome, Outcome::GoalReached);
    assert!(dist(&e.motion().goal, &limited.x[limited.x.len() - 3..]) <= 1e-3);

    // Unfiltered but limited: still within the profile, and still reaches the new goal.
    let (hard, outcome, _) = reach_with_goal_change(Some(l), Some(0.0));
    let [v, a, j] = hard.peaks(3, 0..3);
    eprintln!("goal step, Panda limits: {v:.3} m/s, {a:.2} m/s², {j:.1} m/s³");
    assert!(v <= l.max_speed && a <= l.max_acceleration && j <= l.max_jerk, "{v} {a} {j}");
    assert_eq!(outcome, Outcome::GoalReached);
}

/// One random stream of the property test: a reach, a goal change and an obstacle that appears, each superseding
/// the last points handed out, as a real-time stream does.
#[derive(Debug, Clone)]
struct Case {
    goal: [f64; 3],
    new_goal: [f64; 3],
    tau: f64,
    change_at: f64,
    obstacle_at: Option<f64>,
    obstacle_radius: f64,
    rollback: usize,
    segment: usize,
    coarse: bool,
    alpha: Option<f64>,
    profile: usize,
    obstacle_rollback: usize,
    margin: f64,
}

/// The profiles of the property test.
const PROFILES: [Limits; 3] = [Limits::PANDA, Limits::DVRK_PSM, Limits::YOUBOT_BASE];

/// What a stream of `c` handed out, as the robot kept it, the execution at its end, and the index of the first
/// point of the last goal (0 when the goal did not change before the end).
fn stream(c: &Case, limits: Limits) -> (Received, Execution, usize) {
    stream_of(&REACH, c, limits)
}

/// [`stream`] of the primitive `p`.
fn stream_of(p: &Primitive, c: &Case, limits: Limits) -> (Received, Execution, usize) {
    let start = p.start.clone();
    let goal: Vec<f64> = start.iter().zip(c.goal).map(|(s, g)| s + g).collect();
    let new_goal: Vec<f64> = start.iter().zip(c.new_goal).map(|(s, g)| s + g).collect();
    let stepping = if c.coarse {
        Stepping { dt: DT, step_points: 20, tolerance: Some(3e-6) }
    } else {
        Stepping::rk4(DT)
    };
    let motion = Motion { start: start.clone(), goal, tau: c.tau };
    let scene = Scene::with_obstacles(Vec::new(), Avoidance::new(dynamic_volumetric(10.0, 2.0, 0.5)), 0);
    let mut e = Execution::new(p.clone(), motion, scene, CellMateAvoidance::NONE, stepping, 5000).unwrap();
    e.set_limits(limits, false).unwrap();
    e.set_margin(c.margin).unwrap();
    if let Some(a) = c.alpha {
        e.set_goal_filter(a).unwrap();
    }
    let mut got = Received::default();
    let (mut changed, mut appeared) = (false, false);
    let mut last_goal_from = 0;
    let end = 2.0 * c.tau + 2.0;
    while e.time() < end {
        let s = e.advance(c.segment).unwrap();
        got.supersede(s.start_time, &s.x, 3);
        got.supersede_acc(s.start_time, &s.xdd, 3);
        if s.outcome.is_final() {
            break;
        }
        let t = e.time();
        if !changed && t >= c.change_at {
            changed = true;
            let back = e.rollback_to(t - (c.rollback.min(c.segment) as f64) * DT);
            e.set_goal(new_goal.clone()).unwrap();
            last_goal_from = (back / DT).round() as usize;
        }
        if let Some(at) = c.obstacle_at
            && !appeared
            && t >= at
        {
            appeared = true;
            let back = e.rollback_to(t - (c.obstacle_rollback.min(c.segment) as f64) * DT);
            // Right in front: ahead on the way to the goal.
            let x = &got.x[got.x.len() - 3..];
            let centre: Vec<f64> = (0..3).map(|i| x[i] + 0.3 * (e.motion().goal[i] - x[i])).collect();
            let o = ellipsoid("ball", &centre, &[c.obstacle_radius; 3]);
            e.set_obstacles([(&o, 0.0)]).unwrap();
            got.appeared = Some(((back / DT).round() as usize, centre, c.obstacle_radius));
        }
    }
    (got, e, last_goal_from)
}

/// How far the points from `from` on pass the goal `g`: the largest `(x - g) . u`, with `u` the unit vector from
/// the point at `from` to the goal, and the distance from that point to the goal.
fn overshoot(got: &Received, from: usize, g: &[f64]) -> (f64, f64) {
    let x0 = &got.x[from * 3..from * 3 + 3];
    let reach = dist(x0, g);
    if reach < 1e-9 {
        return (0.0, 0.0);
    }
    let u: Vec<f64> = (0..3).map(|i| (g[i] - x0[i]) / reach).collect();
    let past = got.x[from * 3..]
        .chunks_exact(3)
        .map(|x| (0..3).map(|i| (x[i] - g[i]) * u[i]).sum::<f64>())
        .fold(0.0, f64::max);
    (past, reach)
}

fn case() -> impl Strategy<Value = Case> {
    (
        (
            prop::array::uniform3(-0.4f64..0.4),
            prop::array::uniform3(-0.4f64..0.4),
            0.4f64..3.0,
            0.05f64..1.5,
            prop::option::of(0.05f64..1.5),
            0.03f64..0.15,
        ),
        (0usize..30, 5usize..60, any::<bool>(), prop::option::of(0.0f64..40.0), 0usize..3, 0usize..30),
        prop_oneof![Just(0.0), 0.005f64..0.03],
    )
        .prop_map(
            |(
                (goal, new_goal, tau, change_at, obstacle_at, obstacle_radius),
                (rollback, segment, coarse, alpha, profile, obstacle_rollback),
                margin,
            )| Case {
                goal,
                new_goal,
                tau,
                change_at,
                obstacle_at,
                obstacle_radius,
                rollback,
                segment,
                coarse,
                alpha,
                profile,
                obstacle_rollback,
                margin,
            },
        )
}

/// The property tests' configuration, from a fixed seed unless `PROPTEST_RNG_SEED` is set: a random search over
/// the profiles finds rare corners (see the issue tracker), and CI runs the same cases every time.
fn seeded(cases: u32) -> ProptestConfig {
    let base = config(cases);
    let fixed = std::env::var_os("PROPTEST_RNG_SEED").is_none();
    ProptestConfig { rng_seed: if fixed { RngSeed::Fixed(33) } else { base.rng_seed }, ..base }
}

proptest! {
    #![proptest_config(seeded(12))]

    /// Random goals, taus, goal changes, obstacles appearing on the way, rollbacks (a change superseding points
    /// already handed out), steppings and segment lengths, at the Panda's, the PSM's and the youBot's profiles:
    /// every point the robot keeps is within the profile.
    #[test]
    fn no_setpoint_ever_exceeds_the_profile(c in case()) {
        let (got, _, _) = stream(&c, PROFILES[c.profile]);
        let l = PROFILES[c.profile];
        let [v, a, j] = got.peaks(3, 0..3);
        prop_assert!(
            v <= l.max_speed && a <= l.max_acceleration && j <= l.max_jerk,
            "peaks {v} m/s, {a} m/s², {j} m/s³"
        );
        // The accelerations handed out agree with the positions: they change by no more than the jerk allows
        // either (a controller that feeds them forward sees no step where the limiter takes over or lets go).
        let reported = got.reported_jerk(3);
        prop_assert!(reported <= l.max_jerk, "the handed-out accelerations jump: {reported} m/s³");
    }

    /// The same streams with a safety distance: where the obstacle appeared more than a braking distance beyond the
    /// margin (and the robot could stop), no point the robot keeps comes closer to its true shape than the margin.
    #[test]
    fn an_obstacle_that_appears_beyond_braking_is_kept_at_the_margin(c in case()) {
        let c = Case { margin: c.margin.max(0.005), obstacle_at: Some(c.obstacle_at.unwrap_or(0.3)), ..c };
        let l = PROFILES[c.profile];
        let (got, _, _) = stream(&c, l);
        let Some((from, centre, radius)) = got.appeared.clone() else { return Ok(()) };
        let clearance = |k: usize| dist(&got.x[k * 3..k * 3 + 3], &centre) - radius;
        // The state where it appeared, as the robot kept it: the braking distance's bound from there.
        let k = from.saturating_sub(1).max(2);
        let v = dist(&got.x[k * 3..k * 3 + 3], &got.x[(k - 1) * 3..k * 3]) / DT;
        let a = (0..3)
            .map(|i| (got.x[k * 3 + i] - 2.0 * got.x[(k - 1) * 3 + i] + got.x[(k - 2) * 3 + i]) / (DT * DT))
            .map(|x| x * x)
            .sum::<f64>()
            .sqrt();
        let (am, jm) = (l.max_acceleration, l.max_jerk);
        let vp = v + a * a / (2.0 * jm);
        let braking = vp * a / jm + vp * vp / (2.0 * am) + vp * am / (2.0 * jm) + vp * DT;
        prop_assume!(clearance(k) > c.margin + braking);
        let n = got.x.len() / 3;
        let closest = (from..n).map(clearance).fold(f64::INFINITY, f64::min);
        prop_assert!(
            closest >= c.margin - 1e-9,
            "came {closest} m from the ball with a margin of {} m (it appeared {} m away)",
            c.margin,
            clearance(k)
        );
    }

    /// Straight reaches (each learned from a minimum-jerk demonstration of 0.05 to 0.8 m, replayed at tau 0.05 to
    /// 2 s) at the three profiles: never past the goal by more than max(1 mm, 0.5 % of the reach).
    #[test]
    fn a_limited_reach_never_passes_its_goal(
        length in 0.05f64..0.8,
        tau in 0.05f64..2.0,
        profile in 0usize..3,
    ) {
        let way = [0.3, 0.2, 0.1];
        let norm = dist(&way, &[0.0; 3]);
        let goal = way.map(|w| w / norm * length);
        let c = Case {
            goal,
            new_goal: goal,
            tau,
            change_at: f64::INFINITY,
            obstacle_at: None,
            obstacle_radius: 0.03,
            rollback: 0,
            segment: 10,
            coarse: false,
            alpha: None,
            profile,
            obstacle_rollback: 0,
            margin: 0.0,
        };
        let (got, e, _) = stream_of(&reach_of(goal, 1.0), &c, PROFILES[profile]);
        let (past, reach) = overshoot(&got, 0, &e.motion().goal);
        prop_assert!(past <= (0.005 * reach).max(1e-3), "{past} m past the goal after a reach of {reach} m");
    }
}

/// An obstacle appears ahead of the reach at 0.8 s; the time from then until the path leaves the obstacle-free one by
/// 1 mm, and the smallest clearance to the ball, with the obstacle applied at once and blended in over `blend`.
fn reaction(blend: f64, radius: f64) -> (f64, f64) {
    let p = &*REACH;
    let scene = Scene::with_obstacles(Vec::new(), Avoidance::new(dynamic_volumetric(10.0, 2.0, 0.5)), 0);
    let free = {
        let mut e = run(p, scene.clone(), Stepping::rk4(DT));
        e.advance(3000).unwrap().x
    };
    let mut e = run(p, scene, Stepping::rk4(DT));
    e.set_obstacle_blend(blend).unwrap();
    let mut x = e.advance(800).unwrap().x;
    let here = &x[x.len() - 3..];
    let c: Vec<f64> = (0..3).map(|i| here[i] + 0.4 * (p.goal[i] - here[i])).collect();
    e.set_obstacles([(&ellipsoid("ball", &c, &[radius; 3]), 0.0)]).unwrap();
    x.extend(e.advance(2200).unwrap().x);
    let deviates = (800..3000).find(|&k| dist(&x[3 * k..3 * k + 3], &free[3 * k..3 * k + 3]) > 1e-3);
    let reaction = deviates.map_or(f64::INFINITY, |k| (k - 800) as f64 * DT);
    let clearance =
        (800..3000).map(|k| dist(&x[3 * k..3 * k + 3], &c) - radius).fold(f64::INFINITY, f64::min);
    (reaction, clearance)
}

/// What blending an obstacle in costs: the reaction to an obstacle that appears comes later, by about a third of the
/// blend time here, and the clearance shrinks a little.
#[test]
fn blending_an_obstacle_in_delays_the_reaction_by_less_than_the_blend_time() {
    for radius in [0.03, 0.06] {
        let (now, now_clear) = reaction(0.0, radius);
        let (blended, blended_clear) = reaction(dmp::execution::DEFAULT_OBSTACLE_BLEND, radius);
        eprintln!(
            "ball of {radius} m: 1 mm off the free path after {:.0} ms at once, {:.0} ms blended; clearance \
             {:.1} mm, {:.1} mm",
            now * 1e3,
            blended * 1e3,
            now_clear * 1e3,
            blended_clear * 1e3
        );
        assert!(now.is_finite() && blended >= now && blended - now <= dmp::execution::DEFAULT_OBSTACLE_BLEND);
        assert!(now_clear > 0.0 && blended_clear > 0.0);
    }
}
