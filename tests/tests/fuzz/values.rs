//! Strategies for numbers, names and v1 messages. Every message is built at a "wildness": the share (percent) of
//! its numbers drawn from the extremes (NaN, infinities, 1e300, 1e-300, -0.0, subnormals ...) rather than from
//! plausible ranges, so that some cases go deep into the handlers and others probe every check.

use proptest::collection::vec;
use proptest::prelude::*;

use dmp_proto::v1;

/// The extremes of `f64`, and any bit pattern.
pub fn extreme() -> BoxedStrategy<f64> {
    prop_oneof![
        Just(f64::NAN),
        Just(f64::INFINITY),
        Just(f64::NEG_INFINITY),
        Just(1e300),
        Just(-1e300),
        Just(1e-300),
        Just(-1e-300),
        Just(-0.0),
        Just(0.0),
        Just(5e-324),
        Just(f64::MIN_POSITIVE),
        Just(f64::MAX),
        Just(f64::MIN),
        Just(1e15),
        Just(-1e6),
        any::<f64>(),
    ]
    .boxed()
}

/// A number in `sane`, or an extreme `wild` percent of the time.
fn mixed(wild: u32, sane: BoxedStrategy<f64>) -> BoxedStrategy<f64> {
    prop_oneof![(100 - wild).max(1) => sane, wild.max(1) => extreme()].boxed()
}

/// A coordinate-like number.
pub fn num(wild: u32) -> BoxedStrategy<f64> {
    mixed(wild, prop_oneof![-2.0..2.0f64, Just(0.0), Just(1.0)].boxed())
}

/// A positive size-like number (semi-axes, gains, times).
pub fn pos(wild: u32) -> BoxedStrategy<f64> {
    mixed(wild, prop_oneof![0.01..2.0f64, 1.0..20.0f64].boxed())
}

/// A field that is 0 (the default) half of the time.
pub fn zero_or(s: BoxedStrategy<f64>) -> BoxedStrategy<f64> {
    prop_oneof![Just(0.0), s].boxed()
}

/// The wildness of one message: mostly tame, sometimes every number extreme.
pub fn wildness() -> BoxedStrategy<u32> {
    prop_oneof![3 => Just(0u32), 3 => Just(5u32), 2 => Just(25u32), 1 => Just(100u32)].boxed()
}

/// A length: usually `d`, sometimes another small one.
pub fn len(d: usize) -> BoxedStrategy<usize> {
    prop_oneof![8 => Just(d), 2 => 0..=d + 2].boxed()
}

/// `n` numbers of `s`, or a wrong count.
pub fn nums(d: usize, s: BoxedStrategy<f64>) -> BoxedStrategy<Vec<f64>> {
    len(d).prop_flat_map(move |n| vec(s.clone(), n)).boxed()
}

/// A name: usually one of `known`, sometimes a valid new one, an empty one, a long one or junk.
pub fn name(known: &'static [&'static str]) -> BoxedStrategy<String> {
    prop_oneof![
        8 => proptest::sample::select(known).prop_map(str::to_owned),
        2 => "[A-Za-z0-9_.-]{1,8}",
        1 => Just(String::new()),
        1 => Just("x".repeat(129)),
        1 => "\\PC{0,12}",
        1 => Just("a/b*".to_owned()),
    ]
    .boxed()
}

/// A dimension: mostly 1 to 3, sometimes 0 or larger.
pub fn dim() -> BoxedStrategy<usize> {
    prop_oneof![10 => 1..=3usize, 1 => Just(0usize), 1 => 4..=8usize].boxed()
}

/// A superquadric of dimension `d`.
pub fn superquadric(d: usize, wild: u32) -> BoxedStrategy<v1::Superquadric> {
    let exponents = prop_oneof![Just(Vec::new()), nums(d, mixed(wild, (1.0..6.0f64).boxed()))];
    (nums(d, pos(wild)), exponents)
        .prop_map(|(semi_axes, exponents)| v1::Superquadric { semi_axes, exponents })
        .boxed()
}

