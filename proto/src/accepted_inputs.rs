//! Random inputs inside every range of [`dmp::ranges`] (obstacles of every shape, primitives, motions, all five
//! avoidance methods, groups with footprints), through the wire conversions and an [`Execution`] for a few
//! stretches: nothing panics, every conversion accepts them, every output is finite, and a single robot's run never
//! fails (an obstacle whose term is not finite is dropped and reported instead).

use dmp::execution::{CellMateAvoidance, GroupMember, join_group};
use dmp::field::{Agent, Scene};
use dmp::ranges;
use dmp::{Execution, Motion, Stepping};
use proptest::prelude::*;

use crate::avoidance::avoidance_from_proto;
use crate::obstacle::obstacle_to_engine;
use crate::primitive::primitive_from_proto;
use crate::shape::superquadric_to_shape;
use crate::v1;

/// Half-width of the workspace the inputs are drawn in (the server's default).
const WORKSPACE_M: f64 = 1000.0;

/// A value in `[lo, hi]` spread over its decades (`lo > 0`).
fn log_uniform(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    (lo.ln()..=hi.ln()).prop_map(|l| l.exp())
}

/// A coordinate: mostly near the robot, sometimes anywhere in the workspace.
fn coordinate() -> impl Strategy<Value = f64> {
    prop_oneof![4 => -2.0f64..2.0, 1 => -WORKSPACE_M..=WORKSPACE_M]
}

fn semi_axis() -> impl Strategy<Value = f64> {
    log_uniform(*ranges::SEMI_AXIS_M.start(), *ranges::SEMI_AXIS_M.end())
}

fn exponent() -> impl Strategy<Value = f64> {
    prop_oneof![1.0f64..=*ranges::EXPONENT.end(), (1u32..=8).prop_map(f64::from)]
}

fn superquadric(d: usize) -> impl Strategy<Value = v1::Superquadric> {
    (prop::collection::vec(semi_axis(), d), prop::collection::vec(exponent(), d))
        .prop_map(|(semi_axes, exponents)| v1::Superquadric { semi_axes, exponents })
}

/// A rotation of `d = 2` or `3` dimensions by `angle` (about z in 3-D), row-major.
fn rotation(d: usize, angle: f64) -> Vec<f64> {
    let (s, c) = angle.sin_cos();
    if d == 2 { vec![c, -s, s, c] } else { vec![c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0] }
}

