//! Compiles `dmp/v1/*.proto` without a system `protoc`: protox parses them, tonic-prost-build generates the code,
//! and the encoded descriptor set is written for server reflection.

use std::path::PathBuf;

use prost::Message;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let files = [
        "dmp/v1/types.proto",
        "dmp/v1/primitives.proto",
        "dmp/v1/scene.proto",
        "dmp/v1/motion.proto",
        "dmp/v1/server.proto",
    ];
    for f in &files {
        println!("cargo:rerun-if-changed={f}");
    }
    let fds = protox::compile(files, ["."])?;
    let out = PathBuf::from(std::env::var("OUT_DIR")?);
    std::fs::write(out.join("dmp_descriptor.bin"), fds.encode_to_vec())?;
    tonic_prost_build::configure().build_server(true).build_client(true).compile_fds(fds)?;
    Ok(())
}
