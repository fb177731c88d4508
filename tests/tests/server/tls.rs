//! gRPC over TLS: certificates name identities; a client that trusts another CA, presents a certificate of
//! another CA, or speaks plaintext fails cleanly while everyone else goes on. And secure by default: exposure
//! beyond loopback without protection is refused unless `--insecure`, which GetInfo repeats.

use std::path::Path;

use dmp_client::DmpClient;
use dmp_client::connect::{ConnectOptions, TlsOptions};
use dmp_proto::v1;
use dmp_server::access::init::{InitOptions, init};
use dmp_tests::{TestServer, within};
use tokio_stream::StreamExt;

use crate::{line, spec};

fn set(dir: &Path) -> Vec<(String, String)> {
    let options =
        InitOptions { cells: vec!["cell-a".into()], robots: vec!["panda-1".into()], ..Default::default() };
    init(dir, &options).unwrap().tokens
}

fn tls(ca: &Path, identity: Option<(&Path, &str)>) -> TlsOptions {
    let cert = identity.map(|(dir, name)| dir.join(format!("{name}.pem")));
    let key = identity.map(|(dir, name)| dir.join(format!("{name}.key")));
    TlsOptions::from_files(ca, cert.as_deref(), key.as_deref()).unwrap()
}

async fn connect(url: &str, tls: Option<TlsOptions>, token: Option<&str>) -> Result<DmpClient, String> {
    let options = ConnectOptions { tls, token: token.map(str::to_owned), ..Default::default() };
    let client =
        within("connect", DmpClient::connect_with(url, &options)).await.map_err(|e| e.to_string())?;
    // A failure may only show at the first call.
    within("info", client.info()).await.map_err(|e| e.to_string())?;
    Ok(client)
}

#[tokio::test(flavor = "multi_thread")]
async fn certificates_name_identities_and_bad_clients_fail_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let other = tempfile::tempdir().unwrap();
    let (d, o) = (dir.path(), other.path());
    let tokens = set(d);
    set(o);
    let server = TestServer::start_with(|c| {
        c.zenoh.disabled = true;
        c.cell = "cell-a".into();
        c.security.access = Some(d.join("access.toml"));
        c.security.tls_cert = Some(d.join("server.pem"));
        c.security.tls_key = Some(d.join("server.key"));
        c.security.tls_client_ca = Some(d.join("ca.pem"));
    })
    .await;
    let url = format!("https://{}", server.handle().grpc_addr);
    // Mutual TLS: the certificate's common name is the identity.
    let panda = connect(&url, Some(tls(&d.join("ca.pem"), Some((d, "panda-1")))), None).await.unwrap();
    let info = within("info", panda.info()).await.unwrap();
    assert_eq!((info.identity.as_str(), info.role.as_str()), ("panda-1", "robot"));
    assert!(info.tls && info.mutual_tls && info.access_control && !info.insecure, "{info:?}");
    // TLS without a client certificate, and a token.
    let admin_token = &tokens.iter().find(|(n, _)| n == "admin").unwrap().1;
    let admin = connect(&url, Some(tls(&d.join("ca.pem"), None)), Some(admin_token)).await.unwrap();
    within("put", admin.put_primitive("panda-1", "line", &line(vec![0.0, 0.0], vec![1.0, 0.0], 10.0)))
        .await
        .unwrap();
    let request = v1::ExecuteRequest {
        motion: Some(v1::MotionSpec { cell: "cell-a".into(), ..spec("panda-1", "line") }),
        pacing: v1::Pacing::Realtime as i32,
        ..Default::default()
    };
    let mut running = within("execute", panda.execute(request)).await.unwrap();
    within("segment", running.next()).await.unwrap().unwrap();

    // A client that trusts another CA: the handshake fails.
    let e = connect(&url, Some(tls(&o.join("ca.pem"), None)), Some(admin_token)).await.unwrap_err();
    assert!(e.contains("certificate") || e.contains("UnknownIssuer") || e.contains("transport"), "{e}");
    // A certificate of another CA: refused by the server.
    let e = connect(&url, Some(tls(&d.join("ca.pem"), Some((o, "panda-1")))), None).await.unwrap_err();
    assert!(!e.is_empty());
    // Plaintext against TLS.
    let e =
        connect(&format!("http://{}", server.handle().grpc_addr), None, Some(admin_token)).await.unwrap_err();
    assert!(!e.is_empty());
    // A certificate without a token or with an unknown name: no identity.
    let e = connect(&url, Some(tls(&d.join("ca.pem"), None)), None).await.unwrap_err();
    assert!(e.contains("no credentials"), "{e}");

    // Everyone else went on.
    for _ in 0..3 {
        within("segment", running.next()).await.unwrap().unwrap();
    }
    within("list", admin.list("panda-1")).await.unwrap();
    drop(running);
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread")]
async fn exposure_without_protection_is_refused_unless_insecure_and_then_repeated() {
    let dir = tempfile::tempdir().unwrap();
    let mut config = dmp_tests::config(dir.path());
    config.zenoh.disabled = true;
    config.grpc_addr = "0.0.0.0:0".parse().unwrap();
    let e = within("start", dmp_server::server::start(config.clone())).await.unwrap_err().to_string();
    assert!(e.contains("refusing to start") && e.contains("--insecure"), "{e}");
    config.security.insecure = true;
    let handle = within("start", dmp_server::server::start(config)).await.unwrap();
    let client =
        within("connect", DmpClient::connect(format!("http://127.0.0.1:{}", handle.grpc_addr.port())))
            .await
            .unwrap();
    let info = within("info", client.info()).await.unwrap();
    assert!(info.insecure && !info.access_control, "{info:?}");
    assert!(info.insecure_reasons.iter().any(|r| r.contains("gRPC listens on 0.0.0.0")), "{info:?}");
    assert_eq!(info.identity, "anonymous");
    within("shutdown", handle.shutdown()).await.unwrap();
}

/// What the Kubernetes probes do (`grpc_health_probe -tls -tls-ca-cert=ca.pem`, deploy/k8s/dmp-server.yaml): gRPC
/// health over TLS with the CA alone, no client certificate and no token, for the server and for the scene.
#[tokio::test(flavor = "multi_thread")]
async fn a_probe_with_the_ca_alone_reads_the_health_over_tls() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    set(d);
    let server = TestServer::start_with(|c| dmp_tests::secure(c, d)).await;
    let url = format!("https://{}", server.handle().grpc_addr);
    let options = ConnectOptions { tls: Some(tls(&d.join("ca.pem"), None)), ..Default::default() };
    let probe = within("connect", DmpClient::connect_with(&url, &options)).await.unwrap();
    for service in ["", dmp_proto::v1::scene_service_server::SERVICE_NAME] {
        assert_eq!(within("health", probe.health(service)).await.unwrap(), "SERVING", "{service:?}");
    }
    let e = within("info", probe.info()).await.unwrap_err();
    assert_eq!(e.code(), Some(tonic::Code::Unauthenticated), "nothing but health answers: {e}");
    server.stop().await;
}
