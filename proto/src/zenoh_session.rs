//! The one builder of a Zenoh session's configuration, shared by the server's bridge and the client's publisher
//! (cargo feature `zenoh`).
//!
//! The rules: the mode is `peer` or `client`; every endpoint is checked before Zenoh sees it (the error names it);
//! with `connect` endpoints, opening waits at most [`CONNECT_TIMEOUT_MS`] for them and fails if they cannot be
//! reached, instead of retrying forever in the background; gossip scouting follows the multicast switch, so with
//! it off the session talks only to the endpoints it is given (and to those that connect to it).

use std::path::PathBuf;

use zenoh::Session;
use zenoh::config::EndPoint;

use crate::WireError;

/// How long opening a session waits for its `connect` endpoints before it fails (only when some are given).
pub const CONNECT_TIMEOUT_MS: u64 = 2000;

/// What a session is opened with.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SessionOptions {
    /// `peer` or `client`.
    pub mode: String,
    /// Endpoints to listen on; `None`: Zenoh's default for the mode (a peer listens on a random port of every
    /// interface, a client on none). `Some` of an empty list listens on nothing.
    pub listen: Option<Vec<String>>,
    /// Endpoints to connect to (routers or peers).
    pub connect: Vec<String>,
    /// Multicast scouting (finding peers on the LAN), and with it gossip scouting.
    pub multicast_scouting: bool,
    /// A stock Zenoh configuration file (JSON5) to start from; the settings above are applied on top.
    pub config_file: Option<PathBuf>,
    /// TLS of the `tls/` endpoints.
    pub tls: Option<ZenohTls>,
    /// An `access_control` block to apply, unless the configuration file has one of its own.
    pub access_control: Option<serde_json::Value>,
}

/// TLS of a session's `tls/` endpoints: its certificate and key serve both its listeners and its connections, and
/// `root_ca` verifies the other side (with `mutual`, on listeners too: a peer without a certificate of that CA
/// cannot connect, and its certificate's common name is its subject in the access control).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ZenohTls {
    /// The CA (PEM file).
    pub root_ca: PathBuf,
    /// This session's certificate (PEM file).
    pub cert: PathBuf,
    /// This session's private key (PEM file).
    pub key: PathBuf,
    /// Verify the certificates of peers that connect.
    pub mutual: bool,
}

impl SessionOptions {
    /// A peer on loopback (`tcp/127.0.0.1:0`, read the real port with [`locators`]) without scouting, connecting to
    /// `connect`: what tests open, as Zenoh's own test harness does (multicast fails on CI machines).
    pub fn loopback_peer(connect: Vec<String>) -> Self {
        Self {
            mode: "peer".into(),
            listen: Some(vec!["tcp/127.0.0.1:0".into()]),
            connect,
            multicast_scouting: false,
            config_file: None,
            tls: None,
            access_control: None,
        }
    }
}

