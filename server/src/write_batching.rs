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
//!   [`write_now`] before it is sent: every connection writes at its next flush;
//! - more than [`HIGH_WATER`] bytes held are written at once, and at most [`MAX_HELD`] are held (then the writer
//!   waits for the socket, as it would without the batching).

use std::io::{self, IoSlice};
use std::pin::Pin;
use std::sync::atomic::{AtomicU64, Ordering};
use std::task::{Context, Poll, ready};
use std::time::Duration;

use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};
use tokio::time::{Instant, Sleep};

/// Longest a flushed write is held after the connection's previous write.
pub const HOLD: Duration = Duration::from_millis(3);

/// Held bytes above which a flush writes at once.
pub const HIGH_WATER: usize = 64 * 1024;

/// Most bytes held: a write beyond waits for the socket.
pub const MAX_HELD: usize = 256 * 1024;

/// Bumped by [`write_now`]: a connection that has not seen the current value writes at its next flush.
static URGENT: AtomicU64 = AtomicU64::new(0);

/// Something that cannot wait is about to be sent: every connection writes what it holds at its next flush.
pub fn write_now() {
    URGENT.fetch_add(1, Ordering::Release);
}

/// A connection whose flushes are batched (see the module).
#[derive(Debug)]
pub struct BatchedWrites<T> {
    io: T,
    held: Vec<u8>,
    /// Bytes of `held` already written.
    written: usize,
    /// When the connection last wrote to the socket.
    last_write: Option<Instant>,
    /// The [`URGENT`] value the last write saw.
    urgent_seen: u64,
    /// Wakes the connection to write what it holds.
    timer: Option<Pin<Box<Sleep>>>,
    /// Where [`write_now`] is counted.
    urgent: &'static AtomicU64,
}

impl<T> BatchedWrites<T> {
    /// Wraps a connection.
    pub fn new(io: T) -> Self {
        Self::with_urgency(io, &URGENT)
    }

    /// Wraps a connection that writes at once when `urgent` changes (instead of on [`write_now`]).
    fn with_urgency(io: T, urgent: &'static AtomicU64) -> Self {
        Self {
            io,
            held: Vec::new(),
            written: 0,
            last_write: None,
            urgent_seen: urgent.load(Ordering::Acquire),
            timer: None,
            urgent,
        }
    }

    /// The wrapped connection.
    pub fn get_ref(&self) -> &T {
        &self.io
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
        self.written = 0;
        self.last_write = Some(Instant::now());
        self.timer = None;
        Poll::Ready(Ok(()))
    }

    /// Whether a flush must write now.
    fn due(&mut self, cx: &mut Context<'_>) -> bool {
        let urgent = self.urgent.load(Ordering::Acquire);
        if urgent != self.urgent_seen {
            self.urgent_seen = urgent;
            return true;
        }
        if self.held.len() - self.written >= HIGH_WATER {
            return true;
        }
        let Some(last) = self.last_write else { return true };
        let at = last + HOLD;
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
    type ConnectInfo = T::ConnectInfo;

    fn connect_info(&self) -> Self::ConnectInfo {
        self.io.connect_info()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tokio::io::{AsyncReadExt, AsyncWriteExt};

    /// A connection with its own urgency counter (other tests' urgent writes do not reach it) and its reader.
    async fn pair(
        urgent: &'static AtomicU64,
    ) -> (BatchedWrites<tokio::net::TcpStream>, tokio::net::TcpStream) {
        let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
        let addr = listener.local_addr().unwrap();
        let (a, b) = tokio::join!(tokio::net::TcpStream::connect(addr), listener.accept());
        (BatchedWrites::with_urgency(a.unwrap(), urgent), b.unwrap().0)
    }

    async fn read_now(r: &mut tokio::net::TcpStream) -> Vec<u8> {
        let mut buf = vec![0u8; 1 << 20];
        match tokio::time::timeout(Duration::from_millis(200), r.read(&mut buf)).await {
            Ok(Ok(n)) => buf[..n].to_vec(),
            _ => Vec::new(),
        }
    }

    #[tokio::test]
    async fn an_idle_connection_writes_at_once_a_busy_one_holds_until_its_timer_or_an_urgent_write() {
        static URGENT_HERE: AtomicU64 = AtomicU64::new(0);
        let (mut w, mut r) = pair(&URGENT_HERE).await;
        // Idle: written at the first flush.
        w.write_all(b"first").await.unwrap();
        w.flush().await.unwrap();
        assert_eq!(read_now(&mut r).await, b"first");
        // Just written: held, then written by the timer (the flush future is polled by the connection's task
        // when the timer wakes it; here, by flushing again once the hold has passed).
        w.write_all(b"second").await.unwrap();
        w.flush().await.unwrap();
        let mut buf = [0u8; 64];
        let early = tokio::time::timeout(Duration::from_micros(500), r.read(&mut buf)).await;
        assert!(early.is_err(), "written before the hold: {early:?}");
        tokio::time::sleep(HOLD).await;
        w.flush().await.unwrap();
        assert_eq!(read_now(&mut r).await, b"second");
        // Urgent: written at the next flush, whatever the hold.
        w.write_all(b"third").await.unwrap();
        URGENT_HERE.fetch_add(1, Ordering::Release);
        w.flush().await.unwrap();
        assert_eq!(read_now(&mut r).await, b"third");
        // A large write goes out at once; shutting down writes what is held.
        let big = vec![7u8; HIGH_WATER + 1];
        w.write_all(&big).await.unwrap();
        w.flush().await.unwrap();
        let mut got = Vec::new();
        while got.len() < big.len() {
            let chunk = read_now(&mut r).await;
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
        static URGENT_HERE: AtomicU64 = AtomicU64::new(0);
        let (mut w, mut r) = pair(&URGENT_HERE).await;
        w.write_all(b"a").await.unwrap();
        w.flush().await.unwrap();
        assert_eq!(read_now(&mut r).await, b"a");
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
        let got = tokio::time::timeout(Duration::from_secs(2), writer).await.expect("woken").unwrap();
        assert!(got >= 2, "held at the first flush, written when the timer woke the task ({got} polls)");
        assert_eq!(read_now(&mut r).await, b"held");
    }
}
