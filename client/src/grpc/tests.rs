//! The client without a server: connection failures and bad addresses. Its calls against the real server are
//! end-to-end tests (`tests/tests/client/grpc.rs`).

use super::*;

/// Bound on every await (a hung call fails the test instead of hanging it).
const T: Duration = Duration::from_secs(30);

#[tokio::test(flavor = "multi_thread")]
async fn connection_failures_and_bad_addresses() {
    let e = tokio::time::timeout(T, DmpClient::connect("http://127.0.0.1:1"))
        .await
        .expect("connect")
        .unwrap_err();
    assert!(matches!(e, ClientError::Connect { .. }) && !e.is_bad_input(), "{e}");
    assert!(e.to_string().contains("http://127.0.0.1:1"), "{e}");
    let e =
        tokio::time::timeout(T, DmpClient::connect("http://not a host")).await.expect("connect").unwrap_err();
    assert!(e.is_bad_input(), "{e}");
}
