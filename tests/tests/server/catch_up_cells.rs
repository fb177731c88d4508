//! The scene catch-up reaches every perception node that may publish in the cell: a node's queryable on its own
//! cell's obstacles (`dmp/<cell>/obstacles/**`) is asked as well as one on every cell's, whichever comes first,
//! and under the generated access control a perception identity's queryable is declared and asked.

use std::future::IntoFuture;
use std::path::Path;

use dmp_proto::zenoh_session::{SessionOptions, ZenohTls, session_config};
use dmp_server::server::ServerHandle;
use dmp_tests::within;
use zenoh::query::Queryable;

use super::{secured_cell_a, serve, until};

fn has_obstacle(h: &ServerHandle, cell: &str, id: &str) -> bool {
    h.cells().find(cell).unwrap().is_some_and(|c| c.snapshot().obstacles.contains_key(id))
}

/// A node on `connect` (with the certificate of `identity` in `set`, if any).
async fn node(connect: &str, tls: Option<(&Path, &str)>) -> zenoh::Session {
    let mut options = SessionOptions::loopback_peer(vec![connect.to_owned()]);
    options.listen = Some(Vec::new());
    options.tls = tls.map(|(set, name)| ZenohTls {
        root_ca: set.join("ca.pem"),
        cert: set.join(format!("{name}.pem")),
        key: set.join(format!("{name}.key")),
        mutual: true,
    });
    let mut config = session_config(&options).unwrap();
    config.insert_json5("connect/timeout_ms", "2000").unwrap();
    within("open", zenoh::open(config).into_future()).await.unwrap()
}

/// Declares a queryable on `key` that answers with obstacle `id` of `cell` (JSON, as a perception node puts it).
async fn answer(session: &zenoh::Session, key: &str, cell: &str, id: &str) -> Queryable<()> {
    let reply_key = format!("dmp/{cell}/obstacles/{id}");
    let payload = format!(r#"{{"id": "{id}", "center": [0.5, 0.5], "semi_axes": [0.1, 0.1]}}"#);
    let q = session.declare_queryable(key).callback(move |query| {
        use zenoh::Wait;
        let _ = query.reply(&reply_key, payload.clone()).wait();
    });
    within("queryable", q.into_future()).await.unwrap()
}

#[tokio::test(flavor = "multi_thread")]
async fn per_cell_and_every_cell_queryables_are_all_asked_whichever_comes_first() {
    let dir = tempfile::tempdir().unwrap();
    let (h, _client) = serve(dir.path()).await;
    let connect = h.zenoh_locators[0].clone();
    // A node serving its own cell only.
    let narrow = node(&connect, None).await;
    let _q1 = answer(&narrow, "dmp/default/obstacles/**", "default", "narrow-1").await;
    until("the per-cell node is asked", || has_obstacle(&h, "default", "narrow-1")).await;
    // One serving every cell, then another per-cell one: each is asked although others already answer.
    let wide = node(&connect, None).await;
    let _q2 = answer(&wide, "dmp/*/obstacles/**", "default", "wide").await;
    until("the every-cell node is asked", || has_obstacle(&h, "default", "wide")).await;
    let late = node(&connect, None).await;
    let _q3 = answer(&late, "dmp/default/obstacles/**", "default", "narrow-2").await;
    until("the late per-cell node is asked", || has_obstacle(&h, "default", "narrow-2")).await;
    for s in [narrow, wide, late] {
        within("close", s.close().into_future()).await.unwrap();
    }
    within("shutdown", h.shutdown()).await.unwrap();
}

#[tokio::test(flavor = "multi_thread")]
async fn under_the_generated_access_control_a_perception_node_is_asked() {
    let set = tempfile::tempdir().unwrap();
    let data = tempfile::tempdir().unwrap();
    let (h, locator, _) = secured_cell_a(set.path(), data.path(), &["catch-up-bot"]).await;
    // As the client library declares it: every cell's obstacles; it may answer only for its own.
    let eyes = node(&locator, Some((set.path(), "perception"))).await;
    let _q1 = answer(&eyes, "dmp/*/obstacles/**", "cell-a", "seen").await;
    until("the perception node is asked", || has_obstacle(&h, "cell-a", "seen")).await;
    // Its own cell's only.
    let cell = node(&locator, Some((set.path(), "perception"))).await;
    let _q2 = answer(&cell, "dmp/cell-a/obstacles/**", "cell-a", "seen-by-cell").await;
    until("the per-cell perception node is asked", || has_obstacle(&h, "cell-a", "seen-by-cell")).await;
    for s in [eyes, cell] {
        within("close", s.close().into_future()).await.unwrap();
    }
    within("shutdown", h.shutdown()).await.unwrap();
}
