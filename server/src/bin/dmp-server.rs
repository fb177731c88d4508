//! `dmp-server`: parses the flags, starts logging, and runs the server until SIGINT or SIGTERM.

use std::future::Future;
use std::io::IsTerminal;
use std::process::ExitCode;

use clap::Parser;
use dmp_server::cli::{Args, load_config};
use dmp_server::zenoh_threads::{self, ZENOH_RUNTIME};
use tokio::signal::unix::{SignalKind, signal};
use tracing::{error, info, warn};
use tracing_subscriber::EnvFilter;

/// Thousands of streams allocate and free small buffers (segments, robot states) at a high rate: mimalloc keeps
/// that cheaper than the system allocator. Built without transparent huge pages (`no_thp`): with them its resident
/// memory rose in steps of about 12 MiB over a run (130 to 190 MiB with 1,000 streams) instead of staying flat.
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() -> ExitCode {
    let args = Args::parse();
    // Without a layout of the operator's, the server re-executes itself with its own, first thing: before any
    // thread starts, and before anything is read (a configuration file given as a pipe can be read only once).
    if !args.no_zenoh
        && !args.print_config
        && let Some(e) = zenoh_threads::reexec_with_layout()
    {
        eprintln!(
            "dmp-server: cannot re-execute with {ZENOH_RUNTIME} set ({e}): Zenoh keeps its default threads"
        );
    }
    let config = match load_config(&args) {
        Ok(c) => c,
        Err(e) => {
            eprintln!("dmp-server: {e:#}");
            return ExitCode::from(2);
        }
    };
    if args.print_config {
        match toml::to_string_pretty(&config) {
            Ok(text) => {
                print!("{text}");
                return ExitCode::SUCCESS;
            }
            Err(e) => {
                eprintln!("dmp-server: cannot print the configuration: {e}");
                return ExitCode::FAILURE;
            }
        }
    }
    // Zenoh's threads (`dmp_server::zenoh_threads`): an operator's layout is checked (Zenoh would panic on a bad
    // one).
    if !config.zenoh.disabled
        && let Some(value) = std::env::var_os(ZENOH_RUNTIME)
    {
        let checked = value.to_str().ok_or_else(|| "not UTF-8".to_string()).and_then(zenoh_threads::check);
        if let Err(e) = checked {
            eprintln!("dmp-server: {ZENOH_RUNTIME}: {e}");
            return ExitCode::from(2);
        }
    }

    tracing_subscriber::fmt()
        .with_env_filter(EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new("info")))
        .with_writer(std::io::stderr)
        // Colours only on a terminal: journald and container logs get plain text.
        .with_ansi(std::io::stderr().is_terminal())
        .init();
    // One line with everything (JSON), then the fields an operator looks for first.
    let full = serde_json::to_string(&config).unwrap_or_else(|e| format!("<unprintable: {e}>"));
    info!(
        grpc_addr = %config.grpc_addr,
        data_dir = %config.data_dir.display(),
        cell = %config.cell,
        zenoh = !config.zenoh.disabled,
        zenoh_mode = %config.zenoh.mode,
        zenoh_listen = ?config.zenoh.listen,
        zenoh_connect = ?config.zenoh.connect,
        zenoh_multicast = config.zenoh.multicast_scouting,
        zenoh_runtime = std::env::var(ZENOH_RUNTIME).unwrap_or_default(),
        config = %full,
        "effective configuration"
    );

    let runtime = match tokio::runtime::Builder::new_multi_thread().enable_all().build() {
        Ok(rt) => rt,
        Err(e) => {
            error!(error = %e, "cannot start the tokio runtime");
            eprintln!("dmp-server: cannot start the tokio runtime: {e}");
            return ExitCode::FAILURE;
        }
    };
    let result = runtime.block_on(async {
        let shutdown = shutdown_signal().map_err(|e| format!("cannot install the signal handlers: {e}"))?;
        dmp_server::run::run(config, shutdown).await.map_err(|e| e.to_string())
    });
    match result {
        Ok(()) => {
            info!("stopped");
            ExitCode::SUCCESS
        }
        Err(e) => {
            error!(error = %e, "the server failed");
            eprintln!("dmp-server: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Completes on the first SIGINT or SIGTERM (containers and systemd send SIGTERM). The handlers are installed
/// before the server starts, so a signal is never lost to the default action; a second signal exits at once,
/// without waiting for the drain.
fn shutdown_signal() -> std::io::Result<impl Future<Output = ()> + Send + 'static> {
    let mut interrupt = signal(SignalKind::interrupt())?;
    let mut terminate = signal(SignalKind::terminate())?;
    Ok(async move {
        let name = tokio::select! {
            _ = interrupt.recv() => "SIGINT",
            _ = terminate.recv() => "SIGTERM",
        };
        info!(signal = name, "signal received: stopping (send it again to exit at once)");
        tokio::spawn(async move {
            let name = tokio::select! {
                _ = interrupt.recv() => "SIGINT",
                _ = terminate.recv() => "SIGTERM",
            };
            warn!(signal = name, "second signal: exiting without waiting for the drain");
            std::process::exit(130);
        });
    })
}
