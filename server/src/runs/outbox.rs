//! How the streams hand what they send to the ROS 2 publishers without waiting for them: a bounded channel that is
//! only ever `try_send`-ed from a stream. When it is full (Zenoh slower than the robots), the segments are dropped
//! for ROS 2 and counted (`Ros2Counters::trajectories_dropped`); the robot's own stream never waits. The
//! handle is empty without `ros2.domain`: offering then costs one branch.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use dmp_proto::v1;
use tokio::sync::mpsc;

/// How many hand-overs wait for the publisher at most.
pub(crate) const CAPACITY: usize = 256;

/// What a stream hands over.
#[derive(Debug)]
pub(crate) enum Event {
    /// Segments sent to robots of `cell` (one per member of a group run), when the robot got them.
    Sent {
        /// The cell.
        cell: String,
        /// The segments.
        segments: Vec<v1::Segment>,
        /// When they were sent (the stamp of a segment without wall time).
        sent_unix_s: f64,
    },
    /// The streams of `robots` of `cell` ended: their publishers and paths go.
    Ended {
        /// The cell.
        cell: String,
        /// The robots.
        robots: Vec<String>,
    },
}

/// The streams' side. Cheap to clone; empty (does nothing) without ROS 2.
#[derive(Debug, Clone, Default)]
pub(crate) struct Ros2Out(Option<Arc<Inner>>);

#[derive(Debug)]
struct Inner {
    tx: mpsc::Sender<Event>,
    /// Counts the segments dropped because the publisher was behind.
    dropped: Arc<AtomicU64>,
}

impl Ros2Out {
    /// A handle and the publisher's receiving end; segments dropped are counted in `dropped`.
    pub(crate) fn channel(dropped: Arc<AtomicU64>) -> (Self, mpsc::Receiver<Event>) {
        let (tx, rx) = mpsc::channel(CAPACITY);
        (Self(Some(Arc::new(Inner { tx, dropped }))), rx)
    }

    /// A copy of `batch` to offer once the robot has it; none without ROS 2.
    pub(crate) fn copy_of(&self, batch: &[v1::Segment]) -> Option<Vec<v1::Segment>> {
        self.0.as_ref().map(|_| batch.to_vec())
    }

    /// Hands `segments` (from [`Ros2Out::copy_of`]) of `cell` over, or drops and counts them if the publisher is
    /// behind. Never waits.
    pub(crate) fn offer(&self, cell: &str, segments: Option<Vec<v1::Segment>>, sent_unix_s: f64) {
        let (Some(inner), Some(segments)) = (&self.0, segments) else { return };
        let n = segments.len() as u64;
        let event = Event::Sent { cell: cell.to_owned(), segments, sent_unix_s };
        if inner.tx.try_send(event).is_err() {
            inner.dropped.fetch_add(n, Ordering::Relaxed);
        }
    }

    /// Hands over the end of the streams of `robots`: at once if there is room, else from a task of its own (it
    /// must not be lost, or the robots' paths would stay drawn; the stream that ends does not wait for it).
    pub(crate) fn ended(&self, cell: &str, robots: &[String]) {
        let Some(inner) = &self.0 else { return };
        let event = Event::Ended { cell: cell.to_owned(), robots: robots.to_vec() };
        if let Err(mpsc::error::TrySendError::Full(event)) = inner.tx.try_send(event) {
            let tx = inner.tx.clone();
            tokio::spawn(async move {
                // The publisher gone (shutdown) is the only error: nothing left to tell.
                let _ = tx.send(event).await;
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test]
    async fn a_full_channel_drops_and_counts_and_never_waits() {
        let dropped = Arc::new(AtomicU64::new(0));
        let (out, mut rx) = Ros2Out::channel(dropped.clone());
        let batch = vec![v1::Segment { robot_id: "a".into(), ..Default::default() }; 2];
        for _ in 0..CAPACITY + 3 {
            out.offer("c", out.copy_of(&batch), 1.0);
        }
        assert_eq!(dropped.load(Ordering::Relaxed), 6);
        out.ended("c", &["a".into()]);
        for _ in 0..CAPACITY {
            assert!(matches!(rx.recv().await, Some(Event::Sent { .. })));
        }
        // The end waited for room instead of being dropped.
        assert!(matches!(rx.recv().await, Some(Event::Ended { robots, .. }) if robots == ["a"]));
        assert!(Ros2Out::default().copy_of(&batch).is_none());
    }
}
