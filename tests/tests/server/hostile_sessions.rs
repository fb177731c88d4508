//! Careless or hostile clients that must not stop or steer another robot: bad session commands are rejected with a
//! warning and the run goes on; a robot state stamped far from the server's clock is dropped and counted; a robot
//! vanishes with its liveliness token; a second stream of an executing robot is refused unless it takes over.

use std::future::IntoFuture;
use std::time::Duration;

use dmp_client::ClientError;
use dmp_client::zenoh_pub::ObstaclePublisher;
use dmp_proto::keys::{robot_alive_key, robot_state_key};
use dmp_proto::v1::motion_service_client::MotionServiceClient;
use dmp_proto::v1::session_request::Message;
use dmp_proto::v1::warning::Kind;
use dmp_proto::{codec, v1};
use dmp_server::server::ServerHandle;
use tokio::sync::mpsc;
use tokio_stream::StreamExt;
use tokio_stream::wrappers::ReceiverStream;

use crate::{line, rows, serve, spec, until};
use dmp_tests::within;

fn now_unix_s() -> f64 {
    std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap().as_secs_f64()
}

#[tokio::test(flavor = "multi_thread")]
async fn bad_session_commands_are_rejected_and_the_run_reaches_its_goal() {
    let dir = tempfile::tempdir().unwrap();
    let (handle, client) = serve(dir.path()).await;
    let goal = vec![0.1, 0.0, 0.0];
    within("put", client.put_primitive("psm1", "reach", &line(vec![0.0; 3], goal.clone(), 1.0)))
        .await
        .unwrap();
    let mut motion = spec("psm1", "reach");
    motion.ignore_scene = true;
    // Slow at first (tau 20 s), so that the run is still going when the commands arrive; a valid set_tau at the
    // end speeds it up.
    motion.tau = 20.0;
    let start = v1::ExecuteRequest { motion: Some(motion), max_duration_s: 60.0, ..Default::default() };
    // The generated client: the library's sender cannot send an empty message.
    let (tx, rx) = mpsc::channel(16);
    let send = |message: Option<Message>| {
        let tx = tx.clone();
        async move { within("send", tx.send(v1::SessionRequest { message })).await.unwrap() }
    };
    send(Some(Message::Start(start))).await;
    let mut grpc = within("connect", MotionServiceClient::connect(format!("http://{}", handle.grpc_addr)))
        .await
        .unwrap();
    let mut segments = within("session", grpc.session(ReceiverStream::new(rx))).await.unwrap().into_inner();
    let mut received = vec![within("segment", segments.next()).await.unwrap().unwrap()];

    let far_future = v1::RobotState {
        robot_id: "psm1".into(),
        stamp_unix_s: now_unix_s() + 1e7,
        position: vec![0.0; 3],
        velocity: vec![0.0; 3],
        footprint: None,
        ..Default::default()
    };
    let bad = [
        (
            Some(Message::SetGoal(v1::SetGoal { goal: vec![0.0, 0.0, f64::NAN], ..Default::default() })),
            "set_goal.goal[2]",
        ),
        (Some(Message::SetGoal(v1::SetGoal { goal: vec![0.0, 0.0], ..Default::default() })), "set_goal.goal"),
        (
            Some(Message::SetGoal(v1::SetGoal { goal: vec![0.0, 5000.0, 0.0], ..Default::default() })),
            "set_goal.goal[1]",
        ),
        (Some(Message::SetTau(v1::SetTau { tau: 1e-300 })), "set_tau.tau"),
        (Some(Message::SetTau(v1::SetTau { tau: 0.0 })), "set_tau.tau"),
        (None, "message"),
        (Some(Message::State(far_future)), "state.stamp_unix_s"),
    ];
    for (message, _) in &bad {
        send(message.clone()).await;
    }
    send(Some(Message::SetTau(v1::SetTau { tau: 1.0 }))).await;
    while let Some(s) = within("segment", segments.next()).await {
        received.push(s.expect("the run goes on"));
    }
    let warnings: Vec<(Kind, String)> =
        received.iter().flat_map(|s| &s.warnings).map(|w| (w.kind(), w.field.clone())).collect();
    for (_, field) in &bad {
        let kind = if field.starts_with("state.") { Kind::StateDropped } else { Kind::CommandRejected };
        let n = warnings.iter().filter(|w| w.0 == kind && w.1 == *field).count();
        let expected = bad.iter().filter(|b| b.1 == *field).count();
        assert_eq!(n, expected, "{kind:?} {field} in {warnings:?}");
    }
    assert_eq!(warnings.len(), bad.len(), "{warnings:?}");
    let last = received.last().unwrap();
    assert_eq!(last.status, v1::SegmentStatus::GoalReached as i32, "ended {:?}", last.status());
    let end = rows(last, &last.positions).pop().unwrap();
    let err: f64 = end.iter().zip(&goal).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt();
    assert!(err < 2e-3, "ended {err} from the goal");
    assert_eq!(within("stats", client.stats()).await.unwrap().robot_states_dropped, 1);
    within("shutdown", handle.shutdown()).await.unwrap();
}

