//! SceneService through the real handlers: PutObstacle, DeleteObstacle, ListObstacles and WatchScene (opened, its
//! first event read, dropped) in random sequences.

use proptest::collection::vec;
use proptest::prelude::*;
use proptest::test_runner::TestCaseResult;
use tonic::transport::Channel;

use dmp_proto::v1;
use dmp_proto::v1::scene_service_client::SceneServiceClient;

use crate::fixture::{Fuzzed, bounded, check_obstacle, refused};
use crate::requests::{CELLS, OBSTACLES};
use crate::runner::fuzz;
use crate::values::{name, obstacle};

/// One call of the scene service.
#[derive(Debug, Clone)]
pub enum SceneCall {
    /// PutObstacle.
    Put(v1::PutObstacleRequest),
    /// DeleteObstacle.
    Delete(v1::DeleteObstacleRequest),
    /// ListObstacles.
    List(v1::ListObstaclesRequest),
    /// WatchScene, its first event read.
    Watch(v1::WatchSceneRequest),
}

/// A scene call.
pub fn scene_call() -> impl Strategy<Value = SceneCall> {
    prop_oneof![
        5 => (prop_oneof![1 => Just(None), 9 => obstacle(OBSTACLES).prop_map(Some)], name(CELLS))
            .prop_map(|(obstacle, cell)| SceneCall::Put(v1::PutObstacleRequest { obstacle, cell })),
        2 => (name(OBSTACLES), name(CELLS)).prop_map(|(id, cell)| SceneCall::Delete(v1::DeleteObstacleRequest { id, cell })),
        1 => name(CELLS).prop_map(|cell| SceneCall::List(v1::ListObstaclesRequest { cell })),
        1 => name(CELLS).prop_map(|cell| SceneCall::Watch(v1::WatchSceneRequest { cell })),
    ]
}

fn check_snapshot(s: Option<&v1::SceneSnapshot>) -> TestCaseResult {
    s.map_or(Ok(()), |s| s.obstacles.iter().try_for_each(check_obstacle))
}

/// Sends one call and checks the answer: finite obstacles, or a clear refusal.
pub async fn send(channel: &Channel, call: SceneCall) -> TestCaseResult {
    let mut c = SceneServiceClient::new(channel.clone());
    let what = format!("{call:?}");
    match call {
        SceneCall::Put(r) => {
            bounded("put obstacle", c.put_obstacle(r)).await?.map_or_else(|s| refused(&what, &s), |_| Ok(()))
        }
        SceneCall::Delete(r) => bounded("delete obstacle", c.delete_obstacle(r))
            .await?
            .map_or_else(|s| refused(&what, &s), |_| Ok(())),
        SceneCall::List(r) => match bounded("list obstacles", c.list_obstacles(r)).await? {
            Ok(r) => check_snapshot(Some(r.get_ref())),
            Err(s) => refused(&what, &s),
        },
        SceneCall::Watch(r) => match bounded("watch", c.watch_scene(r)).await? {
            Ok(r) => {
                let mut events = r.into_inner();
                match bounded("first scene event", events.message()).await? {
                    Ok(Some(e)) => check_snapshot(e.snapshot.as_ref()),
                    Ok(None) => Err(TestCaseError::fail("the watch ended without a snapshot")),
                    Err(s) => refused(&what, &s),
                }
            }
            Err(s) => refused(&what, &s),
        },
    }
}

/// Deletes every obstacle of the cells the cases name, so that each case starts from an empty scene (and a
/// failure shrinks to the calls that cause it).
pub async fn clear(channel: &Channel) -> TestCaseResult {
    let mut c = SceneServiceClient::new(channel.clone());
    for cell in CELLS {
        let request = v1::ListObstaclesRequest { cell: (*cell).into() };
        let snapshot = bounded("list obstacles", c.list_obstacles(request))
            .await?
            .map_err(|s| TestCaseError::fail(format!("listing `{cell}` failed: {s}")))?;
        for o in &snapshot.get_ref().obstacles {
            let request = v1::DeleteObstacleRequest { id: o.id.clone(), cell: (*cell).into() };
            bounded("delete obstacle", c.delete_obstacle(request))
                .await?
                .map_err(|s| TestCaseError::fail(format!("deleting `{}` failed: {s}", o.id)))?;
        }
    }
    Ok(())
}

#[test]
fn fuzz_grpc_scene() {
    let server = Fuzzed::start();
    fuzz("grpc_scene", 200, 50, vec(scene_call(), 1..=5), |calls| {
        server.case(async {
            clear(&server.channel).await?;
            for c in calls {
                send(&server.channel, c).await?;
            }
            Ok(())
        })
    });
    server.stop();
}
