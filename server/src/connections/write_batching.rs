//! Write batching on the gRPC connections: many streams' segments in one write.
//!
//! HTTP/2 writes a connection's pending frames whenever its task runs, and it runs after every stream that sent
//! something: a thousand real-time streams, each waking every refill, cost a `writev` (and a wake-up of the
//! reader) per stream and refill, the largest single item of the server's profile after the engine. A
//! [`BatchedWrites`] connection holds what HTTP/2 flushes for at most [`HOLD`] after its previous write, and then
//! writes everything at once:
//!
//! - a connection that has not written for [`HOLD`] writes at once (an idle client's answer is never held);
//! - a real-time segment is sent far ahead of its points (the stream's lookahead), so holding it costs nothing;
//! - what cannot wait (a segment that supersedes points already sent, after a scene change or a command) calls
//!   [`Urgency::write_now`] on its connection's [`Urgency`] (which a request finds in its extensions, in
//!   [`BatchedConnectInfo`]) before it is sent: for the next [`HOLD`] that connection writes at every flush, long
//!   enough for the segment to reach it through the stream's channel and HTTP/2, whatever flushes come first;
//! - more than [`HIGH_WATER`] bytes held are written at once, and at most [`MAX_HELD`] are held (then the writer
//!   waits for the socket, as it would without the batching).
//!
//! The wrapper also closes an idle connection: one with no open stream and no request for its idle timeout (see
//! [`ConnectionActivity`]); its reads end with an error, and HTTP/2 drops the connection.

use std::io::{self, IoSlice};
use std::pin::Pin;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::task::{Context, Poll, ready};
use std::time::Duration;

use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};
use tokio::time::{Instant, Sleep};

use crate::connections::{ConnectionActivity, nanos_now};

/// Longest a flushed write is held after the connection's previous write.
pub(crate) const HOLD: Duration = Duration::from_millis(3);

/// Held bytes above which a flush writes at once.
pub(crate) const HIGH_WATER: usize = 64 * 1024;

/// Most bytes held: a write beyond waits for the socket.
pub(crate) const MAX_HELD: usize = 256 * 1024;

/// A connection's urgency: while it lasts, every flush of the connection writes at once.
#[derive(Debug, Clone, Default)]
pub struct Urgency(Arc<AtomicU64>);

impl Urgency {
    /// Something that cannot wait is about to be sent on the connection: for the next [`HOLD`] its flushes write
    /// at once.
    pub(crate) fn write_now(&self) {
        let until = nanos_now().saturating_add(HOLD.as_nanos() as u64);
        self.0.fetch_max(until, Ordering::AcqRel);
    }

    fn active(&self) -> bool {
        nanos_now() < self.0.load(Ordering::Acquire)
    }
}

/// What a request on a [`BatchedWrites`] connection knows of it (tonic puts it in the request's extensions): the
/// wrapped connection's own information and the connection's [`Urgency`].
#[derive(Debug, Clone)]
pub(crate) struct BatchedConnectInfo<C> {
    /// The wrapped connection's information.
    pub inner: C,
    /// The connection's urgency.
    pub urgency: Urgency,
    /// The connection's streams and requests.
    pub activity: Arc<ConnectionActivity>,
}

/// A connection whose flushes are batched (see the module).
#[derive(Debug)]
pub(crate) struct BatchedWrites<T> {
    io: T,
    held: Vec<u8>,
    /// Bytes of `held` already written.
    written: usize,
    /// When the connection last wrote to the socket.
    last_write: Option<Instant>,
    /// Wakes the connection to write what it holds.
    timer: Option<Pin<Box<Sleep>>>,
    urgency: Urgency,
    /// Longest a flushed write is held ([`HOLD`]).
    hold: Duration,
    activity: Arc<ConnectionActivity>,
    /// Closes the connection after this long without a stream or a request.
    idle_timeout: Option<Duration>,
    /// Wakes the connection to look whether it is idle.
    idle_timer: Option<Pin<Box<Sleep>>>,
}

impl<T> BatchedWrites<T> {
    /// Wraps a connection.
    pub(crate) fn new(io: T) -> Self {
        Self::with_hold(io, HOLD)
    }

    fn with_hold(io: T, hold: Duration) -> Self {
        Self {
            io,
            held: Vec::new(),
            written: 0,
            last_write: None,
            timer: None,
            urgency: Urgency::default(),
            hold,
            activity: Arc::default(),
            idle_timeout: None,
            idle_timer: None,
        }
    }

    /// Closes the connection once it has had no open stream and no request for `timeout` (None: never).
    pub(crate) fn with_idle_timeout(mut self, timeout: Option<Duration>) -> Self {
        self.idle_timeout = timeout.filter(|t| !t.is_zero());
        self
    }

