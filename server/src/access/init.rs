//! `dmp-server access init DIR`: a ready set for a secured cell, made with rcgen. A private CA, the server's
//! certificate (for `localhost`, `127.0.0.1`, `::1` and the hosts given), and for each identity a client
//! certificate (its common name is the identity's name) and a bearer token; the access file that names them.
//! Private keys and tokens are written with mode 0600. The CA's key goes apart, into `DIR/private/` (mode 0700): it
//! signs new certificates and is never handed out, while the rest of `DIR` is handed out file by file. Nothing is
//! overwritten.
//!
//! The identities: `admin` (every cell), `planner`, `perception` and `observer` (the cells given), one `robot`
//! identity per robot id given, acting only as itself, and two of role `server` known by their certificates only:
//! `dmp-server` (the server's own certificate) and `zenoh-router`. With them, the Zenoh configurations of a
//! perception node and of a router of the cell.

use std::io::Write;
use std::path::{Path, PathBuf};

use rcgen::{
    BasicConstraints, CertificateParams, DnType, ExtendedKeyUsagePurpose, IsCa, Issuer, KeyPair,
    KeyUsagePurpose,
};
use thiserror::Error;

use super::credential;
use super::file::{AccessFile, IdentityEntry};
use super::role::Role;

/// Why the set could not be written.
#[derive(Debug, Error)]
pub enum InitError {
    /// A file exists already.
    #[error("{0} exists already: nothing was written over (use an empty directory)")]
    Exists(PathBuf),
    /// Writing failed.
    #[error("cannot write {path}: {source}")]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A certificate could not be made.
    #[error("cannot make a certificate: {0}")]
    Certificate(#[from] rcgen::Error),
    /// A name is not acceptable.
    #[error("{0}")]
    Name(String),
    /// No randomness.
    #[error("no randomness for the tokens: {0}")]
    Random(String),
}

/// What to make.
#[derive(Debug, Clone, Default)]
pub struct InitOptions {
    /// The cells of the planner, perception, observer and robot identities.
    pub cells: Vec<String>,
    /// One robot identity per id.
    pub robots: Vec<String>,
    /// Host names or addresses the server is reached at, besides loopback.
    pub hosts: Vec<String>,
}

/// The Zenoh port of the set's endpoints when none is given: Zenoh's own default.
pub const DEFAULT_ZENOH_PORT: u16 = 7447;

/// Where the CA's private key is written, relative to the set's directory.
pub const CA_KEY: &str = "private/ca.key";

/// More of what to make, beyond [`InitOptions`].
#[derive(Debug, Clone, Default)]
pub struct InitExtras {
    /// The port of the server's (and a router's) Zenoh endpoint in the Zenoh configurations written, and in the
    /// command line printed; `None` is [`DEFAULT_ZENOH_PORT`].
    pub zenoh_port: Option<u16>,
    /// Robot id prefixes (`sim.`): the planner and the observer get every robot whose id starts with one, written as
    /// `sim.*` in the access file.
    pub robot_prefixes: Vec<String>,
}

impl InitExtras {
    /// The Zenoh port in force.
    pub fn zenoh_port(&self) -> u16 {
        self.zenoh_port.unwrap_or(DEFAULT_ZENOH_PORT)
    }
}

/// What was made: the identities, each with its token (to hand over; only its digest is in the access file).
#[derive(Debug, Clone)]
pub struct InitSet {
    /// The directory.
    pub dir: PathBuf,
    /// Each identity's name and token.
    pub tokens: Vec<(String, String)>,
}

/// Writes the set into `dir` (created if missing).
pub fn init(dir: &Path, options: &InitOptions) -> Result<InitSet, InitError> {
    init_with(dir, options, &InitExtras::default())
}

/// Writes the set into `dir` (created if missing), with the Zenoh port and robot prefixes of `extras`.
pub fn init_with(dir: &Path, options: &InitOptions, extras: &InitExtras) -> Result<InitSet, InitError> {
    if options.cells.is_empty() {
        return Err(InitError::Name("give at least one cell (--cell NAME)".into()));
    }
    for (field, names) in [("cell", &options.cells), ("robot", &options.robots)] {
        for n in names {
            dmp_proto::keys::check_name(field, n).map_err(|e| InitError::Name(e.to_string()))?;
        }
    }
    for prefix in &extras.robot_prefixes {
        dmp_proto::keys::check_name("robot prefix", prefix).map_err(|e| InitError::Name(e.to_string()))?;
    }
    if extras.zenoh_port == Some(0) {
        return Err(InitError::Name("--zenoh-port: give a port, 1 to 65535".into()));
    }
    std::fs::create_dir_all(dir).map_err(|source| InitError::Write { path: dir.to_owned(), source })?;
    let private = dir.join("private");
    {
        use std::os::unix::fs::DirBuilderExt;
        std::fs::DirBuilder::new().mode(0o700).create(&private).map_err(|source| match source.kind() {
            std::io::ErrorKind::AlreadyExists => InitError::Exists(private.clone()),
            _ => InitError::Write { path: private.clone(), source },
        })?;
    }
    let writer = Writer { dir };

    let ca_key = KeyPair::generate()?;
    let mut ca = CertificateParams::new(Vec::<String>::new())?;
    ca.is_ca = IsCa::Ca(BasicConstraints::Unconstrained);
    ca.distinguished_name.push(DnType::CommonName, "dmp cell CA");
    ca.key_usages =
        vec![KeyUsagePurpose::KeyCertSign, KeyUsagePurpose::CrlSign, KeyUsagePurpose::DigitalSignature];
    let ca_cert = ca.self_signed(&ca_key)?;
    writer.public("ca.pem", &ca_cert.pem())?;
    writer.secret(CA_KEY, &ca_key.serialize_pem())?;
    let issuer = Issuer::new(ca, ca_key);

    let mut server_names = vec!["localhost".to_owned(), "127.0.0.1".to_owned(), "::1".to_owned()];
    server_names.extend(options.hosts.iter().cloned());
    let server_key = KeyPair::generate()?;
    let mut server = CertificateParams::new(server_names.clone())?;
    server.distinguished_name.push(DnType::CommonName, SERVER_NAME);
    // A server also connects out over Zenoh (to routers and other servers) with this certificate.
    server.extended_key_usages =
        vec![ExtendedKeyUsagePurpose::ServerAuth, ExtendedKeyUsagePurpose::ClientAuth];
    writer.public("server.pem", &server.signed_by(&server_key, &issuer)?.pem())?;
    writer.secret("server.key", &server_key.serialize_pem())?;

    let cells = options.cells.clone();
    // The robots given, and every robot of each prefix (`sim.*`).
    let granted: Vec<String> = options
        .robots
        .iter()
        .cloned()
        .chain(extras.robot_prefixes.iter().map(|p| format!("{p}{}", super::role::PREFIX_WILDCARD)))
        .collect();
    let mut identities = vec![
        (String::from("admin"), Role::Admin, vec!["*".to_owned()], Vec::new()),
        ("zenoh-router".into(), Role::Server, vec!["*".to_owned()], Vec::new()),
        // Primitives belong to robots, not cells: the planner and the observer get the robots given.
        ("planner".into(), Role::Planner, cells.clone(), granted.clone()),
        ("perception".into(), Role::Perception, cells.clone(), Vec::new()),
        ("observer".into(), Role::Observer, cells.clone(), granted),
    ];
    for robot in &options.robots {
        if identities.iter().any(|(n, ..)| n == robot) {
            return Err(InitError::Name(format!("robot `{robot}` has the name of another identity")));
        }
        identities.push((robot.clone(), Role::Robot, cells.clone(), vec![robot.clone()]));
    }
    let mut file = AccessFile::default();
    let mut tokens = Vec::new();
    for (name, role, cells, robots) in identities {
        let key = KeyPair::generate()?;
        // A router also serves TLS: the server's names, both usages.
        let (names, usages) = if role == Role::Server {
            (
                server_names.clone(),
                vec![ExtendedKeyUsagePurpose::ServerAuth, ExtendedKeyUsagePurpose::ClientAuth],
            )
        } else {
            (Vec::new(), vec![ExtendedKeyUsagePurpose::ClientAuth])
        };
        let mut params = CertificateParams::new(names)?;
        params.distinguished_name.push(DnType::CommonName, name.clone());
        params.extended_key_usages = usages;
        writer.public(&format!("{name}.pem"), &params.signed_by(&key, &issuer)?.pem())?;
        writer.secret(&format!("{name}.key"), &key.serialize_pem())?;
        let token = new_token()?;
        writer.secret(&format!("{name}.token"), &format!("{token}\n"))?;
        file.identity.push(IdentityEntry {
            name: name.clone(),
            role,
            cells,
            robots,
            token_sha256: Some(credential::digest_hex(&token)),
            cert_common_name: Some(name.clone()),
        });
        tokens.push((name, token));
    }
    // The server's own certificate names it to the other servers and routers of the plant.
    file.identity.push(IdentityEntry {
        name: SERVER_NAME.into(),
        role: Role::Server,
        cells: vec!["*".into()],
        robots: Vec::new(),
        token_sha256: None,
        cert_common_name: Some(SERVER_NAME.into()),
    });
    let host = options.hosts.first().map_or("127.0.0.1", String::as_str);
    let port = extras.zenoh_port();
    writer.public("zenoh-perception.json5", &zenoh_peer_config(dir, "perception", host, port))?;
    let access = crate::access::Access::from_file(&file).map_err(|e| InitError::Name(e.to_string()))?;
    let acl = super::zenoh_acl::access_control(&access);
    writer.public("zenoh-router.json5", &zenoh_router_config(dir, &acl, port))?;
    let text = toml::to_string_pretty(&file).map_err(|e| InitError::Name(e.to_string()))?;
    writer.public(
        "access.toml",
        &format!(
            "# The identities of the cell (dmp-server --access access.toml). Tokens are stored as their SHA-256\n\
             # digests (`printf %s TOKEN | sha256sum`); a certificate's common name names an identity too.\n\
             # Roles: planner, robot, perception, observer, admin. cells = [\"*\"] is every cell.\n\n{text}"
        ),
    )?;
    Ok(InitSet { dir: dir.to_owned(), tokens })
}

/// The common name of the server's certificate (an identity of role `server`).
pub(crate) const SERVER_NAME: &str = "dmp-server";

/// The Zenoh configuration of a perception node of `name` connecting to the server at `host` over mutual TLS.
fn zenoh_peer_config(dir: &Path, name: &str, host: &str, port: u16) -> String {
    let d = dir.display();
    format!(
        "// A perception node of the cell (zenoh::Config::from_file, or `--zenoh-config` of the tools).\n\
         {{\n  mode: \"peer\",\n  connect: {{ endpoints: [\"tls/{host}:{port}\"] }},\n  listen: {{ endpoints: [] }},\n  \
         scouting: {{ multicast: {{ enabled: false }}, gossip: {{ enabled: false }} }},\n  transport: {{ link: {{ tls: {{\n    \
         root_ca_certificate: \"{d}/ca.pem\",\n    connect_certificate: \"{d}/{name}.pem\",\n    \
         connect_private_key: \"{d}/{name}.key\",\n    enable_mtls: true,\n  }} }} }},\n}}\n"
    )
}

/// The Zenoh configuration of a router of the cell (zenohd -c): mutual TLS, its own certificate, and the access
/// control of the access file (so that it, too, takes from each peer only what its role may send).
fn zenoh_router_config(dir: &Path, acl: &serde_json::Value, port: u16) -> String {
    let d = dir.display();
    let acl = serde_json::to_string_pretty(acl).unwrap_or_default().replace('\n', "\n  ");
    format!(
        "// A Zenoh router of the cell: zenohd -c zenoh-router.json5. Servers connect to it as its clients\n\
         // (dmp-server --zenoh-mode client --zenoh-connect tls/HOST:{port}).\n\
         {{\n  mode: \"router\",\n  listen: {{ endpoints: [\"tls/0.0.0.0:{port}\"] }},\n  \
         scouting: {{ multicast: {{ enabled: false }} }},\n  transport: {{ link: {{ tls: {{\n    \
         root_ca_certificate: \"{d}/ca.pem\",\n    listen_certificate: \"{d}/zenoh-router.pem\",\n    \
         listen_private_key: \"{d}/zenoh-router.key\",\n    connect_certificate: \"{d}/zenoh-router.pem\",\n    \
         connect_private_key: \"{d}/zenoh-router.key\",\n    enable_mtls: true,\n  }} }} }},\n  \
         // Generated from access.toml: regenerate the set (or edit both) when identities change.\n  \
         access_control: {acl},\n}}\n"
    )
}

/// The advertised Zenoh locators (`tls/192.0.2.2:7447`) whose host the server's certificate (PEM) does not name:
/// a client that connects there fails the TLS handshake. Only `tls/` and `quic/` locators are checked. An error
/// when the certificate cannot be read.
pub fn uncovered_locators(cert_pem: &[u8], locators: &[String]) -> Result<Vec<String>, String> {
    use x509_parser::extensions::GeneralName;
    let (_, pem) = x509_parser::pem::parse_x509_pem(cert_pem).map_err(|e| e.to_string())?;
    let cert = pem.parse_x509().map_err(|e| e.to_string())?;
    let mut names: Vec<String> = Vec::new();
    let mut ips: Vec<std::net::IpAddr> = Vec::new();
    if let Ok(Some(san)) = cert.subject_alternative_name() {
        for name in &san.value.general_names {
            match name {
                GeneralName::DNSName(n) => names.push(n.to_ascii_lowercase()),
                GeneralName::IPAddress(b) => match b.len() {
                    4 => ips.push(std::net::IpAddr::from(<[u8; 4]>::try_from(*b).unwrap_or_default())),
                    16 => ips.push(std::net::IpAddr::from(<[u8; 16]>::try_from(*b).unwrap_or_default())),
                    _ => {}
                },
                _ => {}
            }
        }
    }
    let covered =
        |host: &str| match host.trim_start_matches('[').trim_end_matches(']').parse::<std::net::IpAddr>() {
            Ok(ip) => ips.contains(&ip),
            Err(_) => {
                let host = host.to_ascii_lowercase();
                names.iter().any(|n| match n.strip_prefix("*.") {
                    Some(domain) => host.split_once('.').is_some_and(|(_, rest)| rest == domain),
                    None => *n == host,
                })
            }
        };
    Ok(locators
        .iter()
        .filter(|l| {
            let Some(rest) = l.strip_prefix("tls/").or_else(|| l.strip_prefix("quic/")) else { return false };
            let address = rest.split(['#', '?']).next().unwrap_or(rest);
            let host = address.rsplit_once(':').map_or(address, |(h, _)| h);
            !covered(host)
        })
        .cloned()
        .collect())
}

/// A bearer token: 32 random bytes, hex.
fn new_token() -> Result<String, InitError> {
    let mut bytes = [0u8; 32];
    getrandom::fill(&mut bytes).map_err(|e| InitError::Random(e.to_string()))?;
    Ok(hex::encode(bytes))
}

struct Writer<'a> {
    dir: &'a Path,
}

