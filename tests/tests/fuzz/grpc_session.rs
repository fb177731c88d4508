//! MotionService's Session through the real handler: a start (fuzzed) then random commands (states, goals, taus,
//! pauses, resumes, stops, a second start, an empty message), a segment read after each, then the stream dropped.

use proptest::collection::vec;
use proptest::prelude::*;
use proptest::test_runner::TestCaseResult;
use tokio::sync::mpsc;
use tokio_stream::wrappers::ReceiverStream;
use tonic::transport::Channel;

use dmp_proto::v1;
use dmp_proto::v1::motion_service_client::MotionServiceClient;

use crate::fixture::{Fuzzed, bounded, check_segment, refused};
use crate::grpc_motion::{read, store_primitives};
use crate::requests::{execute_request, session_message};
use crate::runner::fuzz;

/// Runs one session: `start` first (unless None: a session that does not begin with a start), then `commands`.
pub async fn session(
    channel: &Channel,
    start: Option<v1::ExecuteRequest>,
    commands: Vec<v1::SessionRequest>,
) -> TestCaseResult {
    let mut c = MotionServiceClient::new(channel.clone());
    let what = format!("session {start:?} {commands:?}");
    let realtime = start.as_ref().is_some_and(|s| s.pacing == v1::Pacing::Realtime as i32);
    let (tx, rx) = mpsc::channel(commands.len() + 1);
    let first = start.map(|s| v1::SessionRequest { message: Some(v1::session_request::Message::Start(s)) });
    let mut messages = first.into_iter().chain(commands);
    let mut tx = Some(tx);
    match messages.next() {
        Some(m) => send(&tx, m).await?,
        // Nothing to send: the client closes its side at once.
        None => tx = None,
    }
    let mut stream = match bounded("session", c.session(ReceiverStream::new(rx))).await? {
        Ok(r) => r.into_inner(),
        Err(s) => return refused(&what, &s),
    };
    read(&what, &mut stream, 1, check_segment).await?;
    for m in messages {
        // The server may have ended the session (a stop, a refused command): then the send fails, which is fine.
        if send(&tx, m).await.is_err() {
            break;
        }
        if !realtime {
            read(&what, &mut stream, 1, check_segment).await?;
        }
    }
    Ok(())
}

async fn send(tx: &Option<mpsc::Sender<v1::SessionRequest>>, m: v1::SessionRequest) -> TestCaseResult {
    let tx = tx.as_ref().ok_or_else(|| TestCaseError::fail("closed"))?;
    tx.send(m).await.map_err(|_| TestCaseError::fail("the session's request stream is closed"))
}

#[test]
fn fuzz_grpc_session() {
    let server = Fuzzed::start();
    store_primitives(&server);
    let start = prop_oneof![1 => Just(None), 9 => execute_request().prop_map(Some)];
    let strategy = (start, vec(session_message(), 0..=6));
    fuzz("grpc_session", 120, 30, strategy, |(start, commands)| {
        server.case(session(&server.channel, start, commands))
    });
    server.stop();
}
