//! What deploy/Dockerfile says: the ports it exposes, its volume, the binaries it installs, its default command.

use std::collections::BTreeSet;

use crate::{SET_DIR, deploy, dmp_server_args, flag_values, port_of, read, set_files, set_paths_in};

/// The facts of deploy/Dockerfile the other files must agree with.
#[derive(Debug)]
pub struct Dockerfile {
    /// EXPOSE.
    pub exposed: BTreeSet<u16>,
    /// VOLUME (one).
    pub volume: String,
    /// What the runtime image has in /usr/local/bin.
    pub binaries: BTreeSet<String>,
    /// CMD, the default flags of dmp-server.
    pub cmd: Vec<String>,
}

impl Dockerfile {
    /// Reads deploy/Dockerfile (instructions continued with `\` joined).
    pub fn load() -> Self {
        let text = read(&deploy().join("Dockerfile")).replace("\\\n", " ");
        let mut exposed = BTreeSet::new();
        let (mut volume, mut cmd, mut binaries) = (None, None, BTreeSet::new());
        let mut runtime = false;
        for line in text.lines().map(str::trim).filter(|l| !l.starts_with('#')) {
            let (instruction, rest) = line.split_once(' ').unwrap_or((line, ""));
            match instruction {
                "FROM" => runtime = rest.ends_with("AS runtime"),
                "EXPOSE" => exposed.extend(rest.split_whitespace().map(|p| {
                    p.trim_end_matches("/tcp").parse::<u16>().unwrap_or_else(|e| panic!("EXPOSE {p}: {e}"))
                })),
                "VOLUME" => volume = Some(serde_json::from_str::<Vec<String>>(rest).unwrap().remove(0)),
                "CMD" => cmd = Some(serde_json::from_str::<Vec<String>>(rest).expect("CMD in exec form")),
                "ENTRYPOINT" => {
                    let e: Vec<String> = serde_json::from_str(rest).expect("ENTRYPOINT in exec form");
                    assert_eq!(e, ["/usr/local/bin/dmp-server"]);
                }
                "COPY" if runtime => {
                    let words: Vec<&str> = rest.split_whitespace().filter(|w| !w.starts_with("--")).collect();
                    let (dest, sources) = words.split_last().unwrap();
                    if *dest == "/usr/local/bin/" {
                        binaries.extend(sources.iter().map(|s| s.rsplit('/').next().unwrap().to_owned()));
                    } else if let Some(name) = dest.strip_prefix("/usr/local/bin/") {
                        binaries.insert(name.to_owned());
                    }
                }
                _ => {}
            }
        }
        Self { exposed, volume: volume.expect("a VOLUME"), binaries, cmd: cmd.expect("a CMD") }
    }

    /// The gRPC port and the metrics port (EXPOSE, in that order: 50051 then 9464 by their CMD flags).
    pub fn grpc_and_metrics_ports(&self) -> (u16, u16) {
        let grpc = port_of(flag_values(&self.cmd, "--grpc-addr")[0]);
        let metrics = port_of(flag_values(&self.cmd, "--metrics-addr")[0]);
        (grpc, metrics)
    }
}

#[test]
fn the_dockerfile_command_parses_and_agrees_with_its_ports_volume_and_set() {
    let d = Dockerfile::load();
    let args = dmp_server_args(&d.cmd, "Dockerfile CMD");
    let (grpc, metrics) = d.grpc_and_metrics_ports();
    assert_eq!(d.exposed, BTreeSet::from([grpc, metrics]), "EXPOSE is the gRPC and the metrics port");
    assert_eq!(args.data_dir.as_deref(), Some(std::path::Path::new(&d.volume)), "--data-dir is the VOLUME");
    for binary in ["dmp-server", "dmpctl", "grpc_health_probe"] {
        assert!(d.binaries.contains(binary), "the image has no /usr/local/bin/{binary}: {:?}", d.binaries);
    }
    let set = set_files(&["c"], &[], &[]);
    let used = set_paths_in(&d.cmd, &set, "Dockerfile CMD");
    assert_eq!(used.len(), 4, "access, the server's certificate and key, the CA: {used:?}");
    assert!(d.cmd.iter().any(|a| a.starts_with(SET_DIR)));
}
