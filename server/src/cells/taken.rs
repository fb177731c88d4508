//! The cells this server serves for a dead server of the plant (fail-over, [`crate::plant::failover`]): whose cells they
//! are, and the signal that ends their streams when they go back.

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};

use tokio_util::sync::{CancellationToken, WaitForCancellationFutureOwned};

use crate::error::ServerError;

/// A cell served for another server.
#[derive(Debug, Clone)]
struct Taken {
    /// Cancelled when the cell goes back (its streams end).
    gone: CancellationToken,
    /// Where it went: set before `gone` is cancelled.
    to: Arc<Mutex<String>>,
}

/// The cells taken over, by name. Cheap to clone; the lock is never held across an await.
#[derive(Debug, Clone, Default)]
pub(crate) struct TakenCells {
    cells: Arc<Mutex<BTreeMap<String, Taken>>>,
}

impl TakenCells {
    /// Starts serving `cell` for another server; false when it was taken already.
    pub(crate) fn take(&self, cell: &str) -> bool {
        let mut cells = self.lock();
        if cells.contains_key(cell) {
            return false;
        }
        let taken = Taken { gone: CancellationToken::new(), to: Arc::default() };
        cells.insert(cell.to_owned(), taken);
        true
    }

    /// Stops serving `cell`, which went to `to` (a server, named in the status that ends its streams); false
    /// when it was not taken.
    pub(crate) fn give_back(&self, cell: &str, to: &str) -> bool {
        let Some(taken) = self.lock().remove(cell) else { return false };
        *taken.to.lock().unwrap_or_else(|p| p.into_inner()) = to.to_owned();
        taken.gone.cancel();
        true
    }

    /// Whether `cell` is taken.
    pub(crate) fn contains(&self, cell: &str) -> bool {
        self.lock().contains_key(cell)
    }

    /// The cells taken, in order.
    #[cfg(test)]
    pub(crate) fn names(&self) -> Vec<String> {
        self.lock().keys().cloned().collect()
    }

    /// For a stream of `cell`: None when the cell is not a taken one (it never goes); else what completes when it
    /// goes back, with where it went.
    pub(crate) fn until_given_back(&self, cell: &str) -> Option<GivenBack> {
        self.lock().get(cell).map(|t| GivenBack { gone: t.gone.clone().cancelled_owned(), to: t.to.clone() })
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, BTreeMap<String, Taken>> {
        self.cells.lock().unwrap_or_else(|p| p.into_inner())
    }
}

/// Completes when a taken cell goes back ([`TakenCells::until_given_back`]).
#[derive(Debug)]
pub(crate) struct GivenBack {
    gone: WaitForCancellationFutureOwned,
    to: Arc<Mutex<String>>,
}

impl GivenBack {
    /// Waits until the cell goes back, and names the server it went to.
    pub(crate) async fn wait(self) -> String {
        self.gone.await;
        self.to.lock().unwrap_or_else(|p| p.into_inner()).clone()
    }

    /// Waits until `cell` goes back: the error that ends its streams here (`UNAVAILABLE`, naming where to resume).
    pub(crate) async fn moved(self, cell: &str) -> ServerError {
        let to = self.wait().await;
        ServerError::Moved(format!(
            "cell `{cell}` moved to server {to} (this server served it while its own server was gone): resume there"
        ))
    }
}

/// [`GivenBack::moved`], or never for a cell that is not a taken one.
pub(crate) async fn moved(given_back: Option<GivenBack>, cell: &str) -> ServerError {
    match given_back {
        Some(g) => g.moved(cell).await,
        None => std::future::pending().await,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test]
    async fn a_taken_cell_ends_its_streams_when_it_goes_back_naming_where() {
        let t = TakenCells::default();
        assert!(t.until_given_back("a").is_none(), "a cell of its own never goes");
        assert!(t.take("a") && !t.take("a"));
        assert!(t.contains("a") && t.names() == ["a"]);
        let back = tokio::spawn(t.until_given_back("a").unwrap().wait());
        assert!(!t.give_back("b", "s9"));
        assert!(t.give_back("a", "s1 at http://h:1"));
        let to = tokio::time::timeout(std::time::Duration::from_secs(10), back).await.unwrap().unwrap();
        assert_eq!(to, "s1 at http://h:1");
        assert!(!t.contains("a"));
    }
}
