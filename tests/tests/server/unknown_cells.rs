//! A motion runs only in a known cell: one with a typo in its name is refused (NOT_FOUND, naming the known
//! cells) instead of running in a new, empty scene; a scene put (gRPC or Zenoh) or the configuration declares a
//! cell, and the default cell always works.

use dmp_client::ClientError;
use dmp_client::zenoh_pub::ObstaclePublisher;
use dmp_proto::v1;
use dmp_tests::{T, TestServer, within};
use tokio_stream::StreamExt;
use tonic::Code;

use crate::{ellipse, line, spec, until};

/// The status of a refused call, with its message.
fn refusal<T>(r: Result<T, ClientError>) -> (Option<Code>, String) {
    match r {
        Ok(_) => (None, "accepted".into()),
        Err(e) => (e.code(), e.to_string()),
    }
}

fn motion_in(cell: &str) -> v1::MotionSpec {
    v1::MotionSpec { cell: cell.into(), ..spec("r", "line") }
}

fn plan_in(cell: &str) -> v1::PlanRequest {
    v1::PlanRequest { motion: Some(motion_in(cell)), dt: 0.01, duration: 1.0 }
}

fn execute_in(cell: &str) -> v1::ExecuteRequest {
    v1::ExecuteRequest { motion: Some(motion_in(cell)), max_duration_s: 10.0, ..Default::default() }
}

/// Asserts `r` is the refusal of unknown cell `cell` listing exactly `known` (in order).
fn assert_unknown<T>(r: Result<T, ClientError>, cell: &str, known: &str) {
    let (code, msg) = refusal(r);
    assert_eq!(code, Some(Code::NotFound), "{msg}");
    assert!(msg.contains(&format!("unknown cell `{cell}`: known cells are {known} (a cell exists")), "{msg}");
}

/// Runs `request` to its end: its last segment's status.
async fn executed(client: &dmp_client::grpc::DmpClient, request: v1::ExecuteRequest) -> i32 {
    let mut stream = within("execute", client.execute(request)).await.unwrap();
    let mut last = None;
    while let Some(s) = within("segment", stream.next()).await {
        last = Some(s.unwrap());
    }
    last.expect("a segment").status
}

#[tokio::test(flavor = "multi_thread")]
async fn a_motion_in_an_unknown_cell_is_refused_naming_the_known_cells_until_a_scene_declares_it() {
    let server = TestServer::start_with(|c| c.zenoh.disabled = true).await;
    let client = server.client().await;
    within("put", client.put_primitive("r", "line", &line(vec![0.0, 0.0], vec![0.5, 0.0], 2.0)))
        .await
        .unwrap();

    // The default cell always works, by its name or by none.
    within("plan in the default cell", client.plan(plan_in(""))).await.unwrap();
    within("plan in `default`", client.plan(plan_in("default"))).await.unwrap();
    assert_eq!(executed(&client, execute_in("")).await, v1::SegmentStatus::GoalReached as i32);

    // A typo: Plan, Execute, a Session's start and a group are refused, and nothing is created.
    assert_unknown(within("plan", client.plan(plan_in("defualt"))).await, "defualt", "`default`");
    let execute = async {
        let mut stream = client.execute(execute_in("defualt")).await?;
        stream.next().await.transpose()
    };
    assert_unknown(within("execute", execute).await, "defualt", "`default`");
    let session = async {
        let mut session = client.session(execute_in("defualt")).await?;
        session.next_segment().await.transpose()
    };
    assert_unknown(within("session", session).await, "defualt", "`default`");
    let group = v1::ExecuteGroupRequest {
        members: vec![
            v1::GroupMember { motion: Some(motion_in("defualt")) },
            v1::GroupMember {
                motion: Some(v1::MotionSpec { robot_id: "r2".into(), ..motion_in("defualt") }),
            },
        ],
        ..Default::default()
    };
    let group = async {
        let mut stream = client.execute_group(group).await?;
        stream.next().await.transpose()
    };
    let (code, msg) = refusal(within("group", group).await);
    assert_eq!(code, Some(Code::NotFound), "{msg}");
    assert!(msg.contains("unknown cell `defualt`"), "{msg}");
    assert!(server.handle().cells().find("defualt").unwrap().is_none(), "a refusal creates no cell");

    // A scene put declares a cell: it is listed, and motions run there.
    let bench = client.clone().with_cell("bench");
    within("put in bench", bench.put_obstacle(ellipse("wall", vec![5.0, 5.0], vec![0.1, 0.1])))
        .await
        .unwrap();
    assert_unknown(within("plan", client.plan(plan_in("bnech"))).await, "bnech", "`default`, `bench`");
    within("plan in bench", client.plan(plan_in("bench"))).await.unwrap();
    assert_eq!(executed(&client, execute_in("bench")).await, v1::SegmentStatus::GoalReached as i32);
    // Emptied, it is unknown again.
    assert!(within("delete", bench.delete_obstacle("wall")).await.unwrap().changed);
    assert_unknown(within("plan", client.plan(plan_in("bench"))).await, "bench", "`default`");
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread")]
async fn a_configured_cell_or_one_declared_over_zenoh_is_known() {
    let server = TestServer::start_with(|c| {
        c.scene.cells.insert("declared".into(), Default::default());
    })
    .await;
    let client = server.client().await;
    within("put", client.put_primitive("r", "line", &line(vec![0.0, 0.0], vec![0.5, 0.0], 2.0)))
        .await
        .unwrap();
    // A `[scene.cells.<cell>]` table declares its cell, empty.
    within("plan in a configured cell", client.plan(plan_in("declared"))).await.unwrap();
    assert_unknown(within("plan", client.plan(plan_in("lab"))).await, "lab", "`default`, `declared`");

    // An obstacle published over Zenoh declares its cell.
    let locators = &server.handle().zenoh_locators;
    let perception = within("zenoh open", ObstaclePublisher::open("lab", locators, &[])).await.unwrap();
    within("subscriber", perception.wait_for_subscriber(T)).await.unwrap();
    let obstacle = serde_json::json!({"center": [5.0, 5.0], "semi_axes": [0.1, 0.1]});
    within("put over zenoh", perception.put_json("box", &obstacle)).await.unwrap();
    let handle = server.handle();
    until("the box arrived", || {
        handle.cells().find("lab").unwrap().is_some_and(|c| !c.snapshot().obstacles.is_empty())
    })
    .await;
    within("plan in lab", client.plan(plan_in("lab"))).await.unwrap();
    server.stop().await;
}
