//! Competing claims on a cell resolve to one owner by the same rule on every server, and converge when a
//! claimant leaves: a fake server `0` claims cell `a` of s1 in a plant of two real servers behind a router; once it
//! is gone, both servers have s1 as the home of `a` and s2 never takes it (before, the last announcement heard
//! decided: `0` stayed the home, and s2, the rendezvous pick for `a`, served it too).

use std::future::IntoFuture;
use std::time::{Duration, Instant};

use dmp_proto::keys::server_key;
use dmp_proto::{codec, v1};
use dmp_server::server::ServerHandle;
use dmp_tests::within;
use zenoh::Wait;

use super::plant::{loopback, plant_server, shut_down, until_all_known};
use super::until;

fn home_of(h: &ServerHandle, cell: &str) -> Option<String> {
    h.cells().directory().homes().get(cell).cloned()
}

#[tokio::test(flavor = "multi_thread")]
async fn a_fake_claimant_that_leaves_hands_the_cell_back_to_its_server_everywhere() {
    let plant = loopback(2).await;
    let s1 = plant_server(plant.dirs[0].path(), &plant.endpoint, "s1", &["a"], &[]).await;
    let s2 = plant_server(plant.dirs[1].path(), &plant.endpoint, "s2", &["b"], &[]).await;
    until_all_known(&[&s1, &s2]).await;

    // The fake: a client of the router announcing server `0` of cell `a`, at an address nobody listens on.
    let mut c = zenoh::Config::default();
    c.insert_json5("mode", "\"client\"").unwrap();
    c.insert_json5("connect/endpoints", &serde_json::to_string(&plant.endpoint).unwrap()).unwrap();
    c.insert_json5("scouting/multicast/enabled", "false").unwrap();
    let fake = within("fake open", zenoh::open(c).into_future()).await.unwrap();
    let me = v1::PlantServer {
        server_id: "0".into(),
        grpc_address: "http://127.0.0.1:1".into(),
        cells: vec!["a".into()],
        ..Default::default()
    };
    let (key, payload) = (server_key("0"), codec::encode(&me));
    let reply_key = key.clone();
    let _answers = within(
        "fake queryable",
        fake.declare_queryable(&key)
            .callback(move |q| {
                let _ = q.reply(&reply_key, payload.clone()).wait();
            })
            .into_future(),
    )
    .await
    .unwrap();
    let _token = within("fake token", fake.liveliness().declare_token(&key).into_future()).await.unwrap();
    until("both know the fake", || [&s1, &s2].iter().all(|h| h.cells().directory().server_ids().len() == 3))
        .await;
    // While it lives, both apply the same rule to the same claims.
    assert_eq!(home_of(&s1, "a"), home_of(&s2, "a"));

    within("fake leaves", fake.close().into_future()).await.unwrap();
    let left = Instant::now();
    until("both see it gone", || [&s1, &s2].iter().all(|h| h.cells().directory().server_ids().len() == 2))
        .await;
    until("s1 is the home of a everywhere", || {
        [&s1, &s2].iter().all(|h| home_of(h, "a").as_deref() == Some("s1"))
    })
    .await;
    eprintln!("converged {:?} after the fake left", left.elapsed());
    // And s2 does not take it (it is the rendezvous pick for `a` among s1 and s2, were the home gone).
    let watch = Instant::now();
    while watch.elapsed() < Duration::from_millis(500) {
        assert!(!s2.cells().serves("a"), "s2 took cell a: two servers serve it");
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
    assert!(s1.cells().serves("a"));
    shut_down([s1, s2], plant.zenohd).await;
}
