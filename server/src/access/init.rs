//! `dmp-server access init DIR`: a ready set for a secured cell, made with rcgen. A private CA, the server's
//! certificate (for `localhost`, `127.0.0.1`, `::1` and the hosts given), and for each identity a client
//! certificate (its common name is the identity's name) and a bearer token; the access file that names them.
//! Private keys and tokens are written with mode 0600. Nothing is overwritten.
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
    if options.cells.is_empty() {
        return Err(InitError::Name("give at least one cell (--cell NAME)".into()));
    }
    for (field, names) in [("cell", &options.cells), ("robot", &options.robots)] {
        for n in names {
            dmp_proto::keys::check_name(field, n).map_err(|e| InitError::Name(e.to_string()))?;
        }
    }
    std::fs::create_dir_all(dir).map_err(|source| InitError::Write { path: dir.to_owned(), source })?;
    let writer = Writer { dir };

    let ca_key = KeyPair::generate()?;
    let mut ca = CertificateParams::new(Vec::<String>::new())?;
    ca.is_ca = IsCa::Ca(BasicConstraints::Unconstrained);
    ca.distinguished_name.push(DnType::CommonName, "dmp cell CA");
    ca.key_usages =
        vec![KeyUsagePurpose::KeyCertSign, KeyUsagePurpose::CrlSign, KeyUsagePurpose::DigitalSignature];
    let ca_cert = ca.self_signed(&ca_key)?;
    writer.public("ca.pem", &ca_cert.pem())?;
    writer.secret("ca.key", &ca_key.serialize_pem())?;
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
    let mut identities = vec![
        (String::from("admin"), Role::Admin, vec!["*".to_owned()], Vec::new()),
        ("zenoh-router".into(), Role::Server, vec!["*".to_owned()], Vec::new()),
        // Primitives belong to robots, not cells: the planner and the observer get the robots given.
        ("planner".into(), Role::Planner, cells.clone(), options.robots.clone()),
        ("perception".into(), Role::Perception, cells.clone(), Vec::new()),
        ("observer".into(), Role::Observer, cells.clone(), options.robots.clone()),
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
    writer.public("zenoh-perception.json5", &zenoh_peer_config(dir, "perception", host))?;
    let access = crate::access::Access::from_file(&file).map_err(|e| InitError::Name(e.to_string()))?;
    let acl = super::zenoh_acl::access_control(&access);
    writer.public("zenoh-router.json5", &zenoh_router_config(dir, &acl))?;
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
fn zenoh_peer_config(dir: &Path, name: &str, host: &str) -> String {
    let d = dir.display();
    format!(
        "// A perception node of the cell (zenoh::Config::from_file, or `--zenoh-config` of the tools).\n\
         {{\n  mode: \"peer\",\n  connect: {{ endpoints: [\"tls/{host}:7447\"] }},\n  listen: {{ endpoints: [] }},\n  \
         scouting: {{ multicast: {{ enabled: false }}, gossip: {{ enabled: false }} }},\n  transport: {{ link: {{ tls: {{\n    \
         root_ca_certificate: \"{d}/ca.pem\",\n    connect_certificate: \"{d}/{name}.pem\",\n    \
         connect_private_key: \"{d}/{name}.key\",\n    enable_mtls: true,\n  }} }} }},\n}}\n"
    )
}

/// The Zenoh configuration of a router of the cell (zenohd -c): mutual TLS, its own certificate, and the access
/// control of the access file (so that it, too, takes from each peer only what its role may send).
fn zenoh_router_config(dir: &Path, acl: &serde_json::Value) -> String {
    let d = dir.display();
    let acl = serde_json::to_string_pretty(acl).unwrap_or_default().replace('\n', "\n  ");
    format!(
        "// A Zenoh router of the cell: zenohd -c zenoh-router.json5. Servers connect to it as its clients\n\
         // (dmp-server --zenoh-mode client --zenoh-connect tls/HOST:7447).\n\
         {{\n  mode: \"router\",\n  listen: {{ endpoints: [\"tls/0.0.0.0:7447\"] }},\n  \
         scouting: {{ multicast: {{ enabled: false }} }},\n  transport: {{ link: {{ tls: {{\n    \
         root_ca_certificate: \"{d}/ca.pem\",\n    listen_certificate: \"{d}/zenoh-router.pem\",\n    \
         listen_private_key: \"{d}/zenoh-router.key\",\n    connect_certificate: \"{d}/zenoh-router.pem\",\n    \
         connect_private_key: \"{d}/zenoh-router.key\",\n    enable_mtls: true,\n  }} }} }},\n  \
         // Generated from access.toml: regenerate the set (or edit both) when identities change.\n  \
         access_control: {acl},\n}}\n"
    )
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
        for secret in ["ca.key", "server.key", "panda-1.key", "panda-1.token"] {
            let mode = std::fs::metadata(dir.path().join(secret)).unwrap().permissions().mode();
            assert_eq!(mode & 0o777, 0o600, "{secret}");
        }
        // Nothing is written over.
        assert!(matches!(init(dir.path(), &options), Err(InitError::Exists(_))));
    }

    /// The DER of a one-certificate PEM.
    fn rustls_pki_der(pem: &str) -> Vec<u8> {
        let (_, pem) = x509_parser::pem::parse_x509_pem(pem.as_bytes()).unwrap();
        pem.contents
    }
}
