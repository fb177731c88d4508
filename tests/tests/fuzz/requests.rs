//! Strategies for the gRPC requests: names mostly of things that exist on the fuzzed server (robots `r1`, `r2`;
//! primitives `p1` (2-D), `p2` (3-D), `fz` (a fuzzed one); cells `""` and `c1`), numbers of any wildness.

use proptest::collection::vec;
use proptest::prelude::*;

use dmp_proto::v1;

use crate::values::{avoidance, extreme, name, nums, obstacle, superquadric, zero_or};

/// Robots of the fuzzed server.
pub const ROBOTS: &[&str] = &["r1", "r2"];
/// Primitive names of the fuzzed server.
pub const PRIMITIVES: &[&str] = &["p1", "p2", "fz"];
/// Cells (the empty name is the default cell).
pub const CELLS: &[&str] = &["", "c1"];
/// Obstacle ids.
pub const OBSTACLES: &[&str] = &["o1", "o2", "o3"];

/// A number in `lo..hi`, or an extreme one time in ten.
pub fn around(lo: f64, hi: f64) -> BoxedStrategy<f64> {
    prop_oneof![9 => lo..hi, 1 => extreme()].boxed()
}

/// What to replay.
pub fn motion_spec() -> BoxedStrategy<v1::MotionSpec> {
    let d = prop_oneof![Just(2usize), Just(3usize)];
    (d, name(ROBOTS), name(PRIMITIVES), name(CELLS))
        .prop_flat_map(|(d, robot_id, primitive, cell)| {
            let point = prop_oneof![Just(Vec::new()), nums(d, around(-1.0, 2.0))];
            (
                prop_oneof![8 => Just(0u64), 1 => 1..3u64, 1 => any::<u64>()],
                (point.clone(), point),
                zero_or(around(0.3, 2.0)),
                (avoidance(), avoidance()),
                prop_oneof![Just(None), superquadric(d, 5).prop_map(Some)],
                vec(obstacle(&["e1", "e2"]), 0..3),
                any::<bool>(),
                prop_oneof![
                    Just(None),
                    (zero_or(around(0.001, 1.0)), zero_or(around(0.001, 1.0)))
                        .prop_map(|(position, speed)| Some(v1::GoalTolerance { position, speed })),
                ],
            )
                .prop_map(
                    move |(
                        version,
                        (start, goal),
                        tau,
                        (avoidance, robot_avoidance),
                        footprint,
                        extra,
                        ignore,
                        goal_tolerance,
                    )| {
                        v1::MotionSpec {
                            robot_id: robot_id.clone(),
                            primitive: primitive.clone(),
                            version,
                            start,
                            goal,
                            tau,
                            avoidance,
                            robot_avoidance,
                            footprint,
                            extra_obstacles: extra,
                            ignore_scene: ignore,
                            cell: cell.clone(),
                            goal_tolerance,
                            limits: None,
                            goal_filter_alpha: 0.0,
                        }
                    },
                )
        })
        .boxed()
}

/// A plan request.
pub fn plan_request() -> BoxedStrategy<v1::PlanRequest> {
    (motion_spec(), zero_or(around(0.001, 0.05)), zero_or(around(0.05, 2.0)))
        .prop_map(|(motion, dt, duration)| v1::PlanRequest { motion: Some(motion), dt, duration })
        .boxed()
}

/// The stream fields of an execute or group request: dt, segment_s, pacing, lookahead_s, max_duration_s,
/// integration_step_s, integration_tolerance.
pub type StreamFields = (f64, f64, i32, f64, f64, f64, f64);

/// Stream fields, mostly as fast as read.
pub fn stream_fields() -> BoxedStrategy<StreamFields> {
    (
        zero_or(around(0.001, 0.02)),
        zero_or(around(0.005, 0.1)),
        prop_oneof![6 => Just(1i32), 2 => Just(0i32), 2 => Just(2i32), 1 => any::<i32>()],
        zero_or(around(0.0, 0.2)),
        zero_or(around(0.02, 2.0)),
        zero_or(around(0.001, 0.01)),
        prop_oneof![6 => Just(0.0), 2 => 1e-6..1e-2f64, 1 => extreme()],
    )
        .boxed()
}

/// An execute request.
pub fn execute_request() -> BoxedStrategy<v1::ExecuteRequest> {
    (motion_spec(), stream_fields())
        .prop_map(|(motion, (dt, segment_s, pacing, lookahead_s, max_duration_s, step, tol))| {
            v1::ExecuteRequest {
                motion: Some(motion),
                dt,
                segment_s,
                pacing,
                lookahead_s,
                max_duration_s,
                integration_step_s: step,
                integration_tolerance: tol,
                take_over: false,
            }
        })
        .boxed()
}

/// A group request of zero to three members.
pub fn group_request() -> BoxedStrategy<v1::ExecuteGroupRequest> {
    (vec(motion_spec(), 0..=3), stream_fields(), zero_or(around(0.3, 2.0)))
        .prop_map(|(members, (dt, segment_s, pacing, lookahead_s, max_duration_s, step, tol), tau)| {
            v1::ExecuteGroupRequest {
                members: members.into_iter().map(|m| v1::GroupMember { motion: Some(m) }).collect(),
                dt,
                segment_s,
                pacing,
                lookahead_s,
                max_duration_s,
                tau,
                integration_step_s: step,
                integration_tolerance: tol,
                take_over: false,
            }
        })
        .boxed()
}

/// One message of a session after its start.
pub fn session_message() -> BoxedStrategy<v1::SessionRequest> {
    use v1::session_request::Message as M;
    let message = prop_oneof![
        3 => crate::values::robot_state(&["r1", "r2"]).prop_map(|s| Some(M::State(s))),
        3 => prop_oneof![Just(2usize), Just(3usize)]
            .prop_flat_map(|d| nums(d, around(-1.0, 2.0)))
            .prop_map(|goal| Some(M::SetGoal(v1::SetGoal { goal }))),
        2 => around(0.2, 3.0).prop_map(|tau| Some(M::SetTau(v1::SetTau { tau }))),
        2 => Just(Some(M::Pause(v1::Pause {}))),
        2 => Just(Some(M::Resume(v1::Resume {}))),
        1 => Just(Some(M::Stop(v1::Stop {}))),
        1 => execute_request().prop_map(|r| Some(M::Start(r))),
        1 => Just(None),
    ];
    message.prop_map(|message| v1::SessionRequest { message }).boxed()
}
