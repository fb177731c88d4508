//! Progress of the long commands (`sim`, `load`, `scenario run --server`, `stream`) on a terminal: a spinner with
//! the elapsed time, the robots and the segments read, drawn on stderr from [`REVEAL_AFTER`] on (a command that is
//! done sooner shows nothing). When stderr is not a terminal (piped, a file, CI) nothing is drawn at all: the bar
//! is [`ProgressDrawTarget::hidden`].

use std::io::IsTerminal;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// How long a command runs before its progress appears.
pub(crate) const REVEAL_AFTER: Duration = Duration::from_secs(2);

/// The progress of one command; cleared when dropped.
#[derive(Debug)]
pub(crate) struct Progress {
    bar: ProgressBar,
    done: Arc<AtomicBool>,
}

impl Progress {
    /// Progress of `what` (e.g. `sim panda: 1 robot`), drawn on stderr after [`REVEAL_AFTER`] when stderr is a
    /// terminal; hidden otherwise.
    pub(crate) fn new(what: impl Into<String>) -> Self {
        Self::with_target(what, std::io::stderr().is_terminal())
    }

    /// [`Progress::new`], drawn (after [`REVEAL_AFTER`]) only if `terminal`.
    pub(crate) fn with_target(what: impl Into<String>, terminal: bool) -> Self {
        let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::hidden());
        let style = ProgressStyle::with_template("{spinner} [{elapsed_precise}] {prefix}: {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_spinner());
        bar.set_style(style);
        bar.set_prefix(what.into());
        let done = Arc::new(AtomicBool::new(false));
        if terminal {
            let (bar, done) = (bar.clone(), done.clone());
            // A plain thread: the offline commands have no runtime, and this one only sleeps once.
            std::thread::spawn(move || {
                std::thread::sleep(REVEAL_AFTER);
                if !done.load(Ordering::Acquire) {
                    bar.set_draw_target(ProgressDrawTarget::stderr());
                    bar.enable_steady_tick(Duration::from_millis(200));
                }
            });
        }
        Self { bar, done }
    }

    /// Whether it is hidden now (not drawn).
    pub(crate) fn is_hidden(&self) -> bool {
        self.bar.is_hidden()
    }

    /// Sets what it says after the elapsed time (`3 robots, 120 segments`).
    pub(crate) fn set_message(&self, message: impl Into<String>) {
        self.bar.set_message(message.into());
    }

    /// Counts one more step (a segment) and says `message`.
    pub(crate) fn tick(&self, message: impl Into<String>) {
        self.bar.inc(1);
        self.bar.set_message(message.into());
    }

    /// Prints a line on stderr above the spinner (plainly when it is not drawn).
    pub(crate) fn println(&self, line: &str) {
        if self.is_hidden() {
            eprintln!("{line}");
        } else {
            self.bar.println(line);
        }
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        self.done.store(true, Ordering::Release);
        self.bar.finish_and_clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nothing_is_drawn_off_a_terminal() {
        let p = Progress::with_target("sim panda", false);
        p.tick("1 segment");
        std::thread::sleep(Duration::from_millis(50));
        assert!(p.is_hidden());
    }
}
