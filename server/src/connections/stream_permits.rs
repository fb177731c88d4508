//! Who may open a stream: two pools, one for the robots' executions (`limits.max_streams`) and one for scene
//! watches (`limits.max_watches`), so that watches can never take an execution's place; and bounds per connection
//! (`limits.max_streams_per_connection`) and per client (`limits.max_streams_per_client`, a client being its IP
//! address over all its connections). A [`StreamPermit`] holds its place in each until it is dropped.

use std::collections::HashMap;
use std::net::IpAddr;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

use tokio::sync::{OwnedSemaphorePermit, Semaphore};
use tonic::Request;
use tonic::transport::server::TcpConnectInfo;

use crate::config::RequestLimits;
use crate::connections::ConnectionActivity;
use crate::connections::write_batching::BatchedConnectInfo;
use crate::error::ServerError;

/// Streams open per client address.
type ClientCounts = Arc<Mutex<HashMap<IpAddr, usize>>>;

/// The pool a stream takes its permit from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum StreamKind {
    /// Execute, Session, ExecuteGroup.
    Execution,
    /// WatchScene.
    Watch,
}

/// Where a request came from.
#[derive(Debug, Clone, Default)]
pub(crate) struct Peer {
    /// The client's IP address (None for a transport without one).
    pub client: Option<IpAddr>,
    /// The connection's activity (None for a connection the server did not wrap).
    pub connection: Option<Arc<ConnectionActivity>>,
}

impl Peer {
    /// The peer of a request, from what the connection put in its extensions.
    pub(crate) fn of<T>(request: &Request<T>) -> Self {
        match request.extensions().get::<BatchedConnectInfo<TcpConnectInfo>>() {
            Some(info) => Peer {
                client: info.inner.remote_addr().map(|a| a.ip()),
                connection: Some(info.activity.clone()),
            },
            None => Peer::default(),
        }
    }
}

/// The server's stream permits.
#[derive(Debug)]
pub(crate) struct StreamPermits {
    executions: Arc<Semaphore>,
    watches: Arc<Semaphore>,
    per_client: ClientCounts,
    max_executions: usize,
    max_watches: usize,
    max_per_connection: usize,
    max_per_client: usize,
    /// Streams refused so far, by the limit that refused them (in the order of [`StreamPermits::refusals`]).
    refused: [AtomicU64; 4],
}

impl StreamPermits {
    /// The permits of `limits`.
    pub(crate) fn new(limits: &RequestLimits) -> Self {
        Self {
            executions: Arc::new(Semaphore::new(limits.max_streams)),
            watches: Arc::new(Semaphore::new(limits.max_watches)),
            per_client: Arc::default(),
            max_executions: limits.max_streams,
            max_watches: limits.max_watches,
            max_per_connection: limits.max_streams_per_connection,
            max_per_client: limits.max_streams_per_client,
            refused: Default::default(),
        }
    }

