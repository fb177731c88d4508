//! The producer on tokio's paused clock, which the server's clock follows: real-time pacing, supersession and the
//! end of a run, deterministic and fast (no network: the stream's channel is read directly).

use std::sync::Arc;
use std::time::Duration;

use dmp::field::Agent;
use dmp::{Avoidance, Motion, Primitive, Stepping};
use dmp_proto::v1;
use tokio::sync::mpsc;

use super::context::RunContext;
use super::control::Control;
use super::pacing::StreamConfig;
use super::pacing::{FIRST_POINT_DELAY, ROLLBACK_MARGIN, history_len};
use super::served_run::{RunAvoidance, ServedRun};
use super::stream::run_stream;
use crate::clock::Clock;

/// A straight 2-D reach from the origin to (1, 0) in `tau` = 1 s, streamed in real time in 10 ms segments.
pub(super) fn reach(cfg: &StreamConfig) -> ServedRun {
    let p =
        Primitive::straight_line(50, 4.0, vec![1000.0; 2], None, 1.0, vec![0.0; 2], vec![1.0, 0.0]).unwrap();
    let member = Agent { id: "arm".into(), dims: vec![0, 1], footprint: None };
    let avoidance = RunAvoidance {
        obstacles: (Avoidance::NONE, 0),
        robots: (Avoidance::NONE, 0),
        extra: Vec::new(),
        ignore_scene: true,
    };
    ServedRun::new(p.clone(), Motion::of(&p), vec![(member, None)], avoidance, cfg.stepping, history_len(cfg))
        .unwrap()
}

/// A cell of its own (`c`), empty.
pub(super) fn cell() -> crate::cells::cell::Cell {
    let config = crate::config::Config::default();
    let memory = crate::memory::MemoryBudget::new(config.limits.max_server_bytes);
    crate::cells::Cells::with_limits("c", &config.limits, memory, Default::default())
        .and_then(|cells| cells.get("c"))
        .expect("cell c")
}

/// Real time, 1 kHz output in 10 ms segments, 50 ms ahead, at most 5 s.
pub(super) fn realtime_10ms() -> StreamConfig {
    StreamConfig {
        stepping: Stepping::rk4(1e-3),
        segment_points: 10,
        realtime: true,
        lookahead: Duration::from_millis(50),
        max_duration: 5.0,
        urgency: None,
    }
}

#[tokio::test(start_paused = true)]
async fn real_time_segments_arrive_before_they_are_due_and_a_goal_change_supersedes_from_now() {
    let clock = Clock::following_tokio();
    let app = Arc::new(RunContext::for_tests(clock));
    let cell = cell();
    let cfg = realtime_10ms();
    let run = reach(&cfg);
    let (tx, mut rx) = mpsc::channel(64);
    let (ctl_tx, ctl_rx) = mpsc::channel(8);
    let started = clock.now_unix_s();
    let producer =
        tokio::spawn(run_stream(app.clone(), run, cell, cfg, tx, Some(ctl_rx), Default::default()));

    let mut goal_sent_at = None;
    let mut superseding = None;
    let mut last_end = f64::NEG_INFINITY;
    let mut last: Option<v1::Segment> = None;
    while let Some(batch) = rx.recv().await {
        let seg = batch.unwrap().remove(0);
        let now = clock.now_unix_s();
        // On time: every segment is here before its first point is due, and no more than the lookahead and a
        // refill ahead of it.
        assert!(
            now <= seg.start_unix_s + 1e-6,
            "segment at t = {} arrived {} s late",
            seg.start_time,
            now - seg.start_unix_s
        );
        assert!(seg.start_unix_s - now <= 0.05 + 0.06 + 0.011, "too far ahead: {}", seg.start_unix_s - now);
        if seg.start_time < last_end - 1e-9 && superseding.is_none() {
            superseding = Some((now, seg.start_time));
        }
        if goal_sent_at.is_none() && seg.start_time >= 0.5 {
            goal_sent_at = Some(now);
            ctl_tx.send(Control::SetGoal(vec![0.5, 0.5], None)).await.unwrap();
        }
        last_end = seg.start_time + seg.dt * (seg.positions.len() / 2) as f64;
        last = Some(seg);
    }
    producer.await.unwrap();
    // The change superseded points already sent, from the robot's time then (plus the rollback margin).
    let (at, from) = superseding.expect("a segment superseded points already sent");
    let robot_time = at - (started + FIRST_POINT_DELAY.as_secs_f64());
    assert!(
        from >= robot_time && from <= robot_time + ROLLBACK_MARGIN.as_secs_f64() + 2e-3,
        "{from} vs {robot_time}"
    );
    // The run reached the new goal and the stream stayed open until its last point was due.
    let last = last.unwrap();
    assert_eq!(last.status, v1::SegmentStatus::GoalReached as i32);
    let end = &last.positions[last.positions.len() - 2..];
    assert!((end[0] - 0.5).abs() < 1e-3 && (end[1] - 0.5).abs() < 1e-3, "{end:?}");
    let last_due = last.start_unix_s + last.dt * (last.positions.len() / 2 - 1) as f64;
    // Unix seconds near 1.7e9 are spaced 2.4e-7 apart.
    assert!(
        clock.now_unix_s() >= last_due - 1e-6,
        "ended {} s before its last point was due",
        last_due - clock.now_unix_s()
    );
}
