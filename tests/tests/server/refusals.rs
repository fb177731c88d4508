//! Refused attempts are on the audit log, rate-limited, with identity, action and reason: a role's refusals over
//! gRPC, and a stream ended by a reload of the access file. A bad token is refused without being repeated. (The
//! limiter's own bounds are unit-tested in `server/src/access/audit.rs`: tests here share one limiter, so each
//! uses identities only it has.)

use dmp_client::DmpClient;
use dmp_client::connect::{ConnectOptions, TlsOptions};
use dmp_tests::within;
use tokio_stream::StreamExt;
use tonic::Code;

use super::audit_log::{capture, lines_with};
use dmp_proto::v1;

use super::{line, secured_cell_a, spec, until};

#[tokio::test(flavor = "multi_thread")]
async fn refusals_are_audited_with_identity_action_and_reason_at_most_five_per_window() {
    capture();
    let set = tempfile::tempdir().unwrap();
    let data = tempfile::tempdir().unwrap();
    let (h, _, tokens) = secured_cell_a(set.path(), data.path(), &["audited-1", "audited-2"]).await;
    let token = |name: &str| tokens.iter().find(|(n, _)| n == name).unwrap().1.clone();
    let url = format!("https://{}", h.grpc_addr);
    let connect = |token: String| {
        let tls = TlsOptions::from_files(&set.path().join("ca.pem"), None, None).unwrap();
        let options = ConnectOptions { token: Some(token), tls: Some(tls), ..Default::default() };
        let url = url.clone();
        async move { within("connect", DmpClient::connect_with(&url, &options)).await.unwrap() }
    };
    let one = connect(token("audited-1")).await;
    for _ in 0..20 {
        let e = within("list", one.list("audited-2")).await.unwrap_err();
        assert_eq!(e.code(), Some(Code::PermissionDenied), "{e}");
    }
    let denied =
        ["identity=audited-1", "action=/dmp.v1.", "may not read the primitives of robot `audited-2`"];
    until("the refusals are audited", || lines_with(&denied).len() == 5).await;
    assert!(lines_with(&denied).iter().all(|l| l.contains("level=WARN") && l.contains("suppressed=0")));

    // A token that names no identity: refused, and never written down.
    let stranger = connect("not-a-token-5f3a".into()).await;
    let e = within("list", stranger.list("audited-1")).await.unwrap_err();
    assert_eq!(e.code(), Some(Code::Unauthenticated), "{e}");
    assert!(lines_with(&["not-a-token-5f3a"]).is_empty());

    // audited-2 streams its robot; a reload removes it: the stream ends, audited.
    let admin = connect(token("admin")).await;
    within("put", admin.put_primitive("audited-2", "line", &line(vec![0.0, 0.0], vec![1.0, 0.0], 20.0)))
        .await
        .unwrap();
    let two = connect(token("audited-2")).await;
    let request = v1::ExecuteRequest {
        motion: Some(v1::MotionSpec { cell: "cell-a".into(), ..spec("audited-2", "line") }),
        pacing: v1::Pacing::Realtime as i32,
        ..Default::default()
    };
    let mut stream = within("execute", two.execute(request)).await.unwrap();
    within("first segment", stream.next()).await.unwrap().unwrap();
    let path = set.path().join("access.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let kept: Vec<&str> =
        text.split("[[identity]]").filter(|block| !block.contains("name = \"audited-2\"")).collect();
    std::fs::write(&path, kept.join("[[identity]]")).unwrap();
    h.reload_access().unwrap();
    let ended = within("the stream ends", async {
        loop {
            match stream.next().await {
                Some(Ok(_)) => continue,
                Some(Err(e)) => return e,
                None => panic!("ended without a status"),
            }
        }
    })
    .await;
    assert!(ended.to_string().contains("audited-2"), "{ended}");
    let stream = ["identity=audited-2", "action=stream", "no longer in the access file"];
    until("the ended stream is audited", || lines_with(&stream).len() == 1).await;
    drop((one, two, stranger, admin));
    within("shutdown", h.shutdown()).await.unwrap();
}
