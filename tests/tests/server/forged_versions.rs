//! Forged version numbers (issue 35, item 2): in an open plant anyone on the Zenoh network can put what a server
//! puts. A record at version 2^64 - 1 and a tombstone at 2^64 - 1, sent on the replication keys (the subscription)
//! and in a catch-up reply (the queryable), are refused by every server; the normal learn, delete and re-learn go
//! on as before. Two servers and a forger, clients of one router in the test process (loopback, scouting off).

use std::future::IntoFuture;

use dmp_client::grpc::DmpClient;
use dmp_proto::keys::{every_primitive, primitive_version_key};
use dmp_proto::primitive::primitive_to_proto;
use dmp_proto::{codec, v1};
use dmp_server::server::ServerHandle;
use dmp_tests::within;
use zenoh::qos::CongestionControl;

use crate::plant::{Loopback, loopback, plant_server, shut_down, until_all_known};
use crate::{line, until};

/// A Zenoh client of the router at `endpoint`, as anyone on the plant's network can open.
async fn forger(endpoint: &[String]) -> zenoh::Session {
    let mut c = zenoh::Config::default();
    c.insert_json5("mode", "\"client\"").unwrap();
    c.insert_json5("connect/endpoints", &serde_json::to_string(endpoint).unwrap()).unwrap();
    c.insert_json5("scouting/multicast/enabled", "false").unwrap();
    c.insert_json5("scouting/gossip/enabled", "false").unwrap();
    within("forger open", zenoh::open(c).into_future()).await.unwrap()
}

/// A well-formed record of `(r, name)` at `version`, claiming to come from `origin`.
fn record(name: &str, version: u64, origin: &str) -> v1::PrimitiveRecord {
    v1::PrimitiveRecord {
        robot_id: "r".into(),
        name: name.into(),
        version,
        created_unix_ms: 1,
        primitive: Some(primitive_to_proto(&line(vec![0.0], vec![9.0], 1.0))),
        origin_server: origin.into(),
    }
}

/// The forger's clock now (NTP64, as the servers stamp versions): a record at it is within any skew.
fn now(forger: &zenoh::Session) -> u64 {
    forger.new_timestamp().get_time().as_u64()
}

/// Puts `r` on its replication key, reliably (a dropped put would make the test pass for nothing).
async fn put(forger: &zenoh::Session, r: &v1::PrimitiveRecord) {
    let key = primitive_version_key(&r.robot_id, &r.name, r.version);
    let sent = forger.put(key, codec::encode(r)).congestion_control(CongestionControl::Block);
    within("forged put", sent.into_future()).await.unwrap();
}

async fn client_of(h: &ServerHandle) -> DmpClient {
    within("connect", DmpClient::connect(format!("http://{}", h.grpc_addr))).await.expect("connects")
}

/// The latest version of `(r, name)` on `h`, if any.
fn latest(h: &ServerHandle, name: &str) -> Option<u64> {
    h.store().get("r", name, 0).ok().map(|r| r.version)
}

