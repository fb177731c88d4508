"""The real server binary, started by the tests: secured as by default (TLS, mutual TLS, an access file made by
`dmp-server access init`), gRPC on a free loopback port, Zenoh on a loopback `tls/` endpoint with multicast
scouting off. Every wait is bounded: readiness is polled (GetInfo over TLS) until a deadline."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Optional

import dmp_cell

REPO = Path(__file__).resolve().parents[2]

#: The longest the server may take to start or stop, seconds.
START_S = 60.0
STOP_S = 20.0

CELL = "cell-a"
ROBOT = "r1"


def server_binary() -> Path:
    """`$DMP_SERVER_BIN`, else `$CARGO_TARGET_DIR/debug/dmp-server`, else the repository's `target/debug/dmp-server`."""
    if os.environ.get("DMP_SERVER_BIN"):
        path = Path(os.environ["DMP_SERVER_BIN"])
    else:
        target = Path(os.environ.get("CARGO_TARGET_DIR") or REPO / "target")
        path = (target if target.is_absolute() else REPO / target) / "debug" / "dmp-server"
    if not path.is_file():
        raise RuntimeError(
            f"{path} does not exist: build it first (`cargo build -p dmp-server`, or `cargo test --workspace`), "
            "or set DMP_SERVER_BIN"
        )
    return path


def free_port() -> int:
    """A loopback port that was free a moment ago (the server is retried on another if it is taken meanwhile)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def until(what: str, cond: Callable[[], bool], timeout: float = 10.0, poll: float = 0.01) -> float:
    """Polls `cond` until it holds, at most `timeout` seconds; returns the time it took. Fails naming `what`."""
    start = time.monotonic()
    while not cond():
        if time.monotonic() - start > timeout:
            raise AssertionError(f"timed out after {timeout} s: {what}")
        time.sleep(poll)
    return time.monotonic() - start


@dataclass
class Server:
    """A running secured server and the set that secures it."""

    process: subprocess.Popen
    address: str
    set_dir: Optional[Path]
    log: Path
    zenoh_locator: str

    def token(self, identity: str) -> Path:
        return self.set_dir / f"{identity}.token"

    def client(self, identity: Optional[str] = "planner", **options) -> dmp_cell.Client:
        """A client over TLS with the identity's token (None: no token); a plain one to an unsecured server."""
        if self.set_dir is None:
            return dmp_cell.Client(self.address, **options)
        options.setdefault("tls_ca", self.set_dir / "ca.pem")
        if identity is not None:
            options.setdefault("token_file", self.token(identity))
        return dmp_cell.Client(self.address, **options)

    def log_tail(self, lines: int = 40) -> str:
        return "\n".join(self.log.read_text(errors="replace").splitlines()[-lines:])

    def stop(self) -> None:
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(timeout=STOP_S)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait(timeout=STOP_S)


def start(workdir: Path, secured: bool = True, attempts: int = 3) -> Server:
    """`access init` into `workdir/set`, then the server secured by it (`secured=False`: the server on its
    defaults, plaintext gRPC and Zenoh on loopback without access control, in the cell `default`); retried on
    another port if the port was taken."""
    binary = server_binary()
    set_dir = workdir / "set"
    if secured:
        subprocess.run(
            [str(binary), "access", "init", str(set_dir), "--cell", CELL, "--robot", ROBOT],
            check=True, capture_output=True, timeout=START_S,
        )
    security = [
        "--cell", CELL,
        "--zenoh-listen", "tls/127.0.0.1:0",
        "--access", str(set_dir / "access.toml"),
        "--tls-cert", str(set_dir / "server.pem"),
        "--tls-key", str(set_dir / "server.key"),
        "--tls-client-ca", str(set_dir / "ca.pem"),
    ] if secured else ["--zenoh-listen", "tcp/127.0.0.1:0"]
    last = ""
    for attempt in range(attempts):
        port = free_port()
        log = workdir / f"server-{attempt}.log"
        args = [
            str(binary),
            "--grpc-addr", f"127.0.0.1:{port}",
            "--data-dir", str(workdir / f"data-{attempt}"),
            "--zenoh-no-multicast",
        ] + security
        env = dict(os.environ, RUST_LOG=os.environ.get("RUST_LOG", "info"))
        with open(log, "wb") as out:
            process = subprocess.Popen(args, stdout=out, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                       env=env)
        server = Server(process, f"127.0.0.1:{port}", set_dir if secured else None, log, "")
        deadline = time.monotonic() + START_S
        while process.poll() is None and time.monotonic() < deadline:
            try:
                with server.client("admin", timeout=1.0) as c:
                    info = c.info()
                scheme = "tls/" if secured else "tcp/"
                server.zenoh_locator = next(loc for loc in info.zenoh_locators if loc.startswith(scheme))
                return server
            except dmp_cell.DmpError:
                time.sleep(0.05)
        last = server.log_tail()
        server.stop()
    raise RuntimeError(f"the server did not start ({attempts} attempts); its log ends with:\n{last}")
