//! The resumable session's timeline, its pose resumption and which failures it resumes from.

use super::*;
use crate::Setpoints;

/// A 1-D segment of `n` points from `t0` (run time), `dt` 1 ms, moving at 1 m/s from `x0`.
fn segment(sequence: u64, t0: f64, x0: f64, n: usize) -> v1::Segment {
    let dt = 1e-3;
    v1::Segment {
        sequence,
        start_time: t0,
        dt,
        dim: 1,
        positions: (0..n).map(|i| x0 + i as f64 * dt).collect(),
        velocities: vec![1.0; n],
        accelerations: vec![0.0; n],
        ..Default::default()
    }
}

#[test]
fn a_resumed_session_goes_on_from_the_last_setpoint_on_one_timeline() {
    let mut timeline = Timeline::default();
    let mut setpoints = Setpoints::new();
    for (k, t0) in [0.0, 0.01].into_iter().enumerate() {
        setpoints.push(&timeline.shift(segment(k as u64, t0, t0, 10))).unwrap();
    }
    let last = timeline.last.clone().unwrap();
    assert!((last.t - 0.019).abs() < 1e-12 && (last.position[0] - 0.019).abs() < 1e-12);
    assert_eq!(last.velocity, [1.0]);
    // The new server's run starts at 0 from that setpoint (its first point is the same state).
    timeline.resumed();
    let first = timeline.shift(segment(0, 0.0, last.position[0], 10));
    assert_eq!(first.sequence, 2, "sequence numbers go on");
    assert!((first.start_time - last.t).abs() < 1e-12, "run times go on from the setpoint resumed from");
    setpoints.push(&first).unwrap();
    // One timeline, one point per millisecond, no jump: the first new point superseded the last old one.
    let t = setpoints.trajectory().unwrap();
    assert_eq!(t.t.len(), 29);
    for k in 1..t.t.len() {
        assert!((t.t[k] - t.t[k - 1] - 1e-3).abs() < 1e-9 && (t.x[k] - t.x[k - 1] - 1e-3).abs() < 1e-9);
    }
    // A second resumption before any new point keeps the same origin.
    let mut early = Timeline::default();
    early.resumed();
    assert_eq!(early.shift(segment(0, 0.0, 0.0, 1)).start_time, 0.0);
}

#[test]
fn a_pose_run_resumes_from_its_last_orientation() {
    let mut timeline = Timeline::default();
    let mut seg = segment(0, 0.0, 0.0, 2);
    seg.orientations = vec![0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.6, 0.8];
    timeline.shift(seg);
    assert_eq!(timeline.last.unwrap().orientation, Some(vec![0.0, 0.0, 0.6, 0.8]));
    timeline = Timeline::default();
    timeline.shift(segment(0, 0.0, 0.0, 2));
    assert_eq!(timeline.last.unwrap().orientation, None, "a position run");
}

#[test]
fn only_a_server_or_route_gone_is_resumed_from() {
    let status = |code| ClientError::Status { code, message: String::new() };
    assert!(resumable(&status(tonic::Code::Unavailable)) && resumable(&status(tonic::Code::Unknown)));
    assert!(resumable(&ClientError::Closed("the session".into())));
    for code in [
        tonic::Code::FailedPrecondition,
        tonic::Code::Internal,
        tonic::Code::Aborted,
        tonic::Code::InvalidArgument,
        tonic::Code::ResourceExhausted,
    ] {
        assert!(!resumable(&status(code)), "{code:?}: the server's word, not its absence");
    }
}

#[test]
fn only_failures_of_the_server_or_the_route_are_retried() {
    let status = |code| ClientError::Status { code, message: String::new() };
    assert!(retryable(&status(tonic::Code::Unavailable)));
    assert!(retryable(&status(tonic::Code::Unknown)));
    assert!(retryable(&ClientError::argument("cell", "no server answered")));
    assert!(!retryable(&status(tonic::Code::InvalidArgument)));
    assert!(!retryable(&status(tonic::Code::PermissionDenied)));
    assert!(!retryable(&status(tonic::Code::Aborted)), "taken over by another stream: the caller's to see");
    assert!(!retryable(&ClientError::argument("motion.goal", "bad")));
}
