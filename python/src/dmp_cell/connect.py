"""How the client reaches a secured server, as `dmpctl` and the Rust client do: TLS (the CA that signed the
server's certificate; for mutual TLS the client's own certificate and key; optionally the name the server's
certificate must have) and a bearer token sent with every call in the `authorization` metadata.

Addresses: `HOST:PORT` (plaintext, or TLS when a CA is given), `http://HOST:PORT`, or `https://HOST:PORT` (needs
the CA).
"""

from __future__ import annotations

import ipaddress
import os
from dataclasses import dataclass
from pathlib import Path
from typing import List, Optional, Sequence, Tuple, Union

import grpc

from .errors import ArgumentError, ConnectError

PathLike = Union[str, "os.PathLike[str]"]

#: How long connecting waits for the server, seconds.
CONNECT_TIMEOUT_S = 5.0

#: Largest message sent or received (a 1,000,000-step 3-D plan is ~75 MB), as the Rust client.
MAX_MESSAGE_BYTES = 256 * 1024 * 1024

#: What a stream may have received and not yet handed over, bytes. With grpcio's probing of the bandwidth-delay
#: product (on by default) the receive window grows until a whole run read "as fast as read" sits in the
#: transport, and a goal change then arrives after the server has finished; kept small, the server stays close to
#: the setpoint being read.
STREAM_LOOKAHEAD_BYTES = 16 * 1024


@dataclass(frozen=True)
class Target:
    """Where to connect: `host:port` without a scheme, and whether TLS is used."""

    authority: str
    tls: bool

    @property
    def host(self) -> str:
        a = self.authority
        if a.startswith("["):
            return a[1 : a.index("]")]
        return a.rsplit(":", 1)[0] if ":" in a else a


def parse_address(address: str, tls: bool) -> Target:
    """The target of `address` (see the module); `tls` says whether a CA was given."""
    if not isinstance(address, str) or not address.strip():
        raise ArgumentError("address", "must be a non-empty `HOST:PORT` or URL")
    address = address.strip()
    scheme, sep, rest = address.partition("://")
    if not sep:
        scheme, rest = ("https" if tls else "http"), address
    rest = rest.rstrip("/")
    if scheme not in ("http", "https") or not rest or "/" in rest:
        raise ArgumentError("address", f"`{address}` is not `HOST:PORT`, `http://HOST:PORT` or `https://HOST:PORT`")
    if scheme == "https" and not tls:
        raise ArgumentError("tls_ca", f"`{address}` needs the server's CA (tls_ca)")
    if scheme == "http" and tls:
        raise ArgumentError("address", f"`{address}`: TLS needs an https:// address")
    return Target(rest, scheme == "https")


def is_loopback(host: str) -> bool:
    """Whether `host` names this machine's loopback."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


def _read(field: str, path: Optional[PathLike]) -> Optional[bytes]:
    if path is None:
        return None
    try:
        return Path(path).read_bytes()
    except OSError as e:
        raise ArgumentError(field, f"cannot read {path}: {e.strerror or e}") from None


def read_token(token: Optional[str], token_file: Optional[PathLike]) -> Optional[str]:
    """The bearer token: `token`, else the content of `token_file` (as `dmp-server access init` writes them),
    trimmed; None for neither. An empty token, or one that is not printable ASCII, is refused."""
    if token is not None and token_file is not None:
        raise ArgumentError("token", "give token or token_file, not both")
    if token_file is not None:
        token = (_read("token_file", token_file) or b"").decode("ascii", "replace")
    if token is None:
        return None
    token = token.strip()
    if not token:
        raise ArgumentError("token", "is empty")
    if not all(33 <= ord(c) < 127 for c in token):
        raise ArgumentError("token", "must be printable ASCII")
    return token


def open_channel(
    address: str,
    *,
    tls_ca: Optional[PathLike] = None,
    tls_cert: Optional[PathLike] = None,
    tls_key: Optional[PathLike] = None,
    server_name: Optional[str] = None,
    timeout: float = CONNECT_TIMEOUT_S,
) -> Tuple[grpc.Channel, Target]:
    """Opens a channel and waits at most `timeout` seconds until it is ready."""
    if (tls_cert is None) != (tls_key is None):
        raise ArgumentError("tls_cert", "the client's certificate and key go together")
    if tls_ca is None and (tls_cert is not None or server_name is not None):
        raise ArgumentError("tls_ca", "TLS options need tls_ca (the CA of the server's certificate)")
    target = parse_address(address, tls_ca is not None)
    options: List[Tuple[str, object]] = [
        ("grpc.max_receive_message_length", MAX_MESSAGE_BYTES),
        ("grpc.max_send_message_length", MAX_MESSAGE_BYTES),
        ("grpc.http2.bdp_probe", 0),
        ("grpc.http2.lookahead_bytes", STREAM_LOOKAHEAD_BYTES),
    ]
    if target.tls:
        credentials = grpc.ssl_channel_credentials(
            root_certificates=_read("tls_ca", tls_ca),
            private_key=_read("tls_key", tls_key),
            certificate_chain=_read("tls_cert", tls_cert),
        )
        if server_name:
            options.append(("grpc.ssl_target_name_override", server_name))
        channel = grpc.secure_channel(target.authority, credentials, options=options)
    else:
        channel = grpc.insecure_channel(target.authority, options=options)
    try:
        grpc.channel_ready_future(channel).result(timeout=timeout)
    except grpc.FutureTimeoutError:
        channel.close()
        scheme = "https" if target.tls else "http"
        raise ConnectError(
            f"cannot connect to the server at {scheme}://{target.authority}: no answer within {timeout} s"
            + (" (or the TLS handshake failed: check tls_ca, tls_cert/tls_key and server_name)" if target.tls else "")
        ) from None
    return channel, target


def metadata(token: Optional[str]) -> Sequence[Tuple[str, str]]:
    """The metadata of every call: the bearer token, when there is one."""
    return (("authorization", f"Bearer {token}"),) if token else ()
