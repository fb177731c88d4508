//! Zenoh under the access file: the server's `tls/` endpoint takes only peers with a certificate of the cell's CA,
//! and the access control generated from the access file (default deny) lets each do only what its role may, on
//! the server's own session, checked here with stock Zenoh sessions.

use std::future::IntoFuture;
use std::path::Path;

use dmp_proto::keys::{obstacle_key, robot_state_key};
use dmp_proto::zenoh_session::{SessionOptions, ZenohTls, session_config};
use dmp_proto::{codec, v1};
use dmp_server::server::ServerHandle;
use dmp_tests::within;

use crate::{secured_cell_a, until};

/// A peer connecting to `locator` with the certificate of `identity` (none: no certificate).
async fn peer(set: &Path, locator: &str, identity: Option<&str>) -> zenoh::Result<zenoh::Session> {
    let mut options = SessionOptions::loopback_peer(vec![locator.to_owned()]);
    options.listen = Some(Vec::new());
    let mut config = if let Some(name) = identity {
        options.tls = Some(ZenohTls {
            root_ca: set.join("ca.pem"),
            cert: set.join(format!("{name}.pem")),
            key: set.join(format!("{name}.key")),
            mutual: true,
        });
        session_config(&options).unwrap()
    } else {
        let mut c = session_config(&options).unwrap();
        let ca = serde_json::Value::from(set.join("ca.pem").display().to_string()).to_string();
        c.insert_json5("transport/link/tls/root_ca_certificate", &ca).unwrap();
        c
    };
    config.insert_json5("connect/timeout_ms", "2000").unwrap();
    zenoh::open(config).await
}