/// An obstacle's shape of dimension `d` (or none).
pub fn shape(d: usize, wild: u32) -> BoxedStrategy<Option<v1::obstacle::Shape>> {
    use v1::obstacle::Shape as S;
    let exponent = mixed(wild, (0.2..4.0f64).boxed());
    prop_oneof![
        6 => superquadric(d, wild).prop_map(|s| Some(S::Superquadric(s))),
        2 => (nums(3, pos(wild)), exponent.clone(), exponent)
            .prop_map(|(semi_axes, n, m)| Some(S::Nested(v1::NestedSuperquadric { semi_axes, n, m }))),
        2 => (-1..=4i32, vec(pos(wild), 0..=4))
            .prop_map(|(r#type, dimensions)| Some(S::Solid(v1::SolidPrimitive { r#type, dimensions }))),
        1 => Just(None),
    ]
    .boxed()
}

/// A rotation of dimension `d`: none, a true rotation (in the first two axes), or any numbers.
pub fn rotation(d: usize, wild: u32) -> BoxedStrategy<Vec<f64>> {
    let turn = (0.0..std::f64::consts::TAU).prop_map(move |a| {
        let mut r = vec![0.0; d * d];
        for i in 0..d {
            r[i * d + i] = 1.0;
        }
        if d >= 2 {
            let (s, c) = a.sin_cos();
            r[0] = c;
            r[1] = -s;
            r[d] = s;
            r[d + 1] = c;
        }
        r
    });
    prop_oneof![4 => Just(Vec::new()), 2 => turn, 1 => nums(d * d, num(wild))].boxed()
}

/// An obstacle named from `ids`.
pub fn obstacle(ids: &'static [&'static str]) -> BoxedStrategy<v1::Obstacle> {
    (dim(), wildness(), name(ids))
        .prop_flat_map(|(d, wild, id)| {
            (
                shape(d, wild),
                nums(d, num(wild)),
                rotation(d, wild),
                prop_oneof![Just(Vec::new()), nums(d, num(wild))],
                zero_or(mixed(wild, (0.0..0.2f64).boxed())),
                zero_or(pos(wild)),
            )
                .prop_map(move |(shape, center, rotation, velocity, margin, ttl_s)| {
                    v1::Obstacle { id: id.clone(), shape, center, rotation, velocity, margin, ttl_s }
                })
        })
        .boxed()
}

/// An avoidance (or none).
pub fn avoidance() -> BoxedStrategy<Option<v1::Avoidance>> {
    use v1::avoidance as a;
    let method = wildness().prop_flat_map(|w| {
        let (p, q, r) = (pos(w), pos(w), pos(w));
        prop_oneof![
            Just(None),
            Just(Some(a::Method::None(a::None {}))),
            (p.clone(), q.clone())
                .prop_map(|(eta, p0)| Some(a::Method::StaticPoint(a::StaticPoint { eta, p0 }))),
            (p.clone(), q.clone())
                .prop_map(|(lambda, beta)| Some(a::Method::DynamicPoint(a::DynamicPoint { lambda, beta }))),
            (p.clone(), q.clone())
                .prop_map(|(gamma, beta)| Some(a::Method::SteeringAngle(a::SteeringAngle { gamma, beta }))),
            (p.clone(), q.clone()).prop_map(|(gain, eta)| Some(a::Method::StaticVolumetric(
                a::StaticVolumetric { a: gain, eta }
            ))),
            (p, q, r).prop_map(|(lambda, beta, eta)| {
                Some(a::Method::DynamicVolumetric(a::DynamicVolumetric { lambda, beta, eta }))
            }),
        ]
    });
    let samples = prop_oneof![4 => Just(0u32), 2 => 1..200u32, 1 => any::<u32>()];
    prop_oneof![
        1 => Just(None),
        3 => (method, any::<bool>(), samples).prop_map(|(method, ignore_obstacle_velocity, point_samples)| {
            Some(v1::Avoidance { method, ignore_obstacle_velocity, point_samples })
        }),
    ]
    .boxed()
}

/// A robot's state named from `ids`.
pub fn robot_state(ids: &'static [&'static str]) -> BoxedStrategy<v1::RobotState> {
    (dim(), wildness(), name(ids))
        .prop_flat_map(|(d, wild, robot_id)| {
            (
                mixed(wild, (1.7e9..1.8e9f64).boxed()),
                nums(d, num(wild)),
                prop_oneof![Just(Vec::new()), nums(d, num(wild))],
                prop_oneof![Just(None), superquadric(d, wild).prop_map(Some)],
            )
                .prop_map(move |(stamp_unix_s, position, velocity, footprint)| v1::RobotState {
                    robot_id: robot_id.clone(),
                    stamp_unix_s,
                    position,
                    velocity,
                    footprint,
                    ..Default::default()
                })
        })
        .boxed()
}

