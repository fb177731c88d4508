//! `dmp-server`: parses the flags, starts logging, and runs the server until SIGINT or SIGTERM (SIGHUP reloads the
//! access file).

use std::future::Future;
use std::io::IsTerminal;
use std::process::ExitCode;

use clap::Parser;
use dmp_server::access::init::{CA_KEY, InitExtras, InitOptions, init_with, uncovered_locators};
use dmp_server::config::command_line::{AccessCommand, Args, Command, load_config};
use dmp_server::zenoh_bridge::threads::{self, ZENOH_RUNTIME};
use tokio::signal::unix::{SignalKind, signal};
use tracing::{error, info, warn};
use tracing_subscriber::EnvFilter;
use tracing_subscriber::layer::SubscriberExt;
use tracing_subscriber::util::SubscriberInitExt;

/// Thousands of streams allocate and free small buffers (segments, robot states) at a high rate: mimalloc keeps
/// that cheaper than the system allocator. Built without transparent huge pages (`no_thp`): with them its resident
/// memory rose in steps over a run instead of staying flat (BENCHMARKS.md).
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() -> ExitCode {
    let args = Args::parse();
    if let Some(Command::Access(AccessCommand::Init {
        dir,
        cells,
        robots,
        hosts,
        zenoh_port,
        robot_prefixes,
    })) = &args.command
    {
        let options = InitOptions { cells: cells.clone(), robots: robots.clone(), hosts: hosts.clone() };
        let extras = InitExtras { zenoh_port: Some(*zenoh_port), robot_prefixes: robot_prefixes.clone() };
        return match init_with(dir, &options, &extras) {
            Ok(set) => {
                println!(
                    "wrote a CA, the server's certificate and the access file into {}",
                    set.dir.display()
                );
                for (name, _) in &set.tokens {
                    println!("  identity `{name}`: {name}.pem, {name}.key, {name}.token");
                }
                println!(
                    "the CA's private key is {d}/{CA_KEY}: keep it apart, never hand it out (it signs new \
                     certificates)",
                    d = set.dir.display()
                );
                println!(
                    "serve with: dmp-server --access {d}/access.toml --tls-cert {d}/server.pem --tls-key {d}/server.key \
                     --tls-client-ca {d}/ca.pem --zenoh-listen tls/0.0.0.0:{zenoh_port}",
                    d = set.dir.display()
                );
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("dmp-server access init: {e}");
                ExitCode::FAILURE
            }
        };
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
    // Zenoh's threads (`dmp_server::zenoh_bridge::threads`): the server's layout unless the operator chose one. Zenoh reads
    // the variable at its first use, later.
    if let Some(layout) =
        threads::layout_to_set(std::env::var_os(ZENOH_RUNTIME).as_deref(), !config.zenoh.disabled)
    {
        // SAFETY: `set_var` is unsound only while another thread may read or write the environment. This process
        // has one thread here: Rust starts none before `main`, and everything above (clap's parsing, reading and
        // parsing the configuration file, printing) runs on this one; logging, the tokio runtime and Zenoh, which
        // start threads, are all set up below.
        #[allow(unsafe_code)]
        unsafe {
            std::env::set_var(ZENOH_RUNTIME, layout);
        }
    }

    let runtime = match tokio::runtime::Builder::new_multi_thread().enable_all().build() {
        Ok(rt) => rt,
        Err(e) => {
            eprintln!("dmp-server: cannot start the tokio runtime: {e}");
            return ExitCode::FAILURE;
        }
    };
    // Traces to OpenTelemetry: the exporter's channel lives on the runtime.
    let otlp = config.otlp_endpoint.as_deref().map(|endpoint| {
        let _runtime = runtime.enter();
        dmp_server::telemetry::otlp_layer(endpoint)
    });
    let (otlp, traces) = match otlp.transpose() {
        Ok(Some((layer, provider))) => (Some(layer), Some(provider)),
        Ok(None) => (None, None),
        Err(e) => {
            eprintln!("dmp-server: {e}");
            return ExitCode::from(2);
        }
    };
    tracing_subscriber::registry()
        .with(EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new("info")))
        .with(
            tracing_subscriber::fmt::layer()
                .with_writer(std::io::stderr)
                // Colours only on a terminal: journald and container logs get plain text.
                .with_ansi(std::io::stderr().is_terminal()),
        )
        .with(otlp)
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
        otlp_endpoint = ?config.otlp_endpoint,
        config = %full,
        "effective configuration"
    );

    let result = runtime.block_on(async {
        let shutdown = shutdown_signal().map_err(|e| format!("cannot install the signal handlers: {e}"))?;
        let hangups =
            signal(SignalKind::hangup()).map_err(|e| format!("cannot install the SIGHUP handler: {e}"))?;
        let hangups = tokio_stream::wrappers::SignalStream::new(hangups);
        let certificate = config.security.tls_cert.clone();
        let handle = dmp_server::server::start(config).await.map_err(|e| e.to_string())?;
        if let Some(path) = certificate {
            warn_uncovered_locators(&path, &handle.zenoh_locators);
        }
        serve(handle, shutdown, hangups).await
    });
    // What is pending goes to the collector before the process exits.
    if let Some(traces) = traces
        && let Err(e) = traces.shutdown()
    {
        warn!(error = %e, "flushing the traces to the OpenTelemetry collector");
    }
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

/// Serves until `shutdown`, reloading the access file on each SIGHUP, then stops cleanly (as
/// `dmp_server::server::run`, once the started server has been checked).
async fn serve(
    handle: dmp_server::server::ServerHandle,
    shutdown: impl Future<Output = ()>,
    mut hangups: impl tokio_stream::Stream<Item = ()> + Unpin,
) -> Result<(), String> {
    tokio::pin!(shutdown);
    loop {
        tokio::select! {
            _ = &mut shutdown => break,
            Some(()) = tokio_stream::StreamExt::next(&mut hangups) => {
                info!("SIGHUP: reloading the access file");
                // A refused file is logged and changes nothing.
                let _ = handle.reload_access();
            }
        }
    }
    info!("shutting down: draining streams, closing Zenoh");
    handle.shutdown().await.map_err(|e| e.to_string())
}

/// Warns when the server advertises a Zenoh address its certificate (`path`) does not name: a client that
/// connects there fails the TLS handshake. The fix is a set made with that address (`access init --host`).
fn warn_uncovered_locators(path: &std::path::Path, locators: &[String]) {
    let pem = match std::fs::read(path) {
        Ok(pem) => pem,
        Err(e) => {
            return warn!(certificate = %path.display(), error = %e, "cannot read the server's certificate");
        }
    };
    match uncovered_locators(&pem, locators) {
        Ok(uncovered) if !uncovered.is_empty() => warn!(
            certificate = %path.display(),
            locators = ?uncovered,
            "the server advertises Zenoh addresses its certificate does not name: clients that connect there fail \
             the TLS handshake. Make a set that names them (dmp-server access init DIR --host ADDRESS, one --host \
             per address), or listen only on addresses it names (--zenoh-listen)"
        ),
        Ok(_) => {}
        Err(e) => warn!(certificate = %path.display(), error = %e, "cannot read the server's certificate"),
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