fn obstacle(id: &str) -> String {
    format!(r#"{{"id": "{id}", "center": [5.0, 5.0], "semi_axes": [0.1, 0.1]}}"#)
}

fn in_scene(h: &ServerHandle, cell: &str, id: &str) -> bool {
    h.cells().find(cell).unwrap().is_some_and(|c| c.snapshot().obstacles.contains_key(id))
}

fn now_unix_s() -> f64 {
    std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap().as_secs_f64()
}

fn state(id: &str) -> Vec<u8> {
    codec::encode(&v1::RobotState {
        robot_id: id.into(),
        stamp_unix_s: now_unix_s(),
        position: vec![0.5, 0.25],
        velocity: vec![0.0, 0.0],
        footprint: Some(v1::Superquadric { semi_axes: vec![0.2, 0.2], exponents: vec![] }),
        ..Default::default()
    })
}

#[tokio::test(flavor = "multi_thread")]
async fn each_zenoh_peer_does_only_what_its_role_may() {
    let set = tempfile::tempdir().unwrap();
    let s = set.path();
    let data = tempfile::tempdir().unwrap();
    let (h, locator, _) = secured_cell_a(s, data.path(), &["panda-1"]).await;

    // A peer without a certificate cannot even connect.
    assert!(within("open", peer(s, &locator, None)).await.is_err(), "connected without a certificate");

    // Perception of cell-a: its obstacles go in; another cell's and a robot state do not.
    let eyes = within("open", peer(s, &locator, Some("perception"))).await.unwrap();
    let put = |session: &zenoh::Session, key: String, payload: Vec<u8>| {
        let session = session.clone();
        async move { within("put", session.put(key, payload).into_future()).await.unwrap() }
    };
    put(&eyes, obstacle_key("cell-b", "elsewhere"), obstacle("elsewhere").into_bytes()).await;
    put(&eyes, robot_state_key("cell-a", "ghost"), state("ghost")).await;
    // A robot's certificate (robots stream over gRPC) changes nothing either.
    let robot = within("open", peer(s, &locator, Some("panda-1"))).await.unwrap();
    put(&robot, obstacle_key("cell-a", "from-robot"), obstacle("from-robot").into_bytes()).await;
    put(&robot, robot_state_key("cell-a", "ghost-2"), state("ghost-2")).await;
    // Then an allowed put: it arrives after the others would have (one link, in order).
    put(&eyes, obstacle_key("cell-a", "seen"), obstacle("seen").into_bytes()).await;
    until("the allowed obstacle arrives", || in_scene(&h, "cell-a", "seen")).await;
    put(&robot, obstacle_key("cell-a", "marker"), obstacle("marker").into_bytes()).await;
    put(&eyes, obstacle_key("cell-a", "after-robot"), obstacle("after-robot").into_bytes()).await;
    until("the second allowed obstacle arrives", || in_scene(&h, "cell-a", "after-robot")).await;
    // An observer reads only; a planner of cell-a may change its scene.
    let observer = within("open", peer(s, &locator, Some("observer"))).await.unwrap();
    let planner = within("open", peer(s, &locator, Some("planner"))).await.unwrap();
    put(&observer, obstacle_key("cell-a", "by-observer"), obstacle("by-observer").into_bytes()).await;
    put(&planner, obstacle_key("cell-a", "by-planner"), obstacle("by-planner").into_bytes()).await;
    until("the planner's obstacle arrives", || in_scene(&h, "cell-a", "by-planner")).await;
    put(&observer, obstacle_key("cell-a", "by-observer-2"), obstacle("by-observer-2").into_bytes()).await;
    put(&eyes, obstacle_key("cell-a", "after-observer"), obstacle("after-observer").into_bytes()).await;
    until("the last allowed obstacle arrives", || in_scene(&h, "cell-a", "after-observer")).await;
    assert!(
        !in_scene(&h, "cell-a", "by-observer") && !in_scene(&h, "cell-a", "by-observer-2"),
        "an observer changed the scene"
    );
    assert!(!in_scene(&h, "cell-b", "elsewhere"), "perception of cell-a changed cell-b");
    assert!(
        !in_scene(&h, "cell-a", "from-robot") && !in_scene(&h, "cell-a", "marker"),
        "a robot changed the scene"
    );
    let cell = h.cells().find("cell-a").unwrap().unwrap();
    assert_eq!(cell.robot_count(), 0, "a robot state was taken from a perception node or a robot");

    // A server of the plant (the router's certificate, role `server`) may publish robot states.
    let other_server = within("open", peer(s, &locator, Some("zenoh-router"))).await.unwrap();
    put(&other_server, robot_state_key("cell-a", "remote"), state("remote")).await;
    until("the other server's robot arrives", || cell.robot_count() == 1).await;

    for session in [eyes, robot, other_server, observer, planner] {
        within("close", session.close().into_future()).await.unwrap();
    }
    within("shutdown", h.shutdown()).await.unwrap();
}

/// The Zenoh key classes × every role with a certificate: obstacles of its cell (put and delete), obstacles of
/// another cell, robot states (put), and reading the robot states the server publishes. Not covered here: deletes
/// of robot states, robots' liveliness tokens and answers to the server's catch-up query (the ACL grants them with
/// the same rules as the puts; `zenoh_acl.rs` tests the rules).
#[tokio::test(flavor = "multi_thread")]
async fn the_zenoh_denial_matrix_holds_for_every_key_class_and_role() {
    use dmp_client::DmpClient;
    use dmp_client::connect::{ConnectOptions, TlsOptions};
    use std::sync::Arc;
    use std::sync::atomic::{AtomicUsize, Ordering};
    use tokio_stream::StreamExt;

    let set = tempfile::tempdir().unwrap();
    let s = set.path();
    let data = tempfile::tempdir().unwrap();
    let (h, locator, tokens) = secured_cell_a(s, data.path(), &["panda-1"]).await;

    // role: (obstacles of its cell, obstacles of another cell, robot states, reads the cell)
    let matrix = [
        ("perception", (true, false, false, false)),
        ("planner", (true, false, false, true)),
        ("observer", (false, false, false, true)),
        ("panda-1", (false, false, false, false)),
        ("zenoh-router", (true, true, true, true)),
        ("admin", (true, true, true, true)),
    ];
    let admin = within("open", peer(s, &locator, Some("admin"))).await.unwrap();
    let put = |session: &zenoh::Session, key: String, payload: Vec<u8>| {
        let session = session.clone();
        async move { within("put", session.put(key, payload).into_future()).await.unwrap() }
    };
    let mut marker = 0;
    let mut sessions = Vec::new();
    let mut received = Vec::new();
    for (role, (obstacles, elsewhere, states, reads)) in matrix {
        let session = within("open", peer(s, &locator, Some(role))).await.unwrap();
        // Put, and delete what the admin put.
        let (mine, gone, far) = (format!("by-{role}"), format!("delete-by-{role}"), format!("far-by-{role}"));
        put(&admin, obstacle_key("cell-a", &gone), obstacle(&gone).into_bytes()).await;
        until("the admin's obstacle arrives", || in_scene(&h, "cell-a", &gone)).await;
        put(&session, obstacle_key("cell-a", &mine), obstacle(&mine).into_bytes()).await;
        within("delete", session.delete(obstacle_key("cell-a", &gone)).into_future()).await.unwrap();
        put(&session, obstacle_key("cell-b", &far), obstacle(&far).into_bytes()).await;
        put(&session, robot_state_key("cell-a", &format!("ghost-{role}")), state(&format!("ghost-{role}")))
            .await;
        // A marker after them: once it is in, everything before it on the same link was handled. A role that may
        // put obstacles sends it on its own link; for the others (observer, robot) it comes from the admin, on
        // another link, so their denials are checked after a round trip rather than in order.
        marker += 1;
        let m = format!("marker-{marker}");
        let by = if obstacles { &session } else { &admin };
        put(by, obstacle_key("cell-a", &m), obstacle(&m).into_bytes()).await;
        until("the marker arrives", || in_scene(&h, "cell-a", &m)).await;
        if obstacles {
            until("an allowed put arrives", || in_scene(&h, "cell-a", &mine)).await;
            until("an allowed delete arrives", || !in_scene(&h, "cell-a", &gone)).await;
        } else {
            assert!(!in_scene(&h, "cell-a", &mine), "{role} put an obstacle");
            assert!(in_scene(&h, "cell-a", &gone), "{role} deleted an obstacle");
        }
        if elsewhere {
            until("an allowed put in another cell arrives", || in_scene(&h, "cell-b", &far)).await;
        } else {
            assert!(!in_scene(&h, "cell-b", &far), "{role} put an obstacle in another cell");
        }
        let ghost = format!("ghost-{role}");
        let cell = h.cells().find("cell-a").unwrap().unwrap();
        let seen =
            || cell.other_robots("", f64::MAX / 4.0, f64::MAX).iter().any(|r| r.state.robot_id == ghost);
        if states {
            until("an allowed robot state arrives", seen).await;
        } else {
            assert!(!seen(), "{role} published a robot state");
        }
        // Reading: count the robot states the server publishes while a robot streams (below).
        let count = Arc::new(AtomicUsize::new(0));
        let counter = count.clone();
        let subscriber = within(
            "subscribe",
            session
                .declare_subscriber(robot_state_key("cell-a", "panda-1"))
                .callback(move |_| {
                    counter.fetch_add(1, Ordering::Relaxed);
                })
                .into_future(),
        )
        .await
        .unwrap();
        received.push((role, reads, count));
        sessions.push((session, subscriber));
    }

    // A robot streams in real time: the server publishes its states to the readers that may see them.
    let admin_token = tokens.iter().find(|(n, _)| n == "admin").unwrap().1.clone();
    let tls = TlsOptions::from_files(&s.join("ca.pem"), None, None).unwrap();
    let connect = ConnectOptions { tls: Some(tls), token: Some(admin_token), ..Default::default() };
    let client = within("connect", DmpClient::connect_with(&format!("https://{}", h.grpc_addr), &connect))
        .await
        .unwrap();
    within("put", client.put_primitive("panda-1", "line", &crate::line(vec![0.0, 0.0], vec![1.0, 0.0], 0.5)))
        .await
        .unwrap();
    let request = dmp_proto::v1::ExecuteRequest {
        motion: Some(crate::spec("panda-1", "line")),
        pacing: dmp_proto::v1::Pacing::Realtime as i32,
        ..Default::default()
    };
    let mut stream = within("execute", client.execute(request)).await.unwrap();
    while let Some(segment) = within("segment", stream.next()).await {
        segment.unwrap();
    }
    let readers: Vec<_> = received.iter().filter(|(_, reads, _)| *reads).collect();
    until("every allowed reader got robot states", || {
        readers.iter().all(|(_, _, n)| n.load(Ordering::Relaxed) >= 3)
    })
    .await;
    for (role, reads, count) in &received {
        if !reads {
            assert_eq!(count.load(Ordering::Relaxed), 0, "{role} read the robot states");
        }
    }
    // The denials once more, a robot's whole run later: the observer's and the robot's were first checked after a
    // marker on another link, which does not order them.
    let cell = h.cells().find("cell-a").unwrap().unwrap();
    for (role, (obstacles, elsewhere, states, _)) in matrix {
        if !obstacles {
            assert!(!in_scene(&h, "cell-a", &format!("by-{role}")), "{role} put an obstacle");
            assert!(in_scene(&h, "cell-a", &format!("delete-by-{role}")), "{role} deleted an obstacle");
        }
        if !elsewhere {
            assert!(
                !in_scene(&h, "cell-b", &format!("far-by-{role}")),
                "{role} put an obstacle in another cell"
            );
        }
        let ghost = format!("ghost-{role}");
        let seen = cell.other_robots("", f64::MAX / 4.0, f64::MAX).iter().any(|r| r.state.robot_id == ghost);
        assert!(states || !seen, "{role} published a robot state");
    }
    for (session, subscriber) in sessions {
        within("undeclare", subscriber.undeclare().into_future()).await.unwrap();
        within("close", session.close().into_future()).await.unwrap();
    }
    within("close", admin.close().into_future()).await.unwrap();
    within("shutdown", h.shutdown()).await.unwrap();
}
