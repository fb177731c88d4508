//! Zenoh's threads in the server: all of Zenoh's runtimes on one worker thread.
//!
//! Zenoh runs its work on runtimes of its own, six threads by default (`rx` two, `tx`, `acc`, `net` and `app`
//! one each), and reads their layout only from the `ZENOH_RUNTIME` environment variable, once, at its first use
//! ([RON](https://github.com/ron-rs/ron), e.g. `(rx: (handover: app))`). The server hands every runtime over to
//! `app` ([`LAYOUT`]): one worker thread instead of six (blocking work still gets threads of its own); what that
//! does to an obstacle update's latency is in BENCHMARKS.md.
//!
//! The layout is configuration: the deploy files set the variable, and the binary sets [`LAYOUT`] in its own
//! environment when the operator chose none and Zenoh is on ([`layout_to_set`]), before it starts any thread. A
//! `ZENOH_RUNTIME` already in the environment is the operator's choice and is left alone; a value Zenoh cannot
//! read is Zenoh's to report.

use std::ffi::OsStr;

/// The variable Zenoh reads its runtimes' layout from.
pub const ZENOH_RUNTIME: &str = "ZENOH_RUNTIME";

/// The server's layout: every Zenoh runtime handed over to `app` (one worker thread).
pub const LAYOUT: &str =
    "(rx: (handover: app), tx: (handover: app), acc: (handover: app), net: (handover: app))";

/// The layout to set, given the environment's `ZENOH_RUNTIME` and whether Zenoh is on: [`LAYOUT`] when Zenoh is
/// on and the operator chose no layout, nothing otherwise (an operator's value, even an empty one, is kept).
pub fn layout_to_set(current: Option<&OsStr>, zenoh_on: bool) -> Option<&'static str> {
    (zenoh_on && current.is_none()).then_some(LAYOUT)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_layout_is_set_only_when_zenoh_is_on_and_the_operator_chose_none() {
        assert_eq!(layout_to_set(None, true), Some(LAYOUT));
        assert_eq!(layout_to_set(None, false), None, "without Zenoh nothing reads it");
        assert_eq!(layout_to_set(Some(OsStr::new("(rx: (worker_threads: 1))")), true), None);
        assert_eq!(layout_to_set(Some(OsStr::new("")), true), None, "an empty value is a choice too");
    }
}
