"""Errors of the client, one class for all, as the Rust client's `ClientError`.

Every failure raises a `DmpError`. When the server answered with a gRPC status, `code` is that
`grpc.StatusCode` and `reason` the server's message (for INVALID_ARGUMENT it reads `field: rule`, and `field`
holds the field). Errors found before anything is sent name the argument at fault in `field`.
"""

from __future__ import annotations

from typing import Optional

import grpc


class DmpError(Exception):
    """Any failure of the client: `code` (a `grpc.StatusCode`, or None when no server answered), `reason`, and
    `field` (the argument or request field at fault, when there is one)."""

    def __init__(self, reason: str, code: Optional[grpc.StatusCode] = None, field: Optional[str] = None):
        self.reason = reason
        self.code = code
        self.field = field
        super().__init__(str(self))

    def __str__(self) -> str:
        where = f"{self.field}: " if self.field and not self.reason.startswith(f"{self.field}:") else ""
        code = f" ({self.code.name})" if self.code is not None else ""
        return f"{where}{self.reason}{code}"

    def is_bad_input(self) -> bool:
        """True when the caller's input is at fault: a bad argument, or a request the server refused as
        INVALID_ARGUMENT or NOT_FOUND."""
        return isinstance(self, ArgumentError) or self.code in (
            grpc.StatusCode.INVALID_ARGUMENT,
            grpc.StatusCode.NOT_FOUND,
        )


class ArgumentError(DmpError, ValueError):
    """An argument of a call breaks a rule (found before anything was sent)."""

    def __init__(self, field: str, reason: str):
        super().__init__(reason, None, field)


class StatusError(DmpError):
    """The server answered with a gRPC status other than OK."""


class ConnectError(DmpError):
    """The server could not be reached (refused, timed out, TLS handshake failed)."""


class ProtocolError(DmpError):
    """The server sent something that breaks the schema's contract (e.g. a segment with the wrong value count)."""


class ZenohError(DmpError):
    """Zenoh failed (opening the session, publishing), or no subscriber (the server) was found in time."""


def from_rpc(e: grpc.RpcError) -> DmpError:
    """The error of a failed call. The server's INVALID_ARGUMENT messages read `field: rule`."""
    code = e.code() if hasattr(e, "code") else grpc.StatusCode.UNKNOWN
    reason = (e.details() if hasattr(e, "details") else None) or str(e) or "no message"
    field = None
    if code == grpc.StatusCode.INVALID_ARGUMENT and ": " in reason:
        field = reason.split(": ", 1)[0]
    if code == grpc.StatusCode.UNAVAILABLE:
        return ConnectError(reason, code, field)
    return StatusError(reason, code, field)
