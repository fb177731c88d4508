//! The robots executing now, by cell: one stream (Execute, Session or ExecuteGroup) per robot of a cell. A second
//! stream of the same robot is refused (`ALREADY_EXISTS`, naming the robot) unless it asks to take over: then the
//! first stream is told to end ([`Claim::taken_over`]) and the second starts once the first has let go.
//!
//! A stream holds a [`Claim`] for its robots from before its first segment until it ends, however it ends: the claim
//! lets go when it is dropped.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use tokio_util::sync::CancellationToken;

use crate::error::ServerError;

/// How long a stream that takes over waits for the stream it ends to let go of its robots.
pub(crate) const TAKE_OVER_WAIT: Duration = Duration::from_secs(5);

/// The registry of executing robots. Cheap to clone.
#[derive(Debug, Clone, Default)]
pub(crate) struct Executing {
    /// The lock is held only to look up, insert or remove, never across an await.
    inner: Arc<Mutex<Registry>>,
}

#[derive(Debug, Default)]
struct Registry {
    next_claim: u64,
    /// By (cell, robot id).
    robots: HashMap<(String, String), Holder>,
}

/// The stream holding a robot.
#[derive(Debug, Clone)]
struct Holder {
    claim: u64,
    /// Cancelled to ask the stream to end.
    take_over: CancellationToken,
    /// Cancelled when the stream has let go.
    released: CancellationToken,
}

/// A stream's hold on its robots; dropping it lets them go.
#[derive(Debug)]
pub(crate) struct Claim {
    executing: Executing,
    id: u64,
    keys: Vec<(String, String)>,
    take_over: CancellationToken,
    released: CancellationToken,
}

impl Executing {
    /// Claims `robots` of `cell` for one stream. A robot held by another stream: refused with `AlreadyExists`
    /// naming it, or with `take_over` that stream is told to end and this waits (at most [`TAKE_OVER_WAIT`]) until
    /// it has let go.
    pub(crate) async fn claim(
        &self,
        cell: &str,
        robots: &[&str],
        take_over: bool,
    ) -> Result<Claim, ServerError> {
        let mut keys: Vec<(String, String)> =
            robots.iter().map(|r| (cell.to_owned(), (*r).to_owned())).collect();
        keys.sort();
        keys.dedup();
        loop {
            let holders: Vec<(String, Holder)> = {
                let mut registry = self.inner.lock().unwrap_or_else(|p| p.into_inner());
                let held: Vec<(String, Holder)> = keys
                    .iter()
                    .filter_map(|k| registry.robots.get(k).map(|h| (k.1.clone(), h.clone())))
                    .collect();
                if held.is_empty() {
                    registry.next_claim += 1;
                    let holder = Holder {
                        claim: registry.next_claim,
                        take_over: CancellationToken::new(),
                        released: CancellationToken::new(),
                    };
                    for k in &keys {
                        registry.robots.insert(k.clone(), holder.clone());
                    }
                    return Ok(Claim {
                        executing: self.clone(),
                        id: holder.claim,
                        keys,
                        take_over: holder.take_over,
                        released: holder.released,
                    });
                }
                held
            };
            if !take_over {
                let robot = &holders[0].0;
                return Err(ServerError::AlreadyExists(format!(
                    "robot `{robot}` is executing in cell `{cell}` already (another stream); set `take_over` to end \
                     that stream and start this one"
                )));
            }
            for (robot, holder) in holders {
                holder.take_over.cancel();
                if tokio::time::timeout(TAKE_OVER_WAIT, holder.released.cancelled()).await.is_err() {
                    return Err(ServerError::FailedPrecondition(format!(
                        "robot `{robot}`: the stream taken over did not end within {TAKE_OVER_WAIT:?}; retry"
                    )));
                }
            }
        }
    }

    /// How many robots are held now (in every cell).
    #[cfg(test)]
    pub(crate) fn len(&self) -> usize {
        self.inner.lock().unwrap_or_else(|p| p.into_inner()).robots.len()
    }

    /// True when no robot is held.
    #[cfg(test)]
    pub(crate) fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

impl Claim {
    /// Completes when another stream takes the robots over: the stream holding this claim must end (and drop it).
    pub(crate) fn taken_over(&self) -> tokio_util::sync::WaitForCancellationFutureOwned {
        self.take_over.clone().cancelled_owned()
    }
}

impl Drop for Claim {
    fn drop(&mut self) {
        {
            let mut registry = self.executing.inner.lock().unwrap_or_else(|p| p.into_inner());
            for k in &self.keys {
                if registry.robots.get(k).is_some_and(|h| h.claim == self.id) {
                    registry.robots.remove(k);
                }
            }
        }
        self.released.cancel();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test]
    async fn a_second_claim_of_a_robot_is_refused_until_the_first_lets_go() {
        let e = Executing::default();
        let first = e.claim("c", &["r1", "r2"], false).await.unwrap();
        let err = e.claim("c", &["r3", "r2"], false).await.unwrap_err();
        assert!(
            matches!(&err, ServerError::AlreadyExists(m) if m.contains("`r2`") && m.contains("`c`")),
            "{err}"
        );
        // Another cell, or another robot, is free.
        let other_cell = e.claim("d", &["r1"], false).await.unwrap();
        let other_robot = e.claim("c", &["r3"], false).await.unwrap();
        assert_eq!(e.len(), 4);
        drop(first);
        assert_eq!(e.len(), 2);
        let again = e.claim("c", &["r1", "r2", "r2"], false).await.unwrap();
        assert_eq!(e.len(), 4);
        drop((again, other_cell, other_robot));
        assert!(e.is_empty());
    }

    #[tokio::test]
    async fn taking_over_ends_the_holder_and_waits_until_it_lets_go() {
        let e = Executing::default();
        let first = e.claim("c", &["r1"], false).await.unwrap();
        let taken = first.taken_over();
        // The holder: ends when told to, and lets go.
        let holder = tokio::spawn(async move {
            taken.await;
            drop(first);
        });
        let second = tokio::time::timeout(Duration::from_secs(10), e.claim("c", &["r1"], true))
            .await
            .expect("the take-over completes")
            .unwrap();
        tokio::time::timeout(Duration::from_secs(10), holder).await.unwrap().unwrap();
        assert_eq!(e.len(), 1);
        // The first claim's release did not remove the second's hold.
        assert!(e.claim("c", &["r1"], false).await.is_err());
        drop(second);
        assert!(e.is_empty());
    }

    #[tokio::test(start_paused = true)]
    async fn a_holder_that_does_not_let_go_fails_the_take_over() {
        let e = Executing::default();
        let _stuck = e.claim("c", &["r1"], false).await.unwrap();
        let err = e.claim("c", &["r1"], true).await.unwrap_err();
        assert!(matches!(err, ServerError::FailedPrecondition(_)), "{err}");
        assert_eq!(e.len(), 1);
    }
}
