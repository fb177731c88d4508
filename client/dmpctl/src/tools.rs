//! The commands that store primitives of robots of their own on the server: `sim` (robots `sim.<name>`), `load`
//! (`load.c<cell>.r<k>`) and `scenario run --server` (`scenario.<name>`). Each deletes what it stored when it ends,
//! on success and on error (the libraries do it, unless `--keep`); here also on Ctrl-C: the run is dropped, its
//! streams end, what it stored is deleted, and `dmpctl` exits with 130.

use std::future::Future;
use std::time::Duration;

use crate::error::DmpctlError;
use crate::progress::Progress;

/// Runs `work`, with `progress` saying `status()` a few times a second; on Ctrl-C drops it and runs `clean_up`
/// (None: `--keep`), which returns what it did.
pub(crate) async fn until_interrupted<T>(
    work: impl Future<Output = Result<T, DmpctlError>>,
    clean_up: Option<impl Future<Output = Result<String, DmpctlError>>>,
    progress: &Progress,
    status: impl Fn() -> String,
) -> Result<T, DmpctlError> {
    let mut work = std::pin::pin!(work);
    let mut every = tokio::time::interval(STATUS_EVERY);
    loop {
        tokio::select! {
            done = &mut work => return done,
            _ = every.tick() => progress.set_message(status()),
            _ = tokio::signal::ctrl_c() => {
                progress.println("dmpctl: interrupted: cleaning up");
                let cleaned = match clean_up {
                    None => "--keep: what it stored is kept".to_string(),
                    Some(c) => c.await.unwrap_or_else(|e| format!("the clean-up failed: {e}")),
                };
                return Err(DmpctlError::Interrupted { cleaned });
            }
        }
    }
}

/// How often the progress's status is refreshed.
const STATUS_EVERY: Duration = Duration::from_millis(250);

/// What a clean-up of `versions` primitive versions of `robots` says.
pub(crate) fn deleted(versions: u64, robots: &[String]) -> String {
    format!("deleted {versions} primitive versions of {}", robots.join(", "))
}
