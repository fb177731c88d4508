//! The Python client (`python/src/dmp_cell`) against the real server: a script that never calls `close()` exits
//! within 2 s of its end. Runs with `DMP_TEST_PYTHON` (a Python with grpcio and eclipse-zenoh), else the
//! workspace's `.venv`; the package is taken from `python/src`, as edited.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use dmp_tests::{TestServer, within};

/// The longest a script may take to exit once its last line ran.
const EXIT_WITHIN: Duration = Duration::from_secs(2);

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap().to_owned()
}

fn python() -> PathBuf {
    let python = std::env::var_os("DMP_TEST_PYTHON")
        .map_or_else(|| workspace().join(".venv/bin/python"), PathBuf::from);
    assert!(python.exists(), "{} does not exist: set DMP_TEST_PYTHON", python.display());
    python
}

#[tokio::test(flavor = "multi_thread")]
async fn a_script_that_never_closes_its_client_exits() {
    let generated = workspace().join("python/src/dmp_cell/_pb");
    assert!(
        generated.is_dir(),
        "{} does not exist: build the package once (pip install -e python) to generate the messages",
        generated.display()
    );
    let server = TestServer::start().await;
    let locator = server.handle().zenoh_locators[0].clone();
    let script = format!(
        "import dmp_cell\n\
         c = dmp_cell.Client('127.0.0.1:{port}')\n\
         c.publish_obstacle(None, {{'id': 'ball', 'center': [0.5, 0.5], 'semi_axes': [0.1, 0.1]}}, '{locator}', wait_s=30)\n\
         print('published', flush=True)\n",
        port = server.handle().grpc_addr.port()
    );
    let mut child = Command::new(python())
        .env("PYTHONPATH", workspace().join("python/src"))
        .env("GRPC_VERBOSITY", "ERROR")
        .args(["-c", &script])
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .expect("python starts");
    let stdout = child.stdout.take().unwrap();
    let ended = within(
        "the script's last line",
        tokio::task::spawn_blocking(move || {
            let mut line = String::new();
            BufReader::new(stdout).read_line(&mut line).unwrap();
            (line, Instant::now())
        }),
    )
    .await
    .unwrap();
    assert_eq!(ended.0.trim(), "published");
    let status = within(
        "the script's exit",
        tokio::task::spawn_blocking(move || {
            let deadline = ended.1 + EXIT_WITHIN;
            loop {
                if let Some(status) = child.try_wait().unwrap() {
                    return Some((status, ended.1.elapsed()));
                }
                if Instant::now() > deadline {
                    let _ = child.kill();
                    let _ = child.wait();
                    return None;
                }
                std::thread::sleep(Duration::from_millis(20));
            }
        }),
    )
    .await
    .unwrap();
    let (status, took) =
        status.expect("the script did not exit within 2 s of its end: the client kept it alive");
    assert!(status.success(), "{status}");
    println!("exited {took:?} after its last line");
    server.stop().await;
}
