//! Compiles `dmp/v1/*.proto` without a system `protoc`: protox parses them, tonic-prost-build generates the code
//! (the server stubs only with the feature `server`), the encoded descriptor set is written for server reflection,
//! and the field numbers of every message are written as constants (`tags.rs`, the `dmp_proto::tags` module) for
//! code that reads a message lazily.

use std::fmt::Write as _;
use std::path::PathBuf;

use prost::Message;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let files = [
        "dmp/v1/types.proto",
        "dmp/v1/primitives.proto",
        "dmp/v1/scene.proto",
        "dmp/v1/motion.proto",
        "dmp/v1/robots.proto",
        "dmp/v1/server.proto",
    ];
    for f in &files {
        println!("cargo:rerun-if-changed={f}");
    }
    let fds = protox::compile(files, ["."])?;
    let out = PathBuf::from(std::env::var("OUT_DIR")?);
    std::fs::write(out.join("dmp_descriptor.bin"), fds.encode_to_vec())?;

    // One module per top-level message of `dmp.v1` (`RobotState` -> `robot_state`), one constant per field
    // (`start_unix_s` -> `START_UNIX_S`).
    let mut tags = String::new();
    for file in fds.file.iter().filter(|f| f.package() == "dmp.v1") {
        for message in &file.message_type {
            writeln!(tags, "/// Field numbers of `dmp.v1.{}`.", message.name())?;
            writeln!(tags, "pub mod {} {{", snake_case(message.name()))?;
            for field in &message.field {
                writeln!(tags, "    /// `{}`.", field.name())?;
                writeln!(tags, "    pub const {}: u32 = {};", field.name().to_uppercase(), field.number())?;
            }
            writeln!(tags, "}}")?;
        }
    }
    std::fs::write(out.join("tags.rs"), tags)?;

    // Server stubs only for a crate that serves (feature `server`): a client's build stays without them.
    let server = std::env::var_os("CARGO_FEATURE_SERVER").is_some();
    tonic_prost_build::configure().build_server(server).build_client(true).compile_fds(fds)?;
    Ok(())
}

/// `RobotState` -> `robot_state`.
fn snake_case(name: &str) -> String {
    let mut s = String::with_capacity(name.len() + 4);
    for (i, c) in name.chars().enumerate() {
        if c.is_ascii_uppercase() && i > 0 {
            s.push('_');
        }
        s.push(c.to_ascii_lowercase());
    }
    s
}
