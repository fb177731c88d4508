//! Nobody steers a robot they were not given: every role against every RPC, with the identities that
//! `dmp-server access init` writes (tokens over loopback here; TLS in `tls.rs`).

use std::collections::HashMap;
use std::path::Path;

use dmp_client::connect::ConnectOptions;
use dmp_client::{ClientError, DmpClient};
use dmp_proto::v1;
use dmp_server::access::init::{InitOptions, init};
use dmp_tests::{TestServer, within};
use tokio_stream::StreamExt;
use tonic::Code;

use crate::{ellipse, line, spec};

/// A secured server of cell `cell-a` (its default cell, with an access file of `access init` for that cell and
/// robots `panda-1` and `panda-2`), and every identity's token.
pub(crate) async fn secured(set: &Path) -> (TestServer, HashMap<String, String>) {
    let options = InitOptions {
        cells: vec!["cell-a".into()],
        robots: vec!["panda-1".into(), "panda-2".into()],
        ..Default::default()
    };
    let made = init(set, &options).unwrap();
    let access = set.join("access.toml");
    let server = TestServer::start_with(|c| {
        c.zenoh.disabled = true;
        c.cell = "cell-a".into();
        c.security.access = Some(access);
    })
    .await;
    (server, made.tokens.into_iter().collect())
}

pub(crate) async fn as_identity(server: &TestServer, token: Option<&str>) -> DmpClient {
    let options = ConnectOptions { token: token.map(str::to_owned), ..Default::default() };
    within("connect", DmpClient::connect_with(&server.url(), &options)).await.unwrap()
}

/// Puts a straight line of `tau` seconds for panda-1 and panda-2, as the admin.
async fn put_lines(server: &TestServer, tokens: &HashMap<String, String>, tau: f64) {
    let admin = as_identity(server, Some(&tokens["admin"])).await;
    for robot in ["panda-1", "panda-2"] {
        let p = line(vec![0.0, 0.0], vec![1.0, 0.0], tau);
        within("put", admin.put_primitive(robot, "line", &p)).await.unwrap();
    }
}

/// One request of the matrix.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
enum Rpc {
    Learn,
    Put,
    Get,
    List,
    ListOther,
    Delete,
    PutObstacle,
    PutObstacleOtherCell,
    DeleteObstacle,
    ListObstacles,
    Watch,
    Plan,
    PlanOther,
    Execute,
    ExecuteOther,
    ExecuteOtherCell,
    Session,
    Group,
    Stats,
    Info,
}

const ALL: [Rpc; 20] = [
    Rpc::Learn,
    Rpc::Put,
    Rpc::Get,
    Rpc::List,
    Rpc::ListOther,
    Rpc::Delete,
    Rpc::PutObstacle,
    Rpc::PutObstacleOtherCell,
    Rpc::DeleteObstacle,
    Rpc::ListObstacles,
    Rpc::Watch,
    Rpc::Plan,
    Rpc::PlanOther,
    Rpc::Execute,
    Rpc::ExecuteOther,
    Rpc::ExecuteOtherCell,
    Rpc::Session,
    Rpc::Group,
    Rpc::Stats,
    Rpc::Info,
];

fn motion(robot: &str, cell: &str) -> v1::MotionSpec {
    v1::MotionSpec { cell: cell.into(), ..spec(robot, "line") }
}

fn execute(robot: &str, cell: &str) -> v1::ExecuteRequest {
    v1::ExecuteRequest { motion: Some(motion(robot, cell)), take_over: true, ..Default::default() }
}

/// The first answer of a stream: Ok, or its error.
fn first<T>(answer: Option<Result<T, ClientError>>) -> Result<(), ClientError> {
    answer.expect("an answer").map(|_| ())
}

