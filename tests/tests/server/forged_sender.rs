//! A refused forged version names its sender when the server can know it: a peer linked to a secured server of
//! the plant with the admin's certificate (the generated access control lets an admin put on the replication
//! keys) puts a record at version 2^64 - 1; the server refuses it and the audit line names the certificate's
//! common name and the Zenoh id that stamped the sample.

use std::future::IntoFuture;

use dmp_proto::keys::primitive_version_key;
use dmp_proto::primitive::primitive_to_proto;
use dmp_proto::zenoh_session::{SessionOptions, ZenohTls, session_config};
use dmp_proto::{codec, v1};
use dmp_server::access::init::{InitOptions, init};
use dmp_server::server::start;
use dmp_tests::{config, within};
use zenoh::qos::CongestionControl;

use super::audit_log::{capture, lines_with};
use super::{line, until};

#[tokio::test(flavor = "multi_thread")]
async fn a_refused_forged_version_names_the_linked_sender() {
    capture();
    let set = tempfile::tempdir().unwrap();
    let data = tempfile::tempdir().unwrap();
    let options = InitOptions { cells: vec!["cell-a".into()], ..Default::default() };
    init(set.path(), &options).unwrap();
    let mut c = config(data.path());
    c.cell = "cell-a".into();
    c.plant.server_id = Some("forged-sender-s1".into());
    dmp_tests::secure(&mut c, set.path());
    let h = within("server start", start(c)).await.expect("server starts");
    let locator = h.zenoh_locators.iter().find(|l| l.starts_with("tls/")).unwrap().clone();

    let mut o = SessionOptions::loopback_peer(vec![locator]);
    o.listen = Some(Vec::new());
    o.tls = Some(ZenohTls {
        root_ca: set.path().join("ca.pem"),
        cert: set.path().join("admin.pem"),
        key: set.path().join("admin.key"),
        mutual: true,
    });
    let mut zc = session_config(&o).unwrap();
    zc.insert_json5("timestamping/enabled", "true").unwrap();
    let forger = within("forger open", zenoh::open(zc).into_future()).await.unwrap();
    let record = v1::PrimitiveRecord {
        robot_id: "forged-sender-r".into(),
        name: "x".into(),
        version: u64::MAX,
        created_unix_ms: 1,
        primitive: Some(primitive_to_proto(&line(vec![0.0], vec![9.0], 1.0))),
        origin_server: "somebody-else".into(),
    };
    let key = primitive_version_key(&record.robot_id, &record.name, record.version);
    let sent = forger.put(&key, codec::encode(&record)).congestion_control(CongestionControl::Block);
    within("forged put", sent.into_future()).await.unwrap();
    let zid = forger.zid().to_string();
    let want = ["identity=admin", "action=replicate", "forged-sender-r", "somebody-else", zid.as_str()];
    until("the refusal names the sender", || !lines_with(&want).is_empty()).await;
    assert!(h.store().get("forged-sender-r", "x", 0).is_err(), "nothing stored");
    within("close", forger.close().into_future()).await.unwrap();
    within("shutdown", h.shutdown()).await.unwrap();
}