/// A 2-D robot going from (0, 0) to (1, 0) as fast as read, avoiding its cell-mates: its positions.
async fn corridor_run(client: &dmp_client::DmpClient) -> Vec<f64> {
    let mut motion = spec("youbot", "corridor");
    motion.footprint = Some(v1::Superquadric { semi_axes: vec![0.2, 0.2], exponents: vec![] });
    let request = v1::ExecuteRequest { motion: Some(motion), max_duration_s: 4.0, ..Default::default() };
    let mut stream = within("execute", client.execute(request)).await.unwrap();
    let mut positions = Vec::new();
    while let Some(s) = within("segment", stream.next()).await {
        positions.extend(s.unwrap().positions);
    }
    positions
}

/// A robot's state next to the corridor's middle, stamped `stamp_unix_s`.
fn phantom(id: &str, stamp_unix_s: f64) -> v1::RobotState {
    v1::RobotState {
        robot_id: id.into(),
        stamp_unix_s,
        position: vec![0.5, 0.25],
        velocity: vec![0.0, 0.0],
        footprint: Some(v1::Superquadric { semi_axes: vec![0.2, 0.2], exponents: vec![] }),
        ..Default::default()
    }
}

/// A raw Zenoh session connected to the server, once the server's robot-state subscriber is known to it.
async fn robot_state_session(handle: &ServerHandle) -> ObstaclePublisher {
    let zenoh =
        within("zenoh open", ObstaclePublisher::open("default", &handle.zenoh_locators, &[])).await.unwrap();
    let probe =
        within("probe", zenoh.session().declare_publisher(robot_state_key("default", "probe")).into_future())
            .await
            .unwrap();
    within("matching", async {
        while !probe.matching_status().into_future().await.unwrap().matching() {
            tokio::time::sleep(Duration::from_millis(5)).await;
        }
    })
    .await;
    zenoh
}

fn robots_in_default_cell(handle: &ServerHandle) -> usize {
    handle.cells().get("default").unwrap().robot_count()
}

#[tokio::test(flavor = "multi_thread")]
async fn a_far_future_robot_state_over_zenoh_does_not_bend_a_path_and_is_counted() {
    let dir = tempfile::tempdir().unwrap();
    let (handle, client) = serve(dir.path()).await;
    within("put", client.put_primitive("youbot", "corridor", &line(vec![0.0, 0.0], vec![1.0, 0.0], 1.0)))
        .await
        .unwrap();
    let alone = corridor_run(&client).await;
    let zenoh = robot_state_session(&handle).await;

    let key = robot_state_key("default", "phantom");
    within(
        "put",
        zenoh.session().put(&key, codec::encode(&phantom("phantom", now_unix_s() + 1e7))).into_future(),
    )
    .await
    .unwrap();
    within("dropped", async {
        while within("stats", client.stats()).await.unwrap().robot_states_dropped < 1 {
            tokio::time::sleep(Duration::from_millis(5)).await;
        }
    })
    .await;
    assert_eq!(robots_in_default_cell(&handle), 0);
    assert_eq!(corridor_run(&client).await, alone, "the dropped state changed the path");

    // The control: the same robot with a fresh stamp (sent again and again, so that it stays fresh) bends the
    // path, so the comparison above can tell.
    let fresh_key = robot_state_key("default", "real");
    within(
        "put",
        zenoh.session().put(&fresh_key, codec::encode(&phantom("real", now_unix_s()))).into_future(),
    )
    .await
    .unwrap();
    until("the fresh robot is seen", || robots_in_default_cell(&handle) == 1).await;
    let session = zenoh.session().clone();
    let refresh = tokio::spawn(async move {
        loop {
            within(
                "put",
                session.put(&fresh_key, codec::encode(&phantom("real", now_unix_s()))).into_future(),
            )
            .await
            .unwrap();
            tokio::time::sleep(Duration::from_millis(50)).await;
        }
    });
    let bent = corridor_run(&client).await;
    refresh.abort();
    let deviation = bent.chunks(2).map(|p| p[1].abs()).fold(0.0, f64::max);
    assert!(deviation > 0.01, "a fresh cell-mate did not bend the path ({deviation} m)");
    assert_eq!(within("stats", client.stats()).await.unwrap().robot_states_dropped, 1);
    within("close", zenoh.close()).await.unwrap();
    within("shutdown", handle.shutdown()).await.unwrap();
}

