//! PrimitiveService through the real handlers: Learn, Put, Get, List and Delete in random sequences.

use proptest::collection::vec;
use proptest::prelude::*;
use proptest::test_runner::TestCaseResult;
use tonic::transport::Channel;

use dmp_proto::v1;
use dmp_proto::v1::primitive_service_client::PrimitiveServiceClient;

use crate::fixture::{Fuzzed, bounded, check_record, refused};
use crate::requests::{PRIMITIVES, ROBOTS};
use crate::runner::fuzz;
use crate::values::{demonstration, learn_parameters, name, primitive};

/// One call of the primitive service.
#[derive(Debug, Clone)]
pub enum PrimitiveCall {
    /// Learn.
    Learn(v1::LearnRequest),
    /// Put.
    Put(v1::PutPrimitiveRequest),
    /// Get.
    Get(v1::GetPrimitiveRequest),
    /// List.
    List(v1::ListPrimitivesRequest),
    /// Delete.
    Delete(v1::DeletePrimitiveRequest),
}

fn call() -> impl Strategy<Value = PrimitiveCall> {
    let (robot, prim) = (name(ROBOTS), name(PRIMITIVES));
    prop_oneof![
        3 => (robot.clone(), prim.clone(), prop_oneof![1 => Just(None), 9 => demonstration().prop_map(Some)],
              learn_parameters())
            .prop_map(|(robot_id, name, demonstration, parameters)| {
                PrimitiveCall::Learn(v1::LearnRequest { robot_id, name, demonstration, parameters })
            }),
        3 => (robot.clone(), prim.clone(), prop_oneof![1 => Just(None), 9 => primitive().prop_map(Some)])
            .prop_map(|(robot_id, name, primitive)| {
                PrimitiveCall::Put(v1::PutPrimitiveRequest { robot_id, name, primitive })
            }),
        2 => (robot.clone(), prim.clone(), prop_oneof![Just(0u64), 1..4u64, any::<u64>()])
            .prop_map(|(robot_id, name, version)| PrimitiveCall::Get(v1::GetPrimitiveRequest { robot_id, name, version })),
        1 => robot.clone().prop_map(|robot_id| PrimitiveCall::List(v1::ListPrimitivesRequest { robot_id, ..Default::default() })),
        1 => (robot, prim).prop_map(|(robot_id, name)| PrimitiveCall::Delete(v1::DeletePrimitiveRequest { robot_id, name })),
    ]
}

/// Sends one call and checks the answer: a finite, valid record, or a clear refusal.
pub async fn send(channel: &Channel, call: PrimitiveCall) -> TestCaseResult {
    let mut c = PrimitiveServiceClient::new(channel.clone());
    let what = format!("{call:?}");
    match call {
        PrimitiveCall::Learn(r) => match bounded("learn", c.learn(r)).await? {
            Ok(r) => {
                check_record(r.get_ref().record.as_ref().ok_or_else(|| TestCaseError::fail("no record"))?)
            }
            Err(s) => refused(&what, &s),
        },
        PrimitiveCall::Put(r) => match bounded("put", c.put(r)).await? {
            Ok(r) => {
                check_record(r.get_ref().record.as_ref().ok_or_else(|| TestCaseError::fail("no record"))?)
            }
            Err(s) => refused(&what, &s),
        },
        PrimitiveCall::Get(r) => match bounded("get", c.get(r)).await? {
            Ok(r) => check_record(r.get_ref()),
            Err(s) => refused(&what, &s),
        },
        PrimitiveCall::List(r) => match bounded("list", c.list(r)).await? {
            Ok(r) => r.get_ref().records.iter().try_for_each(check_record),
            Err(s) => refused(&what, &s),
        },
        PrimitiveCall::Delete(r) => match bounded("delete", c.delete(r)).await? {
            Ok(_) => Ok(()),
            Err(s) => refused(&what, &s),
        },
    }
}

#[test]
fn fuzz_grpc_primitives() {
    let server = Fuzzed::start();
    fuzz("grpc_primitives", 150, 50, vec(call(), 1..=4), |calls| {
        server.case(async {
            for c in calls {
                send(&server.channel, c).await?;
            }
            Ok(())
        })
    });
    server.stop();
}
