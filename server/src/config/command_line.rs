//! The server's command line: a TOML file (`--config`), then flags on top of it.

use std::net::SocketAddr;
use std::path::PathBuf;

use anyhow::Context;
use clap::Parser;

use crate::config::Config;

/// The DMP cell's server: primitives per robot, obstacle scenes over Zenoh, trajectories over gRPC.
///
/// Settings come from the defaults, then the `--config` file, then these flags. Logging follows `RUST_LOG`
/// (default `info`).
#[derive(Debug, Clone, Default, Parser)]
#[command(name = "dmp-server", version)]
pub struct Args {
    /// TOML configuration file (see `deploy/dmp-server.toml`); the flags below override it.
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Address of the gRPC server [default: 127.0.0.1:50051].
    #[arg(long, value_name = "ADDR")]
    pub grpc_addr: Option<SocketAddr>,
    /// Directory of the embedded store, created if missing [default: data].
    #[arg(long, value_name = "DIR")]
    pub data_dir: Option<PathBuf>,
    /// The robot cell: Zenoh keys are `dmp/<cell>/...` [default: default].
    #[arg(long, value_name = "NAME")]
    pub cell: Option<String>,
    /// The cells this server serves, e.g. `a,b` (replaces the file's list); a request for another cell is
    /// refused [default: any cell].
    #[arg(long, value_name = "NAMES", value_delimiter = ',')]
    pub cells: Vec<String>,
    /// This server's id in a plant of servers on one Zenoh network: discovery, replicated primitives [default:
    /// none, a lone server].
    #[arg(long, value_name = "ID")]
    pub server_id: Option<String>,
    /// The gRPC address the plant is told to reach this server at [default: the bound address].
    #[arg(long, value_name = "URL")]
    pub advertise_addr: Option<String>,
    /// A cell and the cells whose robots its robots also avoid, e.g. `a=b,c` (repeatable; replaces the file's
    /// entry of that cell).
    #[arg(long = "neighbours", value_name = "CELL=CELLS")]
    pub neighbours: Vec<String>,
    /// Address of the Prometheus endpoint (`GET /metrics`, plain HTTP, no authentication), e.g. `0.0.0.0:9464`;
    /// port 0 picks a free port [default: off].
    #[arg(long, value_name = "ADDR")]
    pub metrics_addr: Option<SocketAddr>,
    /// The OpenTelemetry collector (OTLP over gRPC) the tracing spans go to, e.g. `http://collector:4317`
    /// [default: off].
    #[arg(long, value_name = "URL")]
    pub otlp_endpoint: Option<String>,
    /// Zenoh mode: an embedded `peer`, or a `client` of a router [default: peer].
    #[arg(long, value_name = "MODE", value_parser = ["peer", "client"])]
    pub zenoh_mode: Option<String>,
    /// Zenoh endpoint to listen on, e.g. `tcp/0.0.0.0:7447` (repeatable; replaces the file's list).
    #[arg(long, value_name = "ENDPOINT")]
    pub zenoh_listen: Vec<String>,
    /// Zenoh endpoint (router or peer) to connect to (repeatable; replaces the file's list).
    #[arg(long, value_name = "ENDPOINT")]
    pub zenoh_connect: Vec<String>,
    /// Turn Zenoh's multicast scouting off (the default: peers are found only through the connect endpoints).
    #[arg(long, conflicts_with = "zenoh_multicast")]
    pub zenoh_no_multicast: bool,
    /// Turn Zenoh's multicast scouting on (any peer on the LAN can join: needs `--insecure`).
    #[arg(long)]
    pub zenoh_multicast: bool,
    /// The access file: identities (token digests, certificate common names), roles, cells and robots. Reloaded on
    /// SIGHUP.
    #[arg(long, value_name = "FILE")]
    pub access: Option<PathBuf>,
    /// The server's TLS certificate chain (PEM); with `--tls-key`, gRPC is served over TLS.
    #[arg(long, value_name = "FILE", requires = "tls_key")]
    pub tls_cert: Option<PathBuf>,
    /// The server's TLS private key (PEM).
    #[arg(long, value_name = "FILE", requires = "tls_cert")]
    pub tls_key: Option<PathBuf>,
    /// The CA of client certificates (PEM): mutual TLS, a certificate's common name names an identity.
    #[arg(long, value_name = "FILE", requires = "tls_cert")]
    pub tls_client_ca: Option<PathBuf>,
    /// Listen beyond loopback without TLS or an access file: anyone who reaches the server can steer every robot.
    /// Repeated in the log and in GetInfo.
    #[arg(long)]
    pub insecure: bool,
    /// A stock Zenoh configuration file (JSON5) to start from; the settings of dmp-server apply on top, and its own
    /// `access_control` replaces the generated one.
    #[arg(long, value_name = "FILE")]
    pub zenoh_config: Option<PathBuf>,
    /// Take ROS 2 topics over rmw_zenoh in this ROS domain (`ROS_DOMAIN_ID`): MoveIt's `/collision_object` and the
    /// topics of the file's `[ros2]` section [default: off].
    #[arg(long, value_name = "N")]
    pub ros2_domain: Option<u32>,
    /// Run without Zenoh (gRPC only).
    #[arg(long)]
    pub no_zenoh: bool,
    /// Print the effective configuration as TOML and exit.
    #[arg(long)]
    pub print_config: bool,
    /// Something else than serving.
    #[command(subcommand)]
    pub command: Option<Command>,
}