/// An obstacle of dimension `d`: a superquadric, or in 3-D also a nested superquadric or a solid.
fn obstacle(d: usize) -> impl Strategy<Value = v1::Obstacle> {
    use v1::obstacle::Shape;
    let solid_dim = log_uniform(*ranges::SOLID_DIMENSION_M.start(), *ranges::SOLID_DIMENSION_M.end());
    let shape = if d == 3 {
        prop_oneof![
            superquadric(3).prop_map(Shape::Superquadric),
            (prop::collection::vec(semi_axis(), 3), exponent(), exponent())
                .prop_map(|(semi_axes, n, m)| Shape::Nested(v1::NestedSuperquadric { semi_axes, n, m })),
            (1i32..=3, prop::collection::vec(solid_dim, 3)).prop_map(|(t, mut dims)| {
                dims.truncate([0, 3, 1, 2][t as usize]);
                Shape::Solid(v1::SolidPrimitive { r#type: t, dimensions: dims })
            }),
        ]
        .boxed()
    } else {
        superquadric(d).prop_map(Shape::Superquadric).boxed()
    };
    let margin = prop_oneof![Just(0.0), log_uniform(1e-3, *ranges::MARGIN_M.end())];
    let speed = 0.0..=*ranges::SPEED_MPS.end();
    (
        shape,
        prop::collection::vec(coordinate(), d),
        margin,
        prop::option::of(-3.2f64..3.2),
        (speed, prop::collection::vec(-1.0f64..1.0, d)),
    )
        .prop_map(move |(shape, center, margin, angle, (speed, dir))| {
            let n = dir.iter().map(|v| v * v).sum::<f64>().sqrt().max(1e-9);
            v1::Obstacle {
                id: String::new(),
                shape: Some(shape),
                center,
                margin,
                rotation: angle.map(|a| rotation(d, a)).unwrap_or_default(),
                velocity: dir.iter().map(|v| v / n * speed).collect(),
                ..Default::default()
            }
        })
}

/// One of the five methods (or none), with parameters in their ranges.
fn avoidance() -> impl Strategy<Value = v1::Avoidance> {
    use v1::avoidance::{self as a, Method};
    let gain = || log_uniform(*ranges::GAIN.start(), *ranges::GAIN.end());
    let beta = || 1.0..=*ranges::ANGULAR_EXPONENT.end();
    let method = prop_oneof![
        Just(Method::None(a::None {})),
        (gain(), log_uniform(*ranges::INFLUENCE_M.start(), *ranges::INFLUENCE_M.end()))
            .prop_map(|(eta, p0)| Method::StaticPoint(a::StaticPoint { eta, p0 })),
        (gain(), beta()).prop_map(|(lambda, beta)| Method::DynamicPoint(a::DynamicPoint { lambda, beta })),
        (gain(), 0.0..=*ranges::STEERING_DECAY.end())
            .prop_map(|(gamma, beta)| Method::SteeringAngle(a::SteeringAngle { gamma, beta })),
        (gain(), log_uniform(*ranges::VOLUME_DECAY.start(), *ranges::VOLUME_DECAY.end()))
            .prop_map(|(a, eta)| Method::StaticVolumetric(a::StaticVolumetric { a, eta })),
        (gain(), beta(), log_uniform(*ranges::C_EXPONENT.start(), *ranges::C_EXPONENT.end())).prop_map(
            |(lambda, beta, eta)| Method::DynamicVolumetric(a::DynamicVolumetric { lambda, beta, eta })
        ),
    ];
    (method, any::<bool>(), 1u32..=16).prop_map(|(method, ignore_obstacle_velocity, point_samples)| {
        v1::Avoidance { method: Some(method), ignore_obstacle_velocity, point_samples }
    })
}

/// A primitive of dimension `d` that RK4 at `dt` runs stably: `K` in its range, `tau` above the stability bound,
/// `D` at most critical, weights anywhere in their range.
fn primitive(d: usize, dt: f64) -> impl Strategy<Value = v1::Primitive> {
    let n = 1usize..=30;
    let alpha = log_uniform(*ranges::ALPHA.start(), *ranges::ALPHA.end());
    let k = log_uniform(*ranges::STIFFNESS.start(), 1e6);
    (n, alpha, k, 0.0f64..=1.0, 0.0f64..=1.0, prop::collection::vec(coordinate(), 2 * d)).prop_flat_map(
        move |(n, alpha, k, damping, tau_at, ends)| {
            let tau_min = (dt * k.sqrt() / dmp::execution::MAX_STIFF_STEP * 1.01).max(1e-3);
            let tau = tau_min * (1e2 / tau_min).powf(tau_at);
            let weight = prop_oneof![-1e3f64..1e3, -*ranges::WEIGHT.end()..=*ranges::WEIGHT.end()];
            prop::collection::vec(weight, d * (n + 1)).prop_map(move |weights| v1::Primitive {
                format_version: dmp::primitive::FORMAT_VERSION,
                dim: d as u32,
                n_basis: n as u32,
                alpha,
                k: vec![k; d],
                d: vec![(2.0 * k.sqrt() * damping).min(*ranges::DAMPING.end()); d],
                tau,
                start: ends[..d].to_vec(),
                goal: ends[d..].to_vec(),
                weights,
                ..Default::default()
            })
        },
    )
}

fn stepping() -> impl Strategy<Value = Stepping> {
    prop_oneof![
        Just(Stepping::rk4(0.01)),
        Just(Stepping { dt: 0.01, step_points: 5, tolerance: None }),
        Just(Stepping { dt: 0.01, step_points: 10, tolerance: Some(1e-4) }),
    ]
}

/// Everything one case runs: the robot's dimension, its primitive, the run's own and the cell's obstacles (some of
/// another dimension), the methods, a second group member's footprint.
#[derive(Debug, Clone)]
struct Case {
    primitive: v1::Primitive,
    extra: Vec<v1::Obstacle>,
    cell: Vec<(v1::Obstacle, f64)>,
    avoidance: v1::Avoidance,
    robot_avoidance: v1::Avoidance,
    group: Option<(v1::Superquadric, v1::Superquadric)>,
    stepping: Stepping,
}

fn case() -> impl Strategy<Value = Case> {
    (2usize..=3, stepping()).prop_flat_map(|(d, stepping)| {
        let other = 5 - d;
        (
            primitive(d, stepping.internal_step()),
            prop::collection::vec(obstacle(d), 0..3),
            prop::collection::vec((prop_oneof![4 => obstacle(d), 1 => obstacle(other)], 0.0f64..2.0), 0..4),
            avoidance(),
            avoidance(),
            prop::option::of((superquadric(d), superquadric(d))),
            Just(stepping),
        )
            .prop_map(|(primitive, extra, cell, avoidance, robot_avoidance, group, stepping)| Case {
                primitive,
                extra,
                cell,
                avoidance,
                robot_avoidance,
                group,
                stepping,
            })
    })
}

/// Converts a case as the server does and builds its run; every conversion must accept the case.
fn run_of(c: &Case) -> Result<(Execution, Vec<dmp::Obstacle>), TestCaseError> {
    let p = primitive_from_proto(&c.primitive).map_err(|e| TestCaseError::fail(format!("primitive: {e}")))?;
    let named = |o: &v1::Obstacle, id: String| v1::Obstacle { id, ..o.clone() };
    let convert =
        |o: v1::Obstacle| obstacle_to_engine(&o).map_err(|e| TestCaseError::fail(format!("{o:?}: {e}")));
    let extra = c
        .extra
        .iter()
        .enumerate()
        .map(|(i, o)| convert(named(o, format!("extra{i}"))))
        .collect::<Result<Vec<_>, _>>()?;
    let cell = c
        .cell
        .iter()
        .enumerate()
        .map(|(i, (o, _))| convert(named(o, format!("cell{i}"))))
        .collect::<Result<Vec<_>, _>>()?;
    let none = dmp::Avoidance::NONE;
    let (av, samples) =
        avoidance_from_proto(Some(&c.avoidance), none).map_err(|e| TestCaseError::fail(e.to_string()))?;
    let (rav, rsamples) = avoidance_from_proto(Some(&c.robot_avoidance), none)
        .map_err(|e| TestCaseError::fail(e.to_string()))?;
    let motion = Motion::of(&p);
    let (primitive, motion, agents) = match &c.group {
        None => (p, motion, Vec::new()),
        Some((fa, fb)) => {
            let shape = |f: &v1::Superquadric| {
                superquadric_to_shape(f).map_err(|e| TestCaseError::fail(e.to_string()))
            };
            let (fa, fb) = (shape(fa)?, shape(fb)?);
            let mut other = motion.clone();
            other.start.iter_mut().for_each(|x| *x += 1.0);
            other.goal.iter_mut().for_each(|x| *x -= 1.0);
            let members = [
                GroupMember { id: "a", primitive: &p, motion: &motion, footprint: Some(&fa) },
                GroupMember { id: "b", primitive: &p, motion: &other, footprint: Some(&fb) },
            ];
            join_group(&members, None).map_err(|e| TestCaseError::fail(e.to_string()))?
        }
    };
    let agents: Vec<Agent> = agents;
    let scene = Scene {
        obstacles: extra,
        avoidance: av,
        agents,
        robot_avoidance: rav,
        point_samples: samples.max(rsamples),
    };
    let mates = CellMateAvoidance { method: rav, point_samples: rsamples };
    let e = Execution::new(primitive, motion, scene, mates, c.stepping, 50)
        .map_err(|e| TestCaseError::fail(format!("run: {e}")))?;
    Ok((e, cell))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn accepted_inputs_never_panic_and_every_output_is_finite(c in case()) {
        let (mut e, cell) = run_of(&c)?;
        for k in 0..6 {
            if k == 2 {
                e.set_obstacles(cell.iter().zip(&c.cell).map(|(o, (_, age))| (o, *age)))
                    .map_err(|err| TestCaseError::fail(format!("set_obstacles: {err}")))?;
            }
            let s = match e.advance(15) {
                Ok(s) => s,
                // The members of a group repel each other with terms that are not obstacles and cannot be dropped:
                // with extreme values (an undamped DMP at tau = 5 ms, pushed apart at the perturbation's cap) they
                // can leave the reach and the run fails with a typed error, never a panic.
                Err(dmp::DmpError::Diverged { .. }) if c.group.is_some() => break,
                Err(err) => return Err(TestCaseError::fail(format!("stretch {k}: {err}"))),
            };
            prop_assert!(s.x.iter().chain(&s.xd).chain(&s.xdd).all(|v| v.is_finite()));
            for i in &s.ignored {
                prop_assert!(!i.reason.is_empty() && !i.id.is_empty());
            }
        }
    }
}
