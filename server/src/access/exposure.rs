//! Secure by default: what the server may expose. Without TLS and an access file it listens on loopback only,
//! with multicast scouting off; anything else is refused at start, naming the setting, unless the operator says
//! `--insecure`, which every start then repeats (the log and GetInfo).

use std::net::{IpAddr, SocketAddr};

use crate::config::Config;
use crate::error::ServerError;

/// How the server is exposed, once checked.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub(crate) struct Exposure {
    /// What is exposed without protection (`--insecure`), in words; empty when nothing is.
    pub warnings: Vec<String>,
}

impl Exposure {
    /// Whether something is exposed without protection.
    pub(crate) fn insecure(&self) -> bool {
        !self.warnings.is_empty()
    }
}

/// Checks `config` against the rules above.
pub(crate) fn check(config: &Config) -> Result<Exposure, ServerError> {
    let s = &config.security;
    let tls = s.tls_cert.is_some() && s.tls_key.is_some();
    let access = s.access.is_some();
    let mut unprotected = Vec::new();
    let protected = tls && access;
    if !is_loopback(config.grpc_addr.ip()) && !protected {
        unprotected.push(format!(
            "gRPC listens on {} without {}",
            config.grpc_addr,
            missing(tls, access, "TLS (--tls-cert, --tls-key)")
        ));
    }
    if !config.zenoh.disabled {
        // Beyond loopback, Zenoh takes `tls/` endpoints with mutual TLS and the access control generated from the
        // access file: a peer needs a certificate of the cell's CA, and its common name's role.
        let zenoh_protected = s.tls_client_ca.is_some() && tls && access;
        let secured = |e: &String| e.starts_with("tls/") && zenoh_protected;
        for endpoint in &config.zenoh.listen {
            if !endpoint_is_loopback(endpoint) && !secured(endpoint) {
                unprotected.push(format!(
                    "Zenoh listens on {endpoint} without TLS (a `tls/` endpoint with --tls-client-ca) and an access file"
                ));
            }
        }
        let peer = config.zenoh.mode == "peer";
        if peer && config.zenoh.listen.is_empty() {
            unprotected.push("Zenoh listens on its default for a peer, every interface, without TLS".into());
        }
        // What comes in through a connection counts as much as what comes in through a listener.
        for endpoint in &config.zenoh.connect {
            if !endpoint_is_loopback(endpoint) && !secured(endpoint) {
                unprotected.push(format!("Zenoh connects to {endpoint} without TLS and an access file"));
            }
        }
        let all_secured = !config.zenoh.listen.is_empty() && config.zenoh.listen.iter().all(secured);
        if config.zenoh.multicast_scouting && !all_secured {
            unprotected.push(
                "Zenoh multicast scouting is on with listeners that are not secured: any peer on the LAN can join"
                    .into(),
            );
        }
    }
    if !unprotected.is_empty() && !s.insecure {
        return Err(ServerError::FailedPrecondition(format!(
            "refusing to start: {}. Listen on loopback, secure it (`dmp-server access init` writes a CA, \
             certificates, tokens and the access file), or accept the risk with --insecure",
            unprotected.join("; ")
        )));
    }
    Ok(Exposure { warnings: unprotected })
}

fn missing(tls: bool, access: bool, tls_words: &str) -> String {
    match (tls, access) {
        (false, false) => format!("{tls_words} and an access file (--access)"),
        (false, true) => tls_words.to_owned(),
        _ => "an access file (--access)".to_owned(),
    }
}

fn is_loopback(ip: IpAddr) -> bool {
    match ip {
        IpAddr::V4(v4) => v4.is_loopback(),
        IpAddr::V6(v6) => v6.is_loopback() || v6.to_ipv4_mapped().is_some_and(|v4| v4.is_loopback()),
    }
}

/// Whether a Zenoh endpoint (`tcp/127.0.0.1:7447`, `tcp/[::1]:7447#...`, `tcp/localhost:7447`) is on loopback.
/// What cannot be read as an address is taken as not loopback.
pub(crate) fn endpoint_is_loopback(endpoint: &str) -> bool {
    let Some((_, address)) = endpoint.split_once('/') else { return false };
    let address = address.split(['?', '#']).next().unwrap_or_default();
    if let Ok(socket) = address.parse::<SocketAddr>() {
        return is_loopback(socket.ip());
    }
    address.rsplit_once(':').is_some_and(|(host, _)| host.eq_ignore_ascii_case("localhost"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn endpoints_on_loopback() {
        for e in ["tcp/127.0.0.1:7447", "tcp/[::1]:0", "tcp/localhost:7447", "tls/127.0.0.2:1#iface=lo"] {
            assert!(endpoint_is_loopback(e), "{e}");
        }
        for e in ["tcp/0.0.0.0:7447", "tcp/[::]:7447", "tcp/192.168.1.4:7447", "tcp/host:1", "garbage"] {
            assert!(!endpoint_is_loopback(e), "{e}");
        }
    }

    #[test]
    fn the_defaults_listen_on_loopback_and_start() {
        assert_eq!(check(&Config::default()).unwrap(), Exposure::default());
    }

    #[test]
    fn anything_beyond_loopback_is_refused_unless_insecure_and_then_repeated() {
        let mut c = Config { grpc_addr: "0.0.0.0:50051".parse().unwrap(), ..Config::default() };
        let e = check(&c).unwrap_err().to_string();
        assert!(e.contains("gRPC listens on 0.0.0.0:50051 without TLS") && e.contains("--access"), "{e}");
        c.security.tls_cert = Some("c.pem".into());
        c.security.tls_key = Some("k.pem".into());
        let e = check(&c).unwrap_err().to_string();
        assert!(e.contains("without an access file (--access)"), "{e}");
        c.security.access = Some("access.toml".into());
        assert!(!check(&c).unwrap().insecure());
        c.zenoh.listen = vec!["tcp/0.0.0.0:7447".into()];
        c.zenoh.multicast_scouting = true;
        let e = check(&c).unwrap_err().to_string();
        assert!(e.contains("Zenoh listens on tcp/0.0.0.0:7447") && e.contains("multicast"), "{e}");
        c.zenoh.listen = vec!["tls/0.0.0.0:7447".into()];
        assert!(check(&c).is_err(), "mutual TLS is needed");
        c.security.tls_client_ca = Some("ca.pem".into());
        assert!(!check(&c).unwrap().insecure());
        c.zenoh.listen = vec!["tcp/0.0.0.0:7447".into()];
        c.security.insecure = true;
        assert_eq!(check(&c).unwrap().warnings.len(), 2);
        c.security.insecure = false;
        c.zenoh.multicast_scouting = false;
        c.zenoh.listen = Vec::new();
        assert!(check(&c).unwrap_err().to_string().contains("every interface"));
        c.zenoh.listen = vec!["tcp/127.0.0.1:7447".into()];
        c.zenoh.connect = vec!["tcp/10.1.2.3:7447".into()];
        assert!(check(&c).unwrap_err().to_string().contains("connects to tcp/10.1.2.3:7447"));
        c.zenoh.connect = vec!["tls/10.1.2.3:7447".into()];
        assert!(!check(&c).unwrap().insecure());
        c.security.insecure = true;
        c.zenoh.disabled = true;
        assert!(!check(&c).unwrap().insecure());
    }
}