#[tokio::test(flavor = "multi_thread")]
async fn a_record_or_tombstone_forged_at_the_end_of_time_is_refused_and_learning_goes_on() {
    let Loopback { zenohd, endpoint, dirs } = loopback(2).await;
    let s1 = plant_server(dirs[0].path(), &endpoint, "s1", &["a"], &[]).await;
    let s2 = plant_server(dirs[1].path(), &endpoint, "s2", &["b"], &[]).await;
    until_all_known(&[&s1, &s2]).await;
    let (c1, c2) = (client_of(&s1).await, client_of(&s2).await);
    let x = within("put x", c1.put_primitive("r", "x", &line(vec![0.0], vec![1.0], 1.0))).await.unwrap();
    let y = within("put y", c1.put_primitive("r", "y", &line(vec![0.0], vec![2.0], 1.0))).await.unwrap();
    until("s2 holds x and y", || latest(&s2, "x") == Some(x.version) && latest(&s2, "y") == Some(y.version))
        .await;

    // The attack, on the subscription: x at 2^64 - 1 in s1's name, a tombstone of y at 2^64 - 1. Then a record
    // the servers accept, from the same session: once it is stored, the forged ones were handled (in order).
    let f = forger(&endpoint).await;
    put(&f, &record("x", u64::MAX, "s1")).await;
    let stone =
        f.delete(primitive_version_key("r", "y", u64::MAX)).congestion_control(CongestionControl::Block);
    within("forged tombstone", stone.into_future()).await.unwrap();
    let marker = record("marker", now(&f), "s1");
    put(&f, &marker).await;
    let servers = [&s1, &s2];
    until("both hold the marker", || servers.iter().all(|h| latest(h, "marker") == Some(marker.version)))
        .await;
    for h in servers {
        assert_eq!(latest(h, "x"), Some(x.version), "the forged x is not the latest");
        assert!(h.store().get("r", "x", u64::MAX).is_err(), "nor stored");
        assert_eq!(latest(h, "y"), Some(y.version), "the forged tombstone deleted nothing");
        assert_eq!(h.store().tombstone("r", "y").unwrap(), None, "nor was it recorded");
    }

    // Learn, delete, re-learn: as before, on every server.
    let x2 = within("relearn x on s2", c2.put_primitive("r", "x", &line(vec![0.0], vec![3.0], 1.0)))
        .await
        .unwrap();
    assert!(
        x2.version > x.version && x2.version < marker.version + (60 << 32),
        "the clock, not after 2^64 - 1"
    );
    until("x2 everywhere", || servers.iter().all(|h| latest(h, "x") == Some(x2.version))).await;
    within("delete x on s1", c1.delete("r", "x")).await.unwrap();
    until("x deleted everywhere", || servers.iter().all(|h| latest(h, "x").is_none())).await;
    let x3 = within("learn x again on s2", c2.put_primitive("r", "x", &line(vec![0.0], vec![4.0], 1.0)))
        .await
        .unwrap();
    assert!(x3.version > x2.version);
    until("x3 everywhere, the latest", || servers.iter().all(|h| latest(h, "x") == Some(x3.version))).await;
    // y replicates again: deleted on s2, learned on s1, everywhere.
    within("delete y on s2", c2.delete("r", "y")).await.unwrap();
    until("y deleted everywhere", || servers.iter().all(|h| latest(h, "y").is_none())).await;
    let y2 =
        within("learn y again", c1.put_primitive("r", "y", &line(vec![0.0], vec![5.0], 1.0))).await.unwrap();
    until("y2 everywhere", || servers.iter().all(|h| latest(h, "y") == Some(y2.version))).await;

    // The attack, in a catch-up: s2 restarts with only the forger to ask, which answers x at 2^64 - 1, a
    // tombstone of x at 2^64 - 1, a new name z at 2^64 - 1, then a second marker.
    within("s1 down", s1.shutdown()).await.unwrap();
    within("s2 down", s2.shutdown()).await.unwrap();
    let queryable =
        within("forged queryable", f.declare_queryable(every_primitive()).into_future()).await.unwrap();
    let marker2 = record("marker2", now(&f), "s1");
    let answers = marker2.clone();
    let answering = tokio::spawn(async move {
        while let Ok(query) = queryable.handler().recv_async().await {
            let x_key = primitive_version_key("r", "x", u64::MAX);
            query.reply(x_key.clone(), codec::encode(&record("x", u64::MAX, "s1"))).await.unwrap();
            query.reply_del(x_key).await.unwrap();
            let z = record("z", u64::MAX, "s2");
            query.reply(primitive_version_key("r", "z", u64::MAX), codec::encode(&z)).await.unwrap();
            let m = primitive_version_key("r", "marker2", answers.version);
            query.reply(m, codec::encode(&answers)).await.unwrap();
        }
    });
    let s2 = plant_server(dirs[1].path(), &endpoint, "s2", &["b"], &[]).await;
    until("s2 caught up with the forger", || latest(&s2, "marker2") == Some(marker2.version)).await;
    assert_eq!(latest(&s2, "x"), Some(x3.version), "the forged x is refused in a catch-up too");
    assert!(
        s2.store().tombstone("r", "x").unwrap().is_some_and(|n| n < x3.version),
        "the forged one refused"
    );
    assert_eq!(latest(&s2, "z"), None);
    let c2 = client_of(&s2).await;
    let x4 =
        within("learn x after", c2.put_primitive("r", "x", &line(vec![0.0], vec![6.0], 1.0))).await.unwrap();
    assert!(x4.version > x3.version);
    assert_eq!(latest(&s2, "x"), Some(x4.version));

    answering.abort();
    within("forger close", f.close().into_future()).await.unwrap();
    shut_down([s2], zenohd).await;
}