/// Sends `rpc` as `c`; Ok when the server did it (its first answer, for streams).
async fn attempt(c: &DmpClient, rpc: Rpc) -> Result<(), ClientError> {
    let a = c.clone().with_cell("cell-a");
    let t: Vec<f64> = (0..50).map(|i| f64::from(i) * 0.02).collect();
    let rows: Vec<Vec<f64>> = t.iter().map(|t| vec![*t, t * (1.0 - t)]).collect();
    match rpc {
        Rpc::Learn => c.learn("panda-1", "learned", &t, &rows, Default::default()).await.map(|_| ()),
        Rpc::Put => {
            c.put_primitive("panda-1", "put", &line(vec![0.0, 0.0], vec![1.0, 0.0], 1.0)).await.map(|_| ())
        }
        Rpc::Get => c.get("panda-1", "line", 0).await.map(|_| ()),
        Rpc::List => c.list("panda-1").await.map(|_| ()),
        Rpc::ListOther => c.list("panda-2").await.map(|_| ()),
        Rpc::Delete => match c.delete("panda-1", "scratch").await {
            Err(e) if e.code() == Some(Code::NotFound) => Ok(()),
            other => other.map(|_| ()),
        },
        Rpc::PutObstacle => a.put_obstacle(ellipse("o", vec![5.0, 5.0], vec![0.1, 0.1])).await.map(|_| ()),
        Rpc::PutObstacleOtherCell => {
            a.with_cell("cell-b").put_obstacle(ellipse("o", vec![5.0, 5.0], vec![0.1, 0.1])).await.map(|_| ())
        }
        Rpc::DeleteObstacle => a.delete_obstacle("o").await.map(|_| ()),
        Rpc::ListObstacles => a.list_obstacles().await.map(|_| ()),
        Rpc::Watch => first(a.watch_scene().await?.next().await),
        Rpc::Plan => c.plan(plan("panda-1")).await.map(|_| ()),
        Rpc::PlanOther => c.plan(plan("panda-2")).await.map(|_| ()),
        Rpc::Execute => first(c.execute(execute("panda-1", "cell-a")).await?.next().await),
        Rpc::ExecuteOther => first(c.execute(execute("panda-2", "cell-a")).await?.next().await),
        Rpc::ExecuteOtherCell => first(c.execute(execute("panda-1", "cell-b")).await?.next().await),
        Rpc::Session => first(c.session(execute("panda-1", "cell-a")).await?.next_segment().await),
        Rpc::Group => {
            let member = |r: &str, y: f64| v1::GroupMember {
                motion: Some(v1::MotionSpec {
                    start: vec![0.0, y],
                    goal: vec![1.0, y],
                    footprint: Some(v1::Superquadric { semi_axes: vec![0.1, 0.1], exponents: vec![] }),
                    ..motion(r, "cell-a")
                }),
            };
            let group = v1::ExecuteGroupRequest {
                members: vec![member("panda-1", 0.0), member("panda-2", 1.0)],
                take_over: true,
                ..Default::default()
            };
            first(c.execute_group(group).await?.next().await)
        }
        Rpc::Stats => c.stats().await.map(|_| ()),
        Rpc::Info => c.info().await.map(|_| ()),
    }
}

fn plan(robot: &str) -> v1::PlanRequest {
    v1::PlanRequest { motion: Some(motion(robot, "cell-a")), ..Default::default() }
}

/// What each identity may do (the rest is denied).
fn allowed(identity: &str) -> Vec<Rpc> {
    use Rpc::*;
    match identity {
        "admin" => ALL.to_vec(),
        "planner" => vec![
            Learn,
            Put,
            Get,
            List,
            ListOther,
            Delete,
            PutObstacle,
            DeleteObstacle,
            ListObstacles,
            Watch,
            Plan,
            PlanOther,
            Execute,
            ExecuteOther,
            Session,
            Group,
            Stats,
            Info,
        ],
        "perception" => vec![PutObstacle, DeleteObstacle, ListObstacles, Watch, Info],
        "observer" => vec![Get, List, ListOther, ListObstacles, Watch, Stats, Info],
        "panda-1" => vec![Get, List, Plan, Execute, Session, Info],
        other => panic!("no row for {other}"),
    }
}