    /// Whether the connection has been idle for its timeout; otherwise its timer is set to look again.
    fn poll_idle(&mut self, cx: &mut Context<'_>) -> bool {
        let Some(timeout) = self.idle_timeout else { return false };
        loop {
            let Some(remaining) = self.activity.idle_remaining(timeout) else { return true };
            let at = Instant::now() + remaining;
            let timer = self.idle_timer.get_or_insert_with(|| Box::pin(tokio::time::sleep_until(at)));
            if timer.as_mut().poll(cx).is_pending() {
                return false;
            }
            // The timer fired: the connection may have been active since; look again from now.
            timer.as_mut().reset(at);
            if timer.as_mut().poll(cx).is_pending() {
                return false;
            }
        }
    }

    /// The connection's urgency.
    #[cfg(test)]
    pub(crate) fn urgency(&self) -> &Urgency {
        &self.urgency
    }
}

impl<T: AsyncWrite + Unpin> BatchedWrites<T> {
    /// Writes everything held (Pending while the socket is full).
    fn poll_drain(&mut self, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        while self.written < self.held.len() {
            let n = ready!(Pin::new(&mut self.io).poll_write(cx, &self.held[self.written..]))?;
            if n == 0 {
                return Poll::Ready(Err(io::ErrorKind::WriteZero.into()));
            }
            self.written += n;
        }
        self.held.clear();
        if self.held.capacity() > HIGH_WATER {
            // After a burst: do not keep its buffer for the connection's life.
            self.held.shrink_to(HIGH_WATER);
        }
        self.written = 0;
        self.last_write = Some(Instant::now());
        self.timer = None;
        Poll::Ready(Ok(()))
    }

    /// Whether a flush must write now.
    fn due(&mut self, cx: &mut Context<'_>) -> bool {
        // A drain the socket cut short goes on; so do urgent writes and large ones.
        if self.written > 0 || self.urgency.active() || self.held.len() >= HIGH_WATER {
            return true;
        }
        let Some(last) = self.last_write else { return true };
        let at = last + self.hold;
        if Instant::now() >= at {
            return true;
        }
        let timer = self.timer.get_or_insert_with(|| Box::pin(tokio::time::sleep_until(at)));
        timer.as_mut().poll(cx).is_ready()
    }

    fn hold(&mut self, cx: &mut Context<'_>, bufs: &[IoSlice<'_>]) -> Poll<io::Result<usize>> {
        let len: usize = bufs.iter().map(|b| b.len()).sum();
        if self.held.len() - self.written + len > MAX_HELD {
            ready!(self.poll_drain(cx))?;
            if len > MAX_HELD {
                return Pin::new(&mut self.io).poll_write_vectored(cx, bufs);
            }
        }
        for b in bufs {
            self.held.extend_from_slice(b);
        }
        Poll::Ready(Ok(len))
    }
}

impl<T: AsyncRead + Unpin> AsyncRead for BatchedWrites<T> {
    fn poll_read(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &mut ReadBuf<'_>,
    ) -> Poll<io::Result<()>> {
        if self.poll_idle(cx) {
            return Poll::Ready(Err(io::Error::new(
                io::ErrorKind::TimedOut,
                "closed: no stream and no request for the idle timeout",
            )));
        }
        Pin::new(&mut self.io).poll_read(cx, buf)
    }
}

impl<T: AsyncWrite + Unpin> AsyncWrite for BatchedWrites<T> {
    fn poll_write(mut self: Pin<&mut Self>, cx: &mut Context<'_>, buf: &[u8]) -> Poll<io::Result<usize>> {
        self.hold(cx, &[IoSlice::new(buf)])
    }

    fn poll_write_vectored(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        bufs: &[IoSlice<'_>],
    ) -> Poll<io::Result<usize>> {
        self.hold(cx, bufs)
    }

    fn is_write_vectored(&self) -> bool {
        true
    }

    fn poll_flush(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        let this = &mut *self;
        if this.written < this.held.len() {
            if !this.due(cx) {
                // Held: the timer wakes the connection's task, whose next flush writes.
                return Poll::Ready(Ok(()));
            }
            ready!(this.poll_drain(cx))?;
        }
        Pin::new(&mut this.io).poll_flush(cx)
    }

    fn poll_shutdown(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        ready!(self.poll_drain(cx))?;
        Pin::new(&mut self.io).poll_shutdown(cx)
    }
}

impl<T: tonic::transport::server::Connected> tonic::transport::server::Connected for BatchedWrites<T> {
    type ConnectInfo = BatchedConnectInfo<T::ConnectInfo>;