/// The Zenoh configuration of `options` (see the module's rules). Errors name the setting: `zenoh.mode`,
/// `zenoh.listen[i]`, `zenoh.connect[i]`.
pub fn session_config(options: &SessionOptions) -> Result<zenoh::Config, WireError> {
    if !matches!(options.mode.as_str(), "peer" | "client") {
        return Err(WireError::new(
            "zenoh.mode",
            format!("must be `peer` or `client`, found `{}`", options.mode),
        ));
    }
    let endpoints = |field: &str, list: &[String]| -> Result<String, WireError> {
        for (i, e) in list.iter().enumerate() {
            e.parse::<EndPoint>()
                .map_err(|err| WireError::new(format!("zenoh.{field}[{i}]"), err.to_string()))?;
        }
        Ok(serde_json::Value::from(list.to_vec()).to_string())
    };
    let mut c = match &options.config_file {
        Some(path) => zenoh::Config::from_file(path)
            .map_err(|e| WireError::new("zenoh.config_file", format!("{}: {e}", path.display())))?,
        None => zenoh::Config::default(),
    };
    let own_acl = c.get_json("access_control/enabled").is_ok_and(|v| v == "true");
    let mut set = |key: &str, value: String| -> Result<(), WireError> {
        c.insert_json5(key, &value).map_err(|e| WireError::new(format!("zenoh config {key}"), e.to_string()))
    };
    set("mode", serde_json::Value::from(options.mode.as_str()).to_string())?;
    if let Some(listen) = &options.listen {
        set("listen/endpoints", endpoints("listen", listen)?)?;
    }
    if !options.connect.is_empty() {
        set("connect/endpoints", endpoints("connect", &options.connect)?)?;
        set("connect/timeout_ms", CONNECT_TIMEOUT_MS.to_string())?;
        set("connect/exit_on_failure", "true".into())?;
    }
    set("scouting/multicast/enabled", options.multicast_scouting.to_string())?;
    set("scouting/gossip/enabled", options.multicast_scouting.to_string())?;
    if let Some(tls) = &options.tls {
        let path = |p: &PathBuf| serde_json::Value::from(p.display().to_string()).to_string();
        set("transport/link/tls/root_ca_certificate", path(&tls.root_ca))?;
        set("transport/link/tls/listen_certificate", path(&tls.cert))?;
        set("transport/link/tls/listen_private_key", path(&tls.key))?;
        set("transport/link/tls/connect_certificate", path(&tls.cert))?;
        set("transport/link/tls/connect_private_key", path(&tls.key))?;
        set("transport/link/tls/enable_mtls", tls.mutual.to_string())?;
    }
    if let Some(acl) = &options.access_control
        && !own_acl
    {
        set("access_control", acl.to_string())?;
    }
    Ok(c)
}

/// Whether the configuration file of `options` has an access control of its own (which then replaces the one
/// `options` would apply).
pub fn has_own_access_control(options: &SessionOptions) -> Result<bool, WireError> {
    let Some(path) = &options.config_file else { return Ok(false) };
    let c = zenoh::Config::from_file(path)
        .map_err(|e| WireError::new("zenoh.config_file", format!("{}: {e}", path.display())))?;
    Ok(c.get_json("access_control/enabled").is_ok_and(|v| v == "true"))
}

/// The endpoints a session really listens on (`tcp/127.0.0.1:0` resolved to its port), for peers to connect to.
pub async fn locators(session: &Session) -> Vec<String> {
    session.info().locators().await.into_iter().map(|l| l.to_string()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn config_is_built_and_checked() {
        let c = session_config(&SessionOptions::loopback_peer(vec!["tcp/127.0.0.1:7447".into()])).unwrap();
        let json = format!("{c}");
        assert!(json.contains("tcp/127.0.0.1:7447"), "{json}");
        let mut bad = SessionOptions::loopback_peer(vec![]);
        bad.mode = "router".into();
        assert!(session_config(&bad).unwrap_err().to_string().starts_with("zenoh.mode"));
        let bad = SessionOptions::loopback_peer(vec!["tcp/127.0.0.1:1".into(), "not an endpoint".into()]);
        assert!(session_config(&bad).unwrap_err().to_string().starts_with("zenoh.connect[1]"));
        let bad =
            SessionOptions { listen: Some(vec!["nowhere".into()]), ..SessionOptions::loopback_peer(vec![]) };
        assert_eq!(session_config(&bad).unwrap_err().field, "zenoh.listen[0]");
    }

    #[test]
    fn listening_on_nothing_differs_from_the_default() {
        let nothing =
            session_config(&SessionOptions { listen: Some(vec![]), ..SessionOptions::loopback_peer(vec![]) })
                .unwrap();
        assert_eq!(nothing.get_json("listen/endpoints").unwrap(), "[]");
        let default =
            session_config(&SessionOptions { listen: None, ..SessionOptions::loopback_peer(vec![]) })
                .unwrap();
        assert_ne!(default.get_json("listen/endpoints").unwrap(), "[]");
    }
}
