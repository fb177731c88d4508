//! Rejected session commands on tokio's paused clock: the warning reaches the robot within a refill, the run goes
//! on as before, and a rejection sends nothing ahead of the pacing.

use std::sync::Arc;

use dmp_proto::v1;
use dmp_proto::v1::warning::Kind;
use tokio::sync::mpsc;

use super::context::RunContext;
use super::control::Control;
use super::pacing::MAX_REFILL;
use super::stream::run_stream;
use crate::clock::Clock;

fn warning(field: &str) -> v1::Warning {
    v1::Warning {
        kind: Kind::CommandRejected as i32,
        field: field.into(),
        reason: "test".into(),
        obstacle_id: String::new(),
    }
}

#[tokio::test(start_paused = true)]
async fn a_rejection_reaches_the_robot_within_a_refill_and_the_run_goes_on() {
    let clock = Clock::following_tokio();
    let app = Arc::new(RunContext::for_tests(clock));
    let cell = super::tests::cell();
    let cfg = super::tests::realtime_10ms();
    let run = super::tests::reach(&cfg);
    let (tx, mut rx) = mpsc::channel(64);
    let (ctl_tx, ctl_rx) = mpsc::channel(8);
    let producer =
        tokio::spawn(run_stream(app.clone(), run, cell, cfg, tx, Some(ctl_rx), Default::default()));

    // (field, sent at) of each rejection not yet received.
    let mut pending: Vec<(String, f64)> = Vec::new();
    let mut received = Vec::new();
    let mut last: Option<v1::Segment> = None;
    let mut mid_run_sent = false;
    let mut after_the_end_sent = false;
    while let Some(batch) = rx.recv().await {
        let seg = batch.unwrap().remove(0);
        let now = clock.now_unix_s();
        assert!(seg.start_unix_s - now <= 0.05 + 0.06 + 0.011, "too far ahead: {}", seg.start_unix_s - now);
        for w in &seg.warnings {
            let i = pending.iter().position(|(f, _)| *f == w.field).expect("a warning sent once");
            let (field, sent_at) = pending.remove(i);
            assert!(
                now - sent_at <= MAX_REFILL.as_secs_f64() + 1e-6,
                "{field} reached the robot {} s after it was rejected",
                now - sent_at
            );
            received.push(field);
        }
        if seg.start_time >= 0.3 && !mid_run_sent {
            mid_run_sent = true;
            // A rejection from the session's reader, and a goal the engine refuses (of the wrong length).
            ctl_tx.send(Control::Rejected(warning("set_tau.tau"))).await.unwrap();
            pending.push(("set_tau.tau".into(), now));
            ctl_tx.send(Control::SetGoal(vec![0.5], None)).await.unwrap();
            pending.push(("set_goal.goal".into(), now));
        }
        if seg.status == v1::SegmentStatus::GoalReached as i32 && !after_the_end_sent {
            // The last segment is sent, the stream waits for its last point: a rejection still gets through.
            after_the_end_sent = true;
            ctl_tx.send(Control::Rejected(warning("message"))).await.unwrap();
            pending.push(("message".into(), now));
        }
        last = Some(seg);
    }
    producer.await.unwrap();
    assert!(pending.is_empty(), "never received: {pending:?}");
    assert_eq!(received, ["set_tau.tau", "set_goal.goal", "message"]);
    let last = last.unwrap();
    assert_eq!(last.status, v1::SegmentStatus::GoalReached as i32);
    let end = &last.positions[last.positions.len() - 2..];
    assert!((end[0] - 1.0).abs() < 1e-3 && end[1].abs() < 1e-3, "the run changed: ended at {end:?}");
}