/// What `dmp-server` does instead of serving.
#[derive(Debug, Clone, clap::Subcommand)]
pub enum Command {
    /// Identities and certificates.
    #[command(subcommand)]
    Access(AccessCommand),
}

/// `dmp-server access ...`
#[derive(Debug, Clone, clap::Subcommand)]
pub enum AccessCommand {
    /// Write a ready set into DIR: a private CA, the server's certificate, a certificate and a token per identity
    /// (admin, planner, perception, observer, and one per --robot), and the access file. Keys and tokens are
    /// written with mode 0600; nothing is overwritten.
    Init {
        /// The directory (created if missing; must not hold a set already).
        dir: PathBuf,
        /// A cell of the planner, perception, observer and robot identities (repeatable, at least one).
        #[arg(long = "cell", value_name = "NAME", required = true)]
        cells: Vec<String>,
        /// A robot id: one robot identity, acting only as itself (repeatable).
        #[arg(long = "robot", value_name = "ID")]
        robots: Vec<String>,
        /// A host name or address the server is reached at, besides loopback (repeatable).
        #[arg(long = "host", value_name = "NAME")]
        hosts: Vec<String>,
        /// The port of the server's Zenoh endpoint, in the Zenoh configurations written and the command printed.
        #[arg(long = "zenoh-port", value_name = "PORT", default_value_t = crate::access::init::DEFAULT_ZENOH_PORT)]
        zenoh_port: u16,
        /// A robot id prefix (e.g. `sim.`): the planner and the observer get every robot whose id starts with it
        /// (repeatable).
        #[arg(long = "robot-prefix", value_name = "PREFIX")]
        robot_prefixes: Vec<String>,
    },
}