#[tokio::test(flavor = "multi_thread")]
async fn a_robot_vanishes_when_its_liveliness_token_goes() {
    let dir = tempfile::tempdir().unwrap();
    let (handle, _client) = serve(dir.path()).await;
    let zenoh = robot_state_session(&handle).await;
    let token = within(
        "token",
        zenoh.session().liveliness().declare_token(robot_alive_key("default", "ghost")).into_future(),
    )
    .await
    .unwrap();
    let key = robot_state_key("default", "ghost");
    within("put", zenoh.session().put(&key, codec::encode(&phantom("ghost", now_unix_s()))).into_future())
        .await
        .unwrap();
    until("the robot is seen", || robots_in_default_cell(&handle) == 1).await;
    within("undeclare", token.undeclare().into_future()).await.unwrap();
    until("the robot is gone", || robots_in_default_cell(&handle) == 0).await;
    within("close", zenoh.close()).await.unwrap();
    within("shutdown", handle.shutdown()).await.unwrap();
}

fn status(e: ClientError) -> (tonic::Code, String) {
    match e {
        ClientError::Status { code, message } => (code, message),
        other => panic!("not a status: {other}"),
    }
}

#[tokio::test(flavor = "multi_thread")]
async fn a_second_stream_of_a_robot_is_refused_unless_it_takes_over() {
    let dir = tempfile::tempdir().unwrap();
    let (handle, client) = serve(dir.path()).await;
    within("put", client.put_primitive("r1", "line", &line(vec![0.0, 0.0], vec![0.5, 0.0], 3.0)))
        .await
        .unwrap();
    let request = |take_over: bool| v1::ExecuteRequest {
        motion: Some(spec("r1", "line")),
        pacing: v1::Pacing::Realtime as i32,
        max_duration_s: 30.0,
        take_over,
        ..Default::default()
    };
    let mut first = within("execute", client.execute(request(false))).await.unwrap();
    within("first segment", first.next()).await.unwrap().unwrap();

    let (code, message) = status(within("second", client.execute(request(false))).await.err().unwrap());
    assert_eq!(code, tonic::Code::AlreadyExists, "{message}");
    assert!(message.contains("`r1`") && message.contains("take_over"), "{message}");
    let (code, message) = status(within("session", client.session(request(false))).await.err().unwrap());
    assert_eq!(code, tonic::Code::AlreadyExists, "{message}");
    assert!(message.contains("`r1`"), "{message}");
    // The first stream is not disturbed by the refusals.
    within("first goes on", first.next()).await.unwrap().unwrap();

    let mut second = within("take over", client.execute(request(true))).await.unwrap();
    let mut ended_with = None;
    while let Some(item) = within("first", first.next()).await {
        if let Err(e) = item {
            ended_with = Some(status(e));
        }
    }
    let (code, message) = ended_with.expect("the first stream ends with a status");
    assert_eq!(code, tonic::Code::Aborted, "{message}");
    assert!(message.contains("taken over by another stream"), "{message}");
    let mut last = None;
    while let Some(item) = within("second", second.next()).await {
        last = Some(item.unwrap());
    }
    assert_eq!(last.unwrap().status, v1::SegmentStatus::GoalReached as i32);

    // The stream that ended let go of the robot, and took its state out of the cell.
    until("the robot's state is gone", || robots_in_default_cell(&handle) == 0).await;
    let again = v1::ExecuteRequest { pacing: v1::Pacing::AsFastAsRead as i32, ..request(false) };
    let mut third = within("again", client.execute(again)).await.unwrap();
    while let Some(item) = within("third", third.next()).await {
        item.unwrap();
    }
    within("shutdown", handle.shutdown()).await.unwrap();
}