impl Writer<'_> {
    fn public(&self, name: &str, text: &str) -> Result<(), InitError> {
        self.write(name, text, 0o644)
    }

    fn secret(&self, name: &str, text: &str) -> Result<(), InitError> {
        self.write(name, text, 0o600)
    }

    fn write(&self, name: &str, text: &str, mode: u32) -> Result<(), InitError> {
        use std::os::unix::fs::OpenOptionsExt;
        let path = self.dir.join(name);
        let mut file =
            std::fs::OpenOptions::new().write(true).create_new(true).mode(mode).open(&path).map_err(
                |source| match source.kind() {
                    std::io::ErrorKind::AlreadyExists => InitError::Exists(path.clone()),
                    _ => InitError::Write { path: path.clone(), source },
                },
            )?;
        file.write_all(text.as_bytes()).map_err(|source| InitError::Write { path, source })
    }
}

#[cfg(test)]
mod tests {
    use std::os::unix::fs::PermissionsExt;

    use super::*;
    use crate::access::Access;

    #[test]
    fn a_set_loads_and_its_secrets_are_private() {
        let dir = tempfile::tempdir().unwrap();
        let options = InitOptions {
            cells: vec!["cell-a".into()],
            robots: vec!["panda-1".into()],
            hosts: vec!["cell-a".into()],
        };
        let set = init(dir.path(), &options).unwrap();
        let access = Access::load(&dir.path().join("access.toml")).unwrap();
        assert_eq!(access.identities().len(), 7);
        for file in ["zenoh-perception.json5", "zenoh-router.json5"] {
            zenoh::Config::from_file(dir.path().join(file)).unwrap();
        }
        for (name, token) in &set.tokens {
            let found = access.by_token(&credential::digest(token)).unwrap();
            assert_eq!(&found.name, name);
            let pem = std::fs::read_to_string(dir.path().join(format!("{name}.pem"))).unwrap();
            let der = rustls_pki_der(&pem);
            assert_eq!(credential::common_name(&der).as_deref(), Some(name.as_str()));
        }
        assert_eq!(access.by_common_name("panda-1").unwrap().scope.robots, ["panda-1"]);
        for secret in [CA_KEY, "server.key", "panda-1.key", "panda-1.token"] {
            let mode = std::fs::metadata(dir.path().join(secret)).unwrap().permissions().mode();
            assert_eq!(mode & 0o777, 0o600, "{secret}");
        }
        // The CA's key is apart from the files handed out.
        assert!(!dir.path().join("ca.key").exists());
        let mode = std::fs::metadata(dir.path().join("private")).unwrap().permissions().mode();
        assert_eq!(mode & 0o777, 0o700);
        // Nothing is written over.
        assert!(matches!(init(dir.path(), &options), Err(InitError::Exists(_))));
    }