    fn connect_info(&self) -> Self::ConnectInfo {
        BatchedConnectInfo {
            inner: self.io.connect_info(),
            urgency: self.urgency.clone(),
            activity: self.activity.clone(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tokio::io::{AsyncReadExt, AsyncWriteExt};

    /// A long hold, so that a slow machine does not write before it by accident.
    const TEST_HOLD: Duration = Duration::from_millis(400);

    /// A connection holding for [`TEST_HOLD`], and its reader.
    async fn pair() -> (BatchedWrites<tokio::net::TcpStream>, tokio::net::TcpStream) {
        let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
        let addr = listener.local_addr().unwrap();
        let (a, b) = tokio::join!(tokio::net::TcpStream::connect(addr), listener.accept());
        (BatchedWrites::with_hold(a.unwrap(), TEST_HOLD), b.unwrap().0)
    }

    async fn read_within(r: &mut tokio::net::TcpStream, wait: Duration) -> Vec<u8> {
        let mut buf = vec![0u8; 1 << 20];
        match tokio::time::timeout(wait, r.read(&mut buf)).await {
            Ok(Ok(n)) => buf[..n].to_vec(),
            _ => Vec::new(),
        }
    }

    #[tokio::test]
    async fn an_idle_connection_writes_at_once_a_busy_one_holds_until_its_timer_or_an_urgent_write() {
        let (mut w, mut r) = pair().await;
        let long = Duration::from_secs(5);
        // Idle: written at the first flush.
        w.write_all(b"first").await.unwrap();
        w.flush().await.unwrap();
        assert_eq!(read_within(&mut r, long).await, b"first");
        // Just written: held (nothing arrives for a while), then written by a flush once the hold has passed.
        w.write_all(b"second").await.unwrap();
        w.flush().await.unwrap();
        assert!(read_within(&mut r, TEST_HOLD / 8).await.is_empty(), "written before the hold");
        tokio::time::sleep(TEST_HOLD).await;
        w.flush().await.unwrap();
        assert_eq!(read_within(&mut r, long).await, b"second");
        // Urgent: written at the next flush, whatever the hold, and so is the next one within the window.
        w.write_all(b"third").await.unwrap();
        let urgency = w.urgency().clone();
        urgency.write_now();
        w.flush().await.unwrap();
        assert_eq!(read_within(&mut r, long).await, b"third");
        // A large write goes out at once; shutting down writes what is held.
        let big = vec![7u8; HIGH_WATER + 1];
        w.write_all(&big).await.unwrap();
        w.flush().await.unwrap();
        let mut got = Vec::new();
        while got.len() < big.len() {
            let chunk = read_within(&mut r, long).await;
            assert!(!chunk.is_empty(), "only {} of {} bytes", got.len(), big.len());
            got.extend(chunk);
        }
        assert_eq!(got, big);
        w.write_all(b"last").await.unwrap();
        w.shutdown().await.unwrap();
        let mut rest = Vec::new();
        r.read_to_end(&mut rest).await.unwrap();
        assert_eq!(rest, b"last");
    }

    #[tokio::test]
    async fn the_timer_wakes_a_task_whose_flush_held_data() {
        let (mut w, mut r) = pair().await;
        w.write_all(b"a").await.unwrap();
        w.flush().await.unwrap();
        assert_eq!(read_within(&mut r, Duration::from_secs(5)).await, b"a");
        // A task that flushes on every wake-up, as HTTP/2's connection task does, and otherwise waits.
        w.write_all(b"held").await.unwrap();
        let writer = tokio::spawn(async move {
            let mut polls = 0;
            std::future::poll_fn(|cx| {
                polls += 1;
                let _ = Pin::new(&mut w).poll_flush(cx);
                if w.held.is_empty() { Poll::Ready(polls) } else { Poll::Pending }
            })
            .await
        });
        let got = tokio::time::timeout(Duration::from_secs(5), writer).await.expect("woken").unwrap();
        assert!(got >= 2, "held at the first flush, written when the timer woke the task ({got} polls)");
        assert_eq!(read_within(&mut r, Duration::from_secs(5)).await, b"held");
    }

    #[tokio::test]
    async fn a_request_finds_its_connections_urgency() {
        use tonic::transport::server::Connected;
        let (w, _r) = pair().await;
        let info = w.connect_info();
        assert!(info.inner.remote_addr().is_some());
        info.urgency.write_now();
        assert!(w.urgency().active(), "the request's urgency is the connection's");
    }

    #[test]
    fn an_urgency_lasts_one_hold() {
        let u = Urgency::default();
        assert!(!u.active());
        u.write_now();
        assert!(u.active());
        let clone = u.clone();
        assert!(clone.active(), "shared by the connection and its requests");
        std::thread::sleep(HOLD + Duration::from_millis(1));
        assert!(!u.active(), "over after one hold");
    }
}
