//! Zenoh's threads in the server: all of Zenoh's runtimes on one worker thread.
//!
//! Zenoh runs its work on runtimes of its own, six threads by default (`rx` two, `tx`, `acc`, `net` and `app`
//! one each), and reads their layout only from the `ZENOH_RUNTIME` environment variable, once, at its first use
//! ([RON](https://github.com/ron-rs/ron), e.g. `(rx: (handover: app))`). The server hands every runtime over to
//! `app` ([`LAYOUT`]): one worker thread instead of six (blocking work still gets threads of its own). Measured with `dmpctl load --robots 100 --scene-updates 10`
//! (BENCHMARKS.md): update to adapted segment p50 0.43 - 0.48 ms instead of 0.49 - 0.55 ms and p99 1.38 - 1.93 ms
//! (ten 60 s runs, five with the same layout for the load generator) instead of 1.47 - 2.28 ms (eight), with no
//! loss at 1,000 robots.
//!
//! Setting a variable of the running process is `unsafe` (other threads may read the environment), so the
//! binary re-executes itself once with the variable set, before it starts any thread ([`reexec_with_layout`]).
//! A `ZENOH_RUNTIME` already in the environment is the operator's choice and is left alone; Zenoh panics on one it
//! cannot parse, so the binary checks it first ([`check`]) and refuses it with the reason.

use std::ffi::OsString;
use std::io;

use ron::extensions::Extensions;
use serde::Deserialize;

/// The variable Zenoh reads its runtimes' layout from.
pub const ZENOH_RUNTIME: &str = "ZENOH_RUNTIME";

/// The server's layout: every Zenoh runtime handed over to `app` (one worker thread).
pub const LAYOUT: &str =
    "(rx: (handover: app), tx: (handover: app), acc: (handover: app), net: (handover: app))";

/// The layout to set, given the environment's `ZENOH_RUNTIME`: [`LAYOUT`] when there is none, nothing when the
/// operator chose one (even an empty one).
pub fn layout_to_set(current: Option<&OsString>) -> Option<&'static str> {
    current.is_none().then_some(LAYOUT)
}

/// Zenoh's runtimes, as `ZENOH_RUNTIME` names them.
#[derive(Debug, Deserialize)]
#[serde(rename_all = "lowercase")]
enum Runtime {
    App,
    Acc,
    Tx,
    Rx,
    Net,
}

/// One runtime's parameters, as Zenoh parses them (zenoh-runtime 1.10's `RuntimeParamHelper`: plain counts, each
/// defaulted, no other field; the struct's name may be written).
#[derive(Debug, Deserialize)]
#[serde(rename = "RuntimeParamHelper", deny_unknown_fields, default)]
struct Param {
    worker_threads: usize,
    max_blocking_threads: usize,
    handover: Option<Runtime>,
}

impl Default for Param {
    fn default() -> Self {
        Self { worker_threads: 1, max_blocking_threads: 50, handover: None }
    }
}

/// The whole layout (Zenoh's `AbstractRuntimeParam`): any of the five runtimes, each defaulted.
#[derive(Debug, Default, Deserialize)]
#[serde(rename = "AbstractRuntimeParam", deny_unknown_fields, default)]
struct Layout {
    app: Param,
    acc: Param,
    tx: Param,
    rx: Param,
    net: Param,
}

/// Checks a `ZENOH_RUNTIME` value as Zenoh will read it (RON with implicit `Some`), and that every runtime Zenoh
/// will build (one not handed over) has at least one thread of each kind (Zenoh panics otherwise); the error says
/// what is wrong. Counts beyond what the system allows also make Zenoh panic, at its first use: not checked.
pub fn check(value: &str) -> Result<(), String> {
    let layout: Layout = ron::Options::default()
        .with_default_extension(Extensions::IMPLICIT_SOME)
        .from_str(value)
        .map_err(|e| format!("not a Zenoh runtime layout: {e}"))?;
    let runtimes = [
        ("app", &layout.app),
        ("acc", &layout.acc),
        ("tx", &layout.tx),
        ("rx", &layout.rx),
        ("net", &layout.net),
    ];
    for (name, p) in runtimes {
        if p.handover.is_some() {
            continue;
        }
        for (field, count) in
            [("worker_threads", p.worker_threads), ("max_blocking_threads", p.max_blocking_threads)]
        {
            if count == 0 {
                return Err(format!("{name}.{field} must be at least 1"));
            }
        }
    }
    Ok(())
}