    #[test]
    fn the_zenoh_port_and_robot_prefixes_reach_the_files() {
        let dir = tempfile::tempdir().unwrap();
        let options =
            InitOptions { cells: vec!["cell-a".into()], hosts: vec!["cell-a".into()], ..Default::default() };
        let extras = InitExtras { zenoh_port: Some(17447), robot_prefixes: vec!["sim.".into()] };
        init_with(dir.path(), &options, &extras).unwrap();
        let peer = std::fs::read_to_string(dir.path().join("zenoh-perception.json5")).unwrap();
        assert!(peer.contains("tls/cell-a:17447") && !peer.contains(":7447"), "{peer}");
        let router = std::fs::read_to_string(dir.path().join("zenoh-router.json5")).unwrap();
        assert!(router.contains("tls/0.0.0.0:17447"), "{router}");
        zenoh::Config::from_file(dir.path().join("zenoh-router.json5")).unwrap();
        let access = Access::load(&dir.path().join("access.toml")).unwrap();
        assert_eq!(access.by_common_name("planner").unwrap().scope.robots, ["sim.*"]);
        let bad = InitExtras { robot_prefixes: vec!["sim/".into()], ..Default::default() };
        assert!(init_with(tempfile::tempdir().unwrap().path(), &options, &bad).is_err());
    }

