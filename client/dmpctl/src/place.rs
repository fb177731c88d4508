//! Where a command acts: its one cell (`--cell`, else the server's default) and the Zenoh endpoints it connects to,
//! asked of the server (GetInfo) by the commands that use Zenoh.

use dmp_client::connect::ConnectOptions;
use dmp_client::grpc::DmpClient;

use crate::args::{Cli, Command, SceneCommand, Via};
use crate::error::DmpctlError;

/// Where a command acts: its one cell, for gRPC and Zenoh alike, and the Zenoh endpoints it connects to.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Place {
    /// `--cell`, else (commands that use Zenoh) the server's default cell from GetInfo; `None`: the server's
    /// default, which gRPC requests get by naming no cell.
    pub(crate) cell: Option<String>,
    /// `--zenoh-connect`, else (commands that use Zenoh, when no `--zenoh-config` names endpoints) the server's
    /// Zenoh locators from GetInfo when the server is on this host ([`usable_locators`]); empty: scouting.
    pub(crate) zenoh_connect: Vec<String>,
}

impl Place {
    /// The cell gRPC requests name (empty: the server's default).
    pub(crate) fn grpc_cell(&self) -> &str {
        self.cell.as_deref().unwrap_or("")
    }

    /// The cell of the Zenoh keys.
    pub(crate) fn zenoh_cell(&self) -> &str {
        self.cell.as_deref().unwrap_or("default")
    }
}

/// The gRPC server of the command: `--server`; else, with `--cell` and Zenoh endpoints (`--zenoh-connect` or
/// `--zenoh-config`), the server of the plant that serves the cell, asked over Zenoh
/// (`dmp_client::discovery`); else `default`. A plant that does not answer is said on stderr and `default` is
/// used. Commands that only publish over Zenoh (`scene ... --via zenoh`) ask nothing.
pub(crate) async fn resolve_server(cli: &Cli, default: &str) -> String {
    if let Some(s) = &cli.server {
        return s.clone();
    }
    let zenoh_only = matches!(
        &cli.command,
        Command::Scene(
            SceneCommand::Put { via: Via::Zenoh, .. } | SceneCommand::Delete { via: Via::Zenoh, .. }
        )
    );
    let Some(cell) = &cli.cell else { return default.to_owned() };
    if zenoh_only || (cli.zenoh_connect.is_empty() && cli.zenoh_config.is_none()) {
        return default.to_owned();
    }
    let timeout = dmp_client::discovery::RESOLVE_TIMEOUT;
    match dmp_client::discovery::resolve_cell_via(
        &cli.zenoh_connect,
        cli.zenoh_config.as_deref(),
        cell,
        timeout,
    )
    .await
    {
        Ok(found) => {
            eprintln!("dmpctl: cell `{cell}` is served by `{}` at {}", found.server_id, found.grpc_address);
            found.grpc_address
        }
        Err(e) => {
            eprintln!(
                "dmpctl: warning: could not find the server of cell `{cell}` over Zenoh ({e}); using {default}"
            );
            default.to_owned()
        }
    }
}

/// Resolves the command's [`Place`]. A `--cell` is checked against the naming rule. Commands that use Zenoh (scene
/// changes `--via zenoh`, `sim`, `load --scene-updates`) ask the server (GetInfo) for what they were not given, so
/// that their Zenoh keys name the server's cell; if it cannot be asked (no gRPC access, only a Zenoh certificate),
/// they say so and go on with `default`. gRPC commands ask nothing: naming no cell is the server's default.
pub(crate) async fn resolve_place(
    cli: &Cli,
    server: &str,
    options: &ConnectOptions,
) -> Result<Place, DmpctlError> {
    if let Some(cell) = &cli.cell {
        dmp_proto::keys::check_name("--cell", cell).map_err(|e| DmpctlError::argument("--cell", e.rule))?;
    }
    let given = Place { cell: cli.cell.clone(), zenoh_connect: cli.zenoh_connect.clone() };
    let uses_zenoh = match &cli.command {
        Command::Scene(SceneCommand::Put { via, .. } | SceneCommand::Delete { via, .. }) => {
            *via == Via::Zenoh
        }
        Command::Sim(_) => true,
        // Through a plant, the load's cells are its own and its servers found over Zenoh: nothing to ask.
        Command::Load(a) => a.scene_updates > 0.0 && !a.via_zenoh_discovery,
        _ => false,
    };
    let need_cell = cli.cell.is_none();
    let need_zenoh = cli.zenoh_connect.is_empty() && cli.zenoh_config.is_none();
    if !uses_zenoh || !(need_cell || need_zenoh) {
        return Ok(given);
    }
    let asked = async { DmpClient::connect_with(server, options).await?.info().await }.await;
    let info = match asked {
        Ok(info) => info,
        Err(e) => {
            eprintln!(
                "dmpctl: warning: could not ask {server} for its default cell and Zenoh locators ({e}); \
                 using cell `{}`{}",
                given.zenoh_cell(),
                if need_zenoh { " and Zenoh scouting" } else { "" }
            );
            return Ok(given);
        }
    };
    let cell = cli.cell.clone().or_else(|| (!info.cell.is_empty()).then(|| info.cell.clone()));
    let zenoh_connect =
        if need_zenoh { usable_locators(server, &info.zenoh_locators) } else { cli.zenoh_connect.clone() };
    Ok(Place { cell, zenoh_connect })
}

/// The host of a URL such as `http://127.0.0.1:50051` or `https://[::1]:50051/`.
fn url_host(url: &str) -> &str {
    let rest = url.split_once("://").map_or(url, |(_, r)| r);
    let authority = rest.split('/').next().unwrap_or(rest);
    match authority.strip_prefix('[') {
        Some(v6) => v6.split(']').next().unwrap_or(v6),
        None => authority.rsplit_once(':').map_or(authority, |(h, _)| h),
    }
}

/// Whether `host` names this machine's loopback.
fn is_loopback(host: &str) -> bool {
    host == "localhost" || host.parse::<std::net::IpAddr>().is_ok_and(|ip| ip.is_loopback())
}

/// The locators of a server at `server` that this client can use: the loopback ones, when the server itself is
/// reached on loopback. A remote server's listen addresses (its loopback, or every one of its interfaces) say
/// nothing reliable about how to reach it from here, and a wrong one would publish to another system: none then
/// (scouting, or `--zenoh-connect`).
pub(crate) fn usable_locators(server: &str, locators: &[String]) -> Vec<String> {
    if !is_loopback(url_host(server)) {
        return Vec::new();
    }
    locators
        .iter()
        .filter(|l| l.split_once('/').is_some_and(|(_, addr)| is_loopback(url_host(addr))))
        .cloned()
        .collect()
}