/// Replaces this process with the same program and arguments, `ZENOH_RUNTIME` set to [`LAYOUT`], when the
/// environment does not set it: returns `None` when nothing needs doing, and the error only if the re-execution
/// failed (the caller goes on with Zenoh's default layout). Call it first thing in `main`, before any thread.
#[cfg(unix)]
pub fn reexec_with_layout() -> Option<io::Error> {
    use std::os::unix::process::CommandExt;

    let layout = layout_to_set(std::env::var_os(ZENOH_RUNTIME).as_ref())?;
    // This very program, even if its file was replaced since it started.
    let exe = if cfg!(target_os = "linux") {
        std::path::PathBuf::from("/proc/self/exe")
    } else {
        match std::env::current_exe() {
            Ok(exe) => exe,
            Err(e) => return Some(e),
        }
    };
    let mut args = std::env::args_os();
    let arg0 = args.next().unwrap_or_else(|| exe.clone().into_os_string());
    // `exec` returns only on failure.
    Some(std::process::Command::new(&exe).arg0(arg0).args(args).env(ZENOH_RUNTIME, layout).exec())
}

/// Not on Unix: Zenoh's default layout.
#[cfg(not(unix))]
pub fn reexec_with_layout() -> Option<io::Error> {
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_layout_is_set_only_when_the_operator_chose_none() {
        assert_eq!(layout_to_set(None), Some(LAYOUT));
        assert_eq!(layout_to_set(Some(&OsString::from("(rx: (worker_threads: 1))"))), None);
        assert_eq!(layout_to_set(Some(&OsString::new())), None, "an empty value is a choice too");
    }

    #[test]
    fn a_layout_is_checked_as_zenoh_reads_it() {
        assert_eq!(check(LAYOUT), Ok(()));
        assert_eq!(check("()"), Ok(()), "Zenoh's default");
        assert_eq!(check("(rx: (worker_threads: 1, max_blocking_threads: 4), app: (handover: net))"), Ok(()));
        assert_eq!(check("AbstractRuntimeParam(rx: RuntimeParamHelper(worker_threads: 2))"), Ok(()), "named");
        assert_eq!(
            check("(rx: (worker_threads: 0, handover: app))"),
            Ok(()),
            "a runtime handed over is not built"
        );
        let refused = |value: &str, says: &str| {
            let e = check(value).expect_err(value);
            assert!(e.contains(says), "{value}: {e}");
        };
        refused("", "not a Zenoh runtime layout");
        refused("(rxx: (worker_threads: 1))", "rxx");
        refused("(rx: (threads: 1))", "threads");
        refused("(rx: (handover: gpu))", "gpu");
        refused("(tx: (worker_threads: -1))", "not a Zenoh runtime layout");
        refused("(net: (worker_threads: 0))", "net.worker_threads must be at least 1");
        refused("(acc: (max_blocking_threads: 0))", "acc.max_blocking_threads must be at least 1");
        // Zenoh's fields are plain: an explicit option, or a struct of another name, makes it panic.
        for value in [
            "(rx: (worker_threads: Some(2)))",
            "(rx: (max_blocking_threads: None))",
            "(rx: None)",
            "(rx: Some((worker_threads: 1)))",
            "Layout(rx: (worker_threads: 1))",
            "(rx: Param(worker_threads: 1))",
        ] {
            refused(value, "not a Zenoh runtime layout");
        }
    }
}