    /// Streams refused so far, by the setting of the limit that refused them.
    pub(crate) fn refusals(&self) -> [(&'static str, u64); 4] {
        let n = |i: usize| self.refused[i].load(Ordering::Relaxed);
        [
            ("limits.max_streams", n(0)),
            ("limits.max_watches", n(1)),
            ("limits.max_streams_per_client", n(2)),
            ("limits.max_streams_per_connection", n(3)),
        ]
    }

    fn refuse(&self, index: usize) {
        self.refused[index].fetch_add(1, Ordering::Relaxed);
    }

    /// Executions open now.
    pub(crate) fn open_executions(&self) -> usize {
        self.max_executions.saturating_sub(self.executions.available_permits())
    }

    /// Watches open now.
    pub(crate) fn open_watches(&self) -> usize {
        self.max_watches.saturating_sub(self.watches.available_permits())
    }

    /// Streams of `client` open now.
    #[cfg(test)]
    pub(crate) fn client_streams(&self, client: IpAddr) -> usize {
        self.per_client.lock().unwrap_or_else(|p| p.into_inner()).get(&client).copied().unwrap_or(0)
    }

    /// A permit for a stream of `kind` from `peer`, or ResourceExhausted naming the limit reached.
    pub(crate) fn acquire(&self, kind: StreamKind, peer: &Peer) -> Result<StreamPermit, ServerError> {
        let (pool, max, name, what, index) = match kind {
            StreamKind::Execution => (&self.executions, self.max_executions, "max_streams", "executions", 0),
            StreamKind::Watch => (&self.watches, self.max_watches, "max_watches", "scene watches", 1),
        };
        let pool = pool.clone().try_acquire_owned().map_err(|_| {
            self.refuse(index);
            ServerError::ResourceExhausted(format!(
                "{max} {what} are open (limits.{name} = {max}); retry later"
            ))
        })?;
        let mut permit = StreamPermit { _pool: pool, client: None, connection: None };
        if let Some(client) = peer.client {
            let mut counts = self.per_client.lock().unwrap_or_else(|p| p.into_inner());
            let n = counts.entry(client).or_insert(0);
            if *n >= self.max_per_client {
                self.refuse(2);
                return Err(ServerError::ResourceExhausted(format!(
                    "client {client} has {n} streams open (limits.max_streams_per_client = {}); close one or retry \
                     later",
                    self.max_per_client
                )));
            }
            *n += 1;
            permit.client = Some((self.per_client.clone(), client));
        }
        if let Some(connection) = &peer.connection {
            if !connection.try_open_stream(self.max_per_connection) {
                self.refuse(3);
                return Err(ServerError::ResourceExhausted(format!(
                    "this connection has {} streams open (limits.max_streams_per_connection = {}); open another \
                     connection or retry later",
                    connection.streams(),
                    self.max_per_connection
                )));
            }
            permit.connection = Some(connection.clone());
        }
        Ok(permit)
    }
}

/// A stream's place in its pool, its client's and its connection's counts; given back when dropped.
#[derive(Debug)]
pub(crate) struct StreamPermit {
    _pool: OwnedSemaphorePermit,
    client: Option<(ClientCounts, IpAddr)>,
    connection: Option<Arc<ConnectionActivity>>,
}

impl Drop for StreamPermit {
    fn drop(&mut self) {
        if let Some((counts, client)) = self.client.take() {
            let mut counts = counts.lock().unwrap_or_else(|p| p.into_inner());
            if let Some(n) = counts.get_mut(&client) {
                *n -= 1;
                if *n == 0 {
                    counts.remove(&client);
                }
            }
        }
        if let Some(c) = self.connection.take() {
            c.close_stream();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limits() -> RequestLimits {
        RequestLimits {
            max_streams: 3,
            max_watches: 2,
            max_streams_per_connection: 2,
            max_streams_per_client: 3,
            ..RequestLimits::default()
        }
    }

    #[test]
    fn watches_and_executions_have_their_own_pools() {
        let p = StreamPermits::new(&limits());
        let anon = Peer::default();
        let w: Vec<_> = (0..2).map(|_| p.acquire(StreamKind::Watch, &anon).unwrap()).collect();
        let e = p.acquire(StreamKind::Watch, &anon).unwrap_err().to_string();
        assert!(e.contains("limits.max_watches = 2"), "{e}");
        let x: Vec<_> = (0..3).map(|_| p.acquire(StreamKind::Execution, &anon).unwrap()).collect();
        assert_eq!((p.open_watches(), p.open_executions()), (2, 3));
        assert!(p.acquire(StreamKind::Execution, &anon).unwrap_err().to_string().contains("max_streams = 3"));
        drop((w, x));
        assert_eq!((p.open_watches(), p.open_executions()), (0, 0));
    }

    #[test]
    fn a_connection_and_a_client_are_bounded_and_counts_return() {
        let p = StreamPermits::new(&limits());
        let ip: IpAddr = "10.0.0.1".parse().unwrap();
        let c1 = Peer { client: Some(ip), connection: Some(Arc::default()) };
        let c2 = Peer { client: Some(ip), connection: Some(Arc::default()) };
        let a = p.acquire(StreamKind::Execution, &c1).unwrap();
        let _b = p.acquire(StreamKind::Watch, &c1).unwrap();
        let e = p.acquire(StreamKind::Execution, &c1).unwrap_err().to_string();
        assert!(e.contains("max_streams_per_connection = 2"), "{e}");
        assert_eq!(p.client_streams(ip), 2, "a refused stream is not counted");
        let _c = p.acquire(StreamKind::Execution, &c2).unwrap();
        let e = p.acquire(StreamKind::Execution, &c2).unwrap_err().to_string();
        assert!(e.contains("client 10.0.0.1") && e.contains("max_streams_per_client = 3"), "{e}");
        // Another client is still served.
        let other = Peer { client: Some("10.0.0.2".parse().unwrap()), connection: Some(Arc::default()) };
        let _d = p.acquire(StreamKind::Watch, &other).unwrap();
        drop(a);
        assert_eq!(p.client_streams(ip), 2);
        assert_eq!(c1.connection.as_ref().unwrap().streams(), 1);
        p.acquire(StreamKind::Execution, &c2).unwrap();
    }
}
