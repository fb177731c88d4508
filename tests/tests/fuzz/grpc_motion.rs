//! MotionService's Plan, Execute (a few segments read, then dropped) and ExecuteGroup through the real handlers,
//! after an optional fuzzed primitive (`r1/fz`) and an optional scene change.

use proptest::prelude::*;
use proptest::test_runner::TestCaseResult;
use tonic::transport::Channel;
use tonic::{Status, Streaming};

use dmp::Primitive;
use dmp_proto::primitive::primitive_to_proto;
use dmp_proto::v1;
use dmp_proto::v1::motion_service_client::MotionServiceClient;
use dmp_proto::v1::primitive_service_client::PrimitiveServiceClient;

use crate::fixture::{Fuzzed, bounded, check_segment, refused};
use crate::grpc_primitives::{self, PrimitiveCall};
use crate::grpc_scene::{self, SceneCall, scene_call};
use crate::requests::{execute_request, group_request, plan_request};
use crate::runner::fuzz;
use crate::values::primitive;

/// One motion call.
#[derive(Debug, Clone)]
pub enum MotionCall {
    /// Plan.
    Plan(v1::PlanRequest),
    /// Execute, up to four segments read.
    Execute(v1::ExecuteRequest),
    /// ExecuteGroup, up to three group segments read.
    Group(v1::ExecuteGroupRequest),
}

/// Stores the primitives the motion requests name: `p1` (2-D) and `p2` (3-D) of `r1` and `r2`.
pub fn store_primitives(server: &Fuzzed) {
    let line = |start: Vec<f64>, goal: Vec<f64>| {
        let d = start.len();
        Primitive::straight_line(20, 4.0, vec![1050.0; d], None, 1.0, start, goal).expect("a line")
    };
    server.block_on(async {
        let mut c = PrimitiveServiceClient::new(server.channel.clone());
        for robot in ["r1", "r2"] {
            for (name, p) in [
                ("p1", line(vec![0.0, 0.0], vec![1.0, 0.5])),
                ("p2", line(vec![0.0, 0.0, 0.0], vec![1.0, 0.5, 0.2])),
            ] {
                let request = v1::PutPrimitiveRequest {
                    robot_id: robot.into(),
                    name: name.into(),
                    primitive: Some(primitive_to_proto(&p)),
                };
                dmp_tests::within("put", c.put(request)).await.expect("stored");
            }
        }
    });
}

/// Reads up to `n` messages of a stream (one in real time), checking each with `check`.
pub async fn read<M>(
    what: &str,
    stream: &mut Streaming<M>,
    n: usize,
    check: impl Fn(&M) -> TestCaseResult,
) -> TestCaseResult {
    for _ in 0..n {
        match bounded(what, stream.message()).await? {
            Ok(Some(m)) => check(&m)?,
            Ok(None) => break,
            Err(s) => return refused(what, &s),
        }
    }
    Ok(())
}

/// How many messages to read of a stream of `pacing`.
fn reads(pacing: i32, n: usize) -> usize {
    if pacing == v1::Pacing::Realtime as i32 { 1 } else { n }
}

fn opened<M>(
    what: &str,
    r: Result<tonic::Response<Streaming<M>>, Status>,
) -> Result<Option<Streaming<M>>, TestCaseError> {
    match r {
        Ok(r) => Ok(Some(r.into_inner())),
        Err(s) => refused(what, &s).map(|()| None),
    }
}

/// Sends one motion call and checks what comes back.
pub async fn send(channel: &Channel, call: MotionCall) -> TestCaseResult {
    let mut c = MotionServiceClient::new(channel.clone());
    let what = format!("{call:?}");
    match call {
        MotionCall::Plan(r) => match bounded("plan", c.plan(r)).await? {
            Ok(r) => {
                let plan = r.into_inner();
                check_segment(
                    plan.trajectory.as_ref().ok_or_else(|| TestCaseError::fail("plan without trajectory"))?,
                )
            }
            Err(s) => refused(&what, &s),
        },
        MotionCall::Execute(r) => {
            let n = reads(r.pacing, 4);
            match opened(&what, bounded("execute", c.execute(r)).await?)? {
                Some(mut s) => read(&what, &mut s, n, check_segment).await,
                None => Ok(()),
            }
        }
        MotionCall::Group(r) => {
            let n = reads(r.pacing, 3);
            match opened(&what, bounded("execute group", c.execute_group(r)).await?)? {
                Some(mut s) => {
                    read(&what, &mut s, n, |g: &v1::GroupSegment| {
                        g.segments.iter().try_for_each(check_segment)
                    })
                    .await
                }
                None => Ok(()),
            }
        }
    }
}

fn motion_call() -> impl Strategy<Value = MotionCall> {
    prop_oneof![
        3 => plan_request().prop_map(MotionCall::Plan),
        3 => execute_request().prop_map(MotionCall::Execute),
        1 => group_request().prop_map(MotionCall::Group),
    ]
}

#[test]
fn fuzz_grpc_motion() {
    let server = Fuzzed::start();
    store_primitives(&server);
    let fuzzed_primitive = prop_oneof![2 => Just(None), 1 => primitive().prop_map(Some)].prop_map(|p| {
        p.map(|p| {
            PrimitiveCall::Put(v1::PutPrimitiveRequest {
                robot_id: "r1".into(),
                name: "fz".into(),
                primitive: Some(p),
            })
        })
    });
    let scene = prop_oneof![2 => Just(None), 1 => scene_call().prop_map(Some)];
    let strategy = (fuzzed_primitive, scene, motion_call());
    fuzz(
        "grpc_motion",
        120,
        30,
        strategy,
        |(put, scene, call): (Option<PrimitiveCall>, Option<SceneCall>, MotionCall)| {
            server.case(async {
                if let Some(put) = put {
                    grpc_primitives::send(&server.channel, put).await?;
                }
                if let Some(scene) = scene {
                    grpc_scene::send(&server.channel, scene).await?;
                }
                send(&server.channel, call).await
            })
        },
    );
    server.stop();
}