/// A primitive message: consistent sizes most of the time, numbers of any wildness.
pub fn primitive() -> BoxedStrategy<v1::Primitive> {
    let basis = prop_oneof![8 => 1..=12u32, 1 => Just(0u32), 1 => 13..=60u32];
    (dim(), basis, wildness())
        .prop_flat_map(|(d, n, wild)| {
            let w = d * (n as usize + 1);
            (
                prop_oneof![9 => Just(1u32), 1 => any::<u32>()],
                prop_oneof![9 => Just(d as u32), 1 => 0..=9u32],
                mixed(wild, (1.0..8.0f64).boxed()),
                nums(d, mixed(wild, (10.0..3000.0f64).boxed())),
                nums(d, mixed(wild, (5.0..110.0f64).boxed())),
                pos(wild),
                (nums(d, num(wild)), nums(d, num(wild))),
                nums(w, mixed(wild, (-500.0..500.0f64).boxed())),
            )
                .prop_map(
                    move |(format_version, dim, alpha, k, dd, tau, (start, goal), weights)| v1::Primitive {
                        format_version,
                        dim,
                        n_basis: n,
                        alpha,
                        k,
                        d: dd,
                        tau,
                        start,
                        goal,
                        weights,
                        ..Default::default()
                    },
                )
        })
        .boxed()
}

/// A demonstration message: increasing times most of the time.
pub fn demonstration() -> BoxedStrategy<v1::Demonstration> {
    (dim(), prop_oneof![8 => 2..40usize, 1 => 0..2usize], wildness())
        .prop_flat_map(|(d, samples, wild)| {
            let times = prop_oneof![
                4 => (0.01..2.0f64).prop_map(move |end| (0..samples).map(|i| end * i as f64 / samples as f64).collect::<Vec<f64>>()),
                1 => nums(samples, num(wild)),
            ];
            (times, nums(samples * d, num(wild)), prop_oneof![9 => Just(d as u32), 1 => 0..=9u32])
                .prop_map(|(t, positions, dim)| v1::Demonstration { t, positions, dim, ..Default::default() })
        })
        .boxed()
}

/// Learning parameters (or none).
pub fn learn_parameters() -> BoxedStrategy<Option<v1::LearnParameters>> {
    let params = (wildness(), 1..=3usize).prop_flat_map(|(wild, d)| {
        (
            prop_oneof![Just(0u32), 1..30u32, Just(5000u32)],
            prop_oneof![Just(Vec::new()), nums(d, mixed(wild, (10.0..3000.0f64).boxed()))],
            prop_oneof![Just(Vec::new()), nums(d, pos(wild))],
            zero_or(mixed(wild, (1.0..8.0f64).boxed())),
        )
            .prop_map(|(n_basis, k, d, alpha)| v1::LearnParameters { n_basis, k, d, alpha })
    });
    prop_oneof![Just(None), params.prop_map(Some)].boxed()
}