#[tokio::test(flavor = "multi_thread")]
async fn every_role_against_every_rpc() {
    let set = tempfile::tempdir().unwrap();
    let (server, tokens) = secured(set.path()).await;
    put_lines(&server, &tokens, 1.0).await;
    let mut failures = Vec::new();
    for identity in ["admin", "planner", "perception", "observer", "panda-1"] {
        let token = &tokens[identity];
        let client = as_identity(&server, Some(token)).await;
        let allowed = allowed(identity);
        for rpc in ALL {
            let result = within("the request", attempt(&client, rpc)).await;
            let denied = result.as_ref().err().and_then(ClientError::code) == Some(Code::PermissionDenied);
            if let Err(e) = &result {
                let text = e.to_string();
                assert!(!text.contains(token.as_str()), "a refusal repeats the token: {text}");
                if denied {
                    assert!(text.contains(&format!("identity `{identity}`")), "{text}");
                }
            }
            match (allowed.contains(&rpc), &result) {
                (true, Err(e)) => failures.push(format!("{identity} {rpc:?}: refused: {e}")),
                (false, Ok(())) => failures.push(format!("{identity} {rpc:?}: allowed")),
                (false, Err(e)) if !denied => {
                    failures.push(format!("{identity} {rpc:?}: not PERMISSION_DENIED: {e}"))
                }
                _ => {}
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread")]
async fn without_a_known_identity_nothing_but_health_answers() {
    let set = tempfile::tempdir().unwrap();
    let (server, _) = secured(set.path()).await;
    for token in [None, Some("not-a-token")] {
        let client = as_identity(&server, token).await;
        for rpc in ALL {
            let e = within("the request", attempt(&client, rpc)).await.unwrap_err();
            assert_eq!(e.code(), Some(Code::Unauthenticated), "{rpc:?}: {e}");
            if let Some(t) = token {
                assert!(!e.to_string().contains(t), "{e}");
            }
        }
    }
    let channel = tonic::transport::Channel::from_shared(server.url()).unwrap().connect().await.unwrap();
    let mut health = tonic_health::pb::health_client::HealthClient::new(channel);
    let answer =
        within("health", health.check(tonic_health::pb::HealthCheckRequest { service: String::new() }))
            .await
            .unwrap()
            .into_inner();
    assert_eq!(answer.status, tonic_health::pb::health_check_response::ServingStatus::Serving as i32);
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread")]
async fn a_reload_that_removes_a_robot_ends_its_stream_and_leaves_the_others() {
    let set = tempfile::tempdir().unwrap();
    let (server, tokens) = secured(set.path()).await;
    put_lines(&server, &tokens, 20.0).await;
    let realtime =
        |robot: &str| v1::ExecuteRequest { pacing: v1::Pacing::Realtime as i32, ..execute(robot, "cell-a") };
    let panda1 = as_identity(&server, Some(&tokens["panda-1"])).await;
    let panda2 = as_identity(&server, Some(&tokens["panda-2"])).await;
    let mut one = within("execute", panda1.execute(realtime("panda-1"))).await.unwrap();
    let mut two = within("execute", panda2.execute(realtime("panda-2"))).await.unwrap();
    within("segment", one.next()).await.unwrap().unwrap();
    within("segment", two.next()).await.unwrap().unwrap();
    // The operator removes panda-1 from the access file and sends SIGHUP.
    let path = set.path().join("access.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let kept: Vec<&str> =
        text.split("[[identity]]").filter(|block| !block.contains("name = \"panda-1\"")).collect();
    std::fs::write(&path, kept.join("[[identity]]")).unwrap();
    // Every identity with a token, and the server's own, less panda-1.
    assert_eq!(server.handle().reload_access().unwrap(), tokens.len());
    let ended = within("panda-1's stream ends", async {
        loop {
            match one.next().await {
                Some(Ok(_)) => continue,
                Some(Err(e)) => return e,
                None => panic!("ended without a status"),
            }
        }
    })
    .await;
    assert_eq!(ended.code(), Some(Code::PermissionDenied), "{ended}");
    assert!(ended.to_string().contains("panda-1"), "{ended}");
    // panda-2 goes on, and panda-1's token is refused from now on.
    for _ in 0..3 {
        within("segment", two.next()).await.unwrap().unwrap();
    }
    let e = within("list", panda1.list("panda-1")).await.unwrap_err();
    assert_eq!(e.code(), Some(Code::Unauthenticated), "{e}");
    // A file that does not parse changes nothing.
    std::fs::write(&path, "[[identity]]\nname = 3\n").unwrap();
    assert!(server.handle().reload_access().is_err());
    within("list", panda2.list("panda-2")).await.unwrap();
    drop((one, two));
    server.stop().await;
}