/// The effective configuration: the defaults, then the file of `--config`, then the flags.
pub fn load_config(args: &Args) -> anyhow::Result<Config> {
    let mut config = match &args.config {
        None => Config::default(),
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("cannot read the configuration file {}", path.display()))?;
            toml::from_str(&text).with_context(|| format!("invalid configuration file {}", path.display()))?
        }
    };
    if let Some(addr) = args.grpc_addr {
        config.grpc_addr = addr;
    }
    if let Some(dir) = &args.data_dir {
        config.data_dir = dir.clone();
    }
    if let Some(cell) = &args.cell {
        config.cell = cell.clone();
    }
    if args.metrics_addr.is_some() {
        config.metrics_addr = args.metrics_addr;
    }
    if args.otlp_endpoint.is_some() {
        config.otlp_endpoint.clone_from(&args.otlp_endpoint);
    }
    dmp_proto::keys::check_name("cell", &config.cell).map_err(|e| anyhow::anyhow!("{e}"))?;
    if !args.cells.is_empty() {
        config.cells = args.cells.clone();
    }
    if args.server_id.is_some() {
        config.plant.server_id.clone_from(&args.server_id);
    }
    if args.advertise_addr.is_some() {
        config.plant.advertise_addr.clone_from(&args.advertise_addr);
    }
    for n in &args.neighbours {
        let (cell, others) = n
            .split_once('=')
            .ok_or_else(|| anyhow::anyhow!("--neighbours: `{n}` is not CELL=CELLS (e.g. a=b,c)"))?;
        let others = others.split(',').filter(|o| !o.is_empty()).map(str::to_owned).collect();
        config.plant.neighbours.insert(cell.to_owned(), others);
    }
    config.check_plant().map_err(|e| anyhow::anyhow!("{e}"))?;
    if let Some(mode) = &args.zenoh_mode {
        config.zenoh.mode = mode.clone();
    }
    if !args.zenoh_listen.is_empty() {
        config.zenoh.listen = args.zenoh_listen.clone();
    }
    if !args.zenoh_connect.is_empty() {
        config.zenoh.connect = args.zenoh_connect.clone();
    }
    if args.zenoh_no_multicast {
        config.zenoh.multicast_scouting = false;
    }
    if args.zenoh_multicast {
        config.zenoh.multicast_scouting = true;
    }
    if args.zenoh_config.is_some() {
        config.zenoh.config_file.clone_from(&args.zenoh_config);
    }
    let security = &mut config.security;
    for (flag, value) in [
        (&mut security.access, &args.access),
        (&mut security.tls_cert, &args.tls_cert),
        (&mut security.tls_key, &args.tls_key),
        (&mut security.tls_client_ca, &args.tls_client_ca),
    ] {
        if value.is_some() {
            flag.clone_from(value);
        }
    }
    if args.insecure {
        security.insecure = true;
    }
    if args.no_zenoh {
        config.zenoh.disabled = true;
    }
    if args.ros2_domain.is_some() {
        config.ros2.domain = args.ros2_domain;
    }
    config.ros2.check().map_err(|e| anyhow::anyhow!("{e}"))?;
    config.defaults.check().map_err(|e| anyhow::anyhow!("{e}"))?;
    Ok(config)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(flags: &[&str]) -> Args {
        Args::try_parse_from(std::iter::once("dmp-server").chain(flags.iter().copied())).unwrap()
    }

    #[test]
    fn no_file_and_no_flags_give_the_defaults() {
        assert_eq!(load_config(&args(&[])).unwrap(), Config::default());
    }

    #[test]
    fn the_file_then_the_flags() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("server.toml");
        std::fs::write(
            &file,
            r#"
grpc_addr = "0.0.0.0:6000"
data_dir = "/var/lib/dmp"
cell = "cell-a"
metrics_addr = "0.0.0.0:9464"

[zenoh]
mode = "client"
connect = ["tcp/10.0.0.1:7447", "tcp/10.0.0.2:7447"]
listen = ["tcp/0.0.0.0:7447"]
multicast_scouting = true

[limits]
max_streams = 10
"#,
        )
        .unwrap();
        let path = file.to_str().unwrap();

        let from_file = load_config(&args(&["--config", path])).unwrap();
        assert_eq!(from_file.grpc_addr, "0.0.0.0:6000".parse().unwrap());
        assert_eq!(from_file.data_dir, PathBuf::from("/var/lib/dmp"));
        assert_eq!(from_file.cell, "cell-a");
        assert_eq!(from_file.zenoh.mode, "client");
        assert_eq!(from_file.zenoh.connect, ["tcp/10.0.0.1:7447", "tcp/10.0.0.2:7447"]);
        assert!(from_file.zenoh.multicast_scouting && !from_file.zenoh.disabled);
        assert_eq!(from_file.limits.max_streams, 10);
        assert_eq!(
            from_file.limits.max_samples,
            Config::default().limits.max_samples,
            "unset keys keep defaults"
        );

        let merged = load_config(&args(&[
            "--config",
            path,
            "--grpc-addr",
            "127.0.0.1:7000",
            "--cell",
            "cell-b",
            "--metrics-addr",
            "127.0.0.1:9464",
            "--zenoh-mode",
            "peer",
            "--zenoh-connect",
            "tcp/127.0.0.1:1",
            "--zenoh-connect",
            "tcp/127.0.0.1:2",
            "--zenoh-no-multicast",
            "--no-zenoh",
        ]))
        .unwrap();
        assert_eq!(merged.grpc_addr, "127.0.0.1:7000".parse().unwrap());
        assert_eq!(merged.cell, "cell-b");
        assert_eq!(merged.metrics_addr, Some("127.0.0.1:9464".parse().unwrap()));
        assert_eq!(from_file.metrics_addr, Some("0.0.0.0:9464".parse().unwrap()));
        assert_eq!(merged.zenoh.mode, "peer");
        assert_eq!(merged.zenoh.connect, ["tcp/127.0.0.1:1", "tcp/127.0.0.1:2"], "flags replace the list");
        assert_eq!(merged.zenoh.listen, ["tcp/0.0.0.0:7447"], "an unset flag keeps the file's value");
        assert_eq!(merged.data_dir, PathBuf::from("/var/lib/dmp"));
        assert!(!merged.zenoh.multicast_scouting && merged.zenoh.disabled);
        assert_eq!(merged.limits.max_streams, 10);
    }

    #[test]
    fn bad_files_and_flags_are_refused_clearly() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("bad.toml");
        std::fs::write(&file, "grpc_adr = \"0.0.0.0:1\"\n").unwrap();
        let e = load_config(&args(&["--config", file.to_str().unwrap()])).unwrap_err();
        let msg = format!("{e:#}");
        assert!(msg.contains("bad.toml") && msg.contains("grpc_adr"), "{msg}");

        let e = load_config(&args(&["--config", "/nonexistent/dmp.toml"])).unwrap_err();
        assert!(format!("{e:#}").contains("cannot read"), "{e:#}");

        let e = load_config(&args(&["--cell", "a/b"])).unwrap_err();
        assert!(e.to_string().starts_with("cell:"), "{e}");

        assert!(Args::try_parse_from(["dmp-server", "--zenoh-mode", "router"]).is_err());
        assert!(Args::try_parse_from(["dmp-server", "--grpc-addr", "nowhere"]).is_err());
    }

    #[test]
    fn the_default_profile_is_read_and_a_bad_field_is_refused_by_its_key() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("server.toml");
        let load = |text: &str| {
            std::fs::write(&file, text).unwrap();
            load_config(&args(&["--config", file.to_str().unwrap()]))
        };
        let c = load("[defaults]\nmargin_m = -1.0\n[defaults.limits]\nmax_speed = 0.5\nmax_jerk = -1.0\n")
            .unwrap();
        assert_eq!((c.defaults.limits.max_speed, c.defaults.limits.max_jerk), (0.5, -1.0));
        assert_eq!(c.defaults.limits.max_acceleration, 5.0, "unset keys keep the defaults");
        assert_eq!(c.defaults.margin_m, -1.0);
        for (text, key) in [
            ("[defaults.limits]\nmax_angular_speed = 0.0\n", "defaults.limits.max_angular_speed:"),
            ("[defaults.limits]\nmax_jerk = nan\n", "defaults.limits.max_jerk:"),
            ("[defaults.limits]\nmax_acceleration = inf\n", "defaults.limits.max_acceleration:"),
            ("[defaults]\nmargin_m = 0.0\n", "defaults.margin_m:"),
        ] {
            let e = format!("{:#}", load(text).unwrap_err());
            assert!(e.starts_with(key), "{text}: {e}");
        }
        let e = format!("{:#}", load("[defaults.limits]\nmax_sped = 1.0\n").unwrap_err());
        assert!(e.contains("max_sped"), "{e}");
    }

    /// Every key path of a TOML document, e.g. `zenoh.listen`.
    fn keys(v: &toml::Value, prefix: &str, out: &mut Vec<String>) {
        if let toml::Value::Table(t) = v {
            for (k, v) in t {
                let path = if prefix.is_empty() { k.clone() } else { format!("{prefix}.{k}") };
                keys(v, &path, out);
                out.push(path);
            }
        }
    }

    #[test]
    fn the_example_configuration_has_every_key_and_loads() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../deploy/dmp-server.toml");
        let config = load_config(&args(&["--config", path])).unwrap();
        assert_eq!(config.data_dir, PathBuf::from("/var/lib/dmp-server"));
        assert_eq!(Config { data_dir: Config::default().data_dir, ..config }, Config::default());
        let (mut documented, mut all) = (Vec::new(), Vec::new());
        keys(&toml::from_str(&std::fs::read_to_string(path).unwrap()).unwrap(), "", &mut documented);
        keys(&toml::Value::try_from(Config::default()).unwrap(), "", &mut all);
        documented.sort();
        all.sort();
        assert_eq!(documented, all, "deploy/dmp-server.toml must list every key of Config");
        // The keys without a default are listed commented out (`#   key = ...`).
        let text = std::fs::read_to_string(path).unwrap();
        let mut optional = Config {
            metrics_addr: Some("127.0.0.1:9464".parse().unwrap()),
            otlp_endpoint: Some("http://collector:4317".into()),
            ..Config::default()
        };
        let set = Some(PathBuf::from("/x"));
        let security = &mut optional.security;
        (security.access, security.tls_cert, security.tls_key, security.tls_client_ca) =
            (set.clone(), set.clone(), set.clone(), set);
        let mut every = Vec::new();
        keys(&toml::Value::try_from(&optional).unwrap(), "", &mut every);
        for key in every.iter().filter(|k| !all.contains(k)) {
            let last = key.rsplit('.').next().unwrap();
            assert!(text.contains(&format!("#   {last} = ")), "deploy/dmp-server.toml must list `{key}`");
        }
    }

    #[test]
    fn the_default_configuration_round_trips_through_toml() {
        let text = toml::to_string_pretty(&Config::default()).unwrap();
        assert_eq!(toml::from_str::<Config>(&text).unwrap(), Config::default());
    }
}
