//! Replaying a demonstration.

use std::f64::consts::PI;

use dmp::{LearnConfig, Motion, Primitive, learn, rollout};
use proptest::prelude::*;

use crate::fixtures::{
    PAPER, config, demo_of, dist, empty_field, last_position, paper_curve, span, uniform_times,
};

/// Learns `curve` sampled every millisecond over `[t0, t0 + duration]`, rolls it out at 1 ms with no
/// obstacle, and checks the replay: the largest deviation after the first 10 % of the time is within 1e-2 of
/// the span, and the end point is within 1e-3 of the span of the goal. Returns the relative deviation.
fn assert_replays(label: &str, t0: f64, duration: f64, curve: impl Fn(f64) -> Vec<f64>) -> f64 {
    let n = (duration / 1e-3).round() as usize;
    let times: Vec<f64> = (0..=n).map(|k| t0 + k as f64 * 1e-3).collect();
    let demo = demo_of(&times, &curve);
    let p = learn(&demo, &LearnConfig::paper()).unwrap();
    assert!((p.tau - duration).abs() < 1e-9);
    let dim = demo.dim();
    let r = rollout(&p, &Motion::of(&p), &empty_field(dim), 1e-3, n).unwrap();
    assert!(r.trajectory.is_finite());
    let span = span(demo.positions());
    let dev = (0..=n)
        .filter(|&k| k as f64 >= 0.1 * n as f64)
        .map(|k| dist(r.trajectory.position(k), &demo.positions()[k]))
        .fold(0.0, f64::max);
    let goal = &demo.positions()[n];
    let end = dist(last_position(&r), goal);
    eprintln!(
        "replay {label}: span {span:.3}, max deviation after 10 % {dev:.3e} ({:.2e} of the span), \
         end {end:.2e} from the goal",
        dev / span
    );
    assert!(dev <= 1e-2 * span, "{label}: deviation {dev} for a span of {span}");
    assert!(end <= 1e-3 * span, "{label}: ends {end} from the goal");
    dev / span
}

#[test]
fn a_learned_primitive_replays_the_papers_curve() {
    assert_replays("paper 2-D", 0.0, 1.0, paper_curve);
}

#[test]
fn a_learned_primitive_replays_a_3d_demonstration_of_two_seconds() {
    // The paper's spiral, lifted along z, played over two seconds (so tau = 2).
    assert_replays("3-D, 2 s", 0.0, 2.0, |t| {
        let u = t / 2.0;
        vec![u * (PI * u).cos(), u * (PI * u).sin(), 0.4 * (PI * u).sin().powi(2) + 0.2 * u]
    });
}

#[test]
fn a_learned_primitive_replays_a_1d_demonstration_that_does_not_start_at_zero() {
    assert_replays("1-D, t in [5, 6.5]", 5.0, 1.5, |t| {
        let u = (t - 5.0) / 1.5;
        vec![0.5 * (1.0 - (PI * u).cos()) + 0.2 * (3.0 * PI * u).sin()]
    });
}

/// Positions of a no-obstacle rollout, row-major.
fn free_rollout(p: &Primitive, dt: f64, steps: usize) -> Vec<f64> {
    rollout(p, &Motion::of(p), &empty_field(p.dim), dt, steps).unwrap().trajectory.x
}

proptest! {
    #![proptest_config(config(12))]

    /// Random increasing sample times (each of `n` intervals jittered by up to 45 % of its nominal length)
    /// learn the same motion as the uniform 1 ms sampling.
    #[test]
    fn a_non_uniformly_sampled_demonstration_learns_the_same_curve(
        n in 400usize..1500,
        jitter in prop::collection::vec(-0.45f64..0.45, 1500),
    ) {
        a_non_uniformly_sampled_demonstration_learns_the_same_curve_case(n, jitter)?;
    }
}

fn a_non_uniformly_sampled_demonstration_learns_the_same_curve_case(
    n: usize,
    jitter: Vec<f64>,
) -> Result<(), TestCaseError> {
    let mut times: Vec<f64> =
        (0..=n).map(|k| (k as f64 + if k == 0 || k == n { 0.0 } else { jitter[k] }) / n as f64).collect();
    times[n] = 1.0;
    let p = learn(&demo_of(&times, paper_curve), &LearnConfig::paper()).unwrap();
    prop_assert!((p.tau - 1.0).abs() < 1e-12);
    let (a, b) = (free_rollout(&PAPER, 1e-3, 1000), free_rollout(&p, 1e-3, 1000));
    let dev = a.chunks(2).zip(b.chunks(2)).map(|(a, b)| dist(a, b)).fold(0.0, f64::max);
    let span = span(demo_of(&uniform_times(), paper_curve).positions());
    eprintln!(
        "non-uniform sampling, {n} intervals: max difference from the uniform one {:.2e} of the span",
        dev / span
    );
    prop_assert!(dev <= 5e-4 * span, "difference {} for a span of {}", dev, span);
    Ok(())
}