    #[test]
    fn advertised_locators_outside_the_certificate_are_named() {
        let dir = tempfile::tempdir().unwrap();
        let options = InitOptions {
            cells: vec!["a".into()],
            hosts: vec!["cell-a.lab".into(), "10.0.0.5".into()],
            ..Default::default()
        };
        init(dir.path(), &options).unwrap();
        let pem = std::fs::read(dir.path().join("server.pem")).unwrap();
        let locators: Vec<String> = [
            "tls/127.0.0.1:7447",
            "tls/10.0.0.5:7447",
            "tls/[::1]:7447",
            "tls/cell-a.lab:7447",
            "tls/192.0.2.2:7447",
            "tcp/192.0.2.2:7448",
            "tls/other.lab:7447",
        ]
        .map(String::from)
        .to_vec();
        assert_eq!(
            uncovered_locators(&pem, &locators).unwrap(),
            ["tls/192.0.2.2:7447", "tls/other.lab:7447"]
        );
        assert!(uncovered_locators(b"not a certificate", &locators).is_err());
    }

    /// The DER of a one-certificate PEM.
    fn rustls_pki_der(pem: &str) -> Vec<u8> {
        let (_, pem) = x509_parser::pem::parse_x509_pem(pem.as_bytes()).unwrap();
        pem.contents
    }
}
