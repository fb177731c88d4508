"""Publishing obstacles over Zenoh, as a perception node (the Rust side is `client/src/zenoh_pub.rs`).

Keys are `dmp/<cell>/obstacles/<obstacle-id>` (`proto/src/keys.rs`): a put adds or replaces the obstacle, a
delete removes it. The payload is the JSON obstacle (`obstacles.py`), encoding `application/json`, as
`dmpctl scene put --via zenoh` sends it.

Zenoh drops a put made before the subscriber is known to the publisher: every put first makes sure that a
subscriber of the cell's obstacles (the server) is known, waiting for it at most `wait_s`, and fails with
`ZenohError` otherwise. Puts use congestion control BLOCK, and `close` closes the session gracefully, so a
short-lived program loses nothing.

The session is opened from a stock Zenoh configuration file when one is given (`zenoh-perception.json5`, as
`dmp-server access init` writes it: mutual TLS with the perception node's certificate), its endpoints replaced by
`connect` when given; otherwise as the Rust publisher's: a peer that, with `connect` endpoints, connects to them
with scouting off and listens on nothing, and without, finds the server by multicast scouting.
"""

from __future__ import annotations

import json
import threading
from pathlib import Path
from typing import Any, Dict, Mapping, Optional, Sequence

import zenoh

from .errors import ArgumentError, ZenohError
from .obstacles import check_name, check_obstacle

#: How long a put waits for the server's subscriber by default, seconds.
SUBSCRIBER_WAIT_S = 5.0


def obstacle_key(cell: str, obstacle_id: str) -> str:
    """`dmp/<cell>/obstacles/<obstacle-id>`."""
    return f"dmp/{cell}/obstacles/{obstacle_id}"


def session_config(connect: Sequence[str], config_file: Optional[str]) -> "zenoh.Config":
    """The configuration of a publishing peer (see the module)."""
    connect = list(connect)
    for i, e in enumerate(connect):
        if not isinstance(e, str) or "/" not in e:
            raise ArgumentError(f"zenoh_connect[{i}]", f"`{e}` is not an endpoint such as tcp/127.0.0.1:7447")
    try:
        if config_file is not None:
            if not Path(config_file).is_file():
                raise ArgumentError("zenoh_config", f"{config_file}: no such file")
            config = zenoh.Config.from_file(str(config_file))
        else:
            config = zenoh.Config()
            config.insert_json5("mode", json.dumps("peer"))
            config.insert_json5("scouting/multicast/enabled", json.dumps(not connect))
            if connect:
                config.insert_json5("listen/endpoints", json.dumps([]))
        if connect:
            config.insert_json5("connect/endpoints", json.dumps(connect))
    except ArgumentError:
        raise
    except Exception as e:  # zenoh raises its own ZError
        raise ArgumentError("zenoh_config", str(e)) from None
    return config


def _matching(publisher) -> bool:
    """Whether a subscriber matches the publisher's key expression (zenoh returns a `MatchingStatus`)."""
    status = publisher.matching_status
    return bool(getattr(status, "matching", status))


class ObstaclePublisher:
    """A Zenoh peer that publishes obstacles, of any cell."""

    def __init__(self, connect: Sequence[str] = (), config_file: Optional[str] = None):
        config = session_config(connect, config_file)
        try:
            self._session = zenoh.open(config)
        except Exception as e:
            raise ZenohError(f"opening the session: {e}") from None
        self._lock = threading.Lock()
        # Per cell: a publisher declared on `dmp/<cell>/obstacles/*` and never put on: its matching status says
        # whether a subscriber of the cell's obstacles is known; and the listener that wakes a wait for it.
        self._probes: Dict[str, Any] = {}
        self._matched: Dict[str, threading.Event] = {}
        self._listeners: Dict[str, Any] = {}

    def _probe(self, cell: str):
        with self._lock:
            if cell not in self._probes:
                event = threading.Event()
                probe = self._session.declare_publisher(f"dmp/{cell}/obstacles/*")

                def on_status(status, event=event):
                    if status.matching:
                        event.set()
                    else:
                        event.clear()

                self._listeners[cell] = probe.declare_matching_listener(on_status)
                self._probes[cell], self._matched[cell] = probe, event
            return self._probes[cell], self._matched[cell]

    def wait_for_subscriber(self, cell: str, timeout: float = SUBSCRIBER_WAIT_S) -> None:
        """Waits until a subscriber of the cell's obstacles (the server) is known, at most `timeout` seconds."""
        probe, matched = self._probe(check_name("cell", cell))
        if _matching(probe) or matched.wait(timeout) or _matching(probe):
            return
        raise ZenohError(
            f"no subscriber of dmp/{cell}/obstacles/* after {timeout} s: is the server running with Zenoh on, "
            "reachable (zenoh_connect), and may the Zenoh identity (zenoh_config) publish in this cell?"
        )

    def put(self, cell: str, obstacle: Mapping[str, Any], wait_s: float = SUBSCRIBER_WAIT_S) -> str:
        """Puts a checked obstacle dict on its key, which it returns."""
        o = check_obstacle(obstacle)
        self.wait_for_subscriber(cell, wait_s)
        key = obstacle_key(cell, o["id"])
        try:
            self._session.put(key, json.dumps(o), encoding=zenoh.Encoding.APPLICATION_JSON,
                              congestion_control=zenoh.CongestionControl.BLOCK)
        except Exception as e:
            raise ZenohError(f"put on {key}: {e}") from None
        return key

    def delete(self, cell: str, obstacle_id: str, wait_s: float = SUBSCRIBER_WAIT_S) -> str:
        """Removes the obstacle `obstacle_id` of the cell; returns its key."""
        check_name("id", obstacle_id)
        self.wait_for_subscriber(cell, wait_s)
        key = obstacle_key(cell, obstacle_id)
        try:
            self._session.delete(key, congestion_control=zenoh.CongestionControl.BLOCK)
        except Exception as e:
            raise ZenohError(f"delete of {key}: {e}") from None
        return key

    def close(self) -> None:
        """Closes the session gracefully (what was put is sent first)."""
        with self._lock:
            for listener in self._listeners.values():
                listener.undeclare()
            for probe in self._probes.values():
                probe.undeclare()
            self._listeners.clear()
            self._probes.clear()
        if not self._session.is_closed():
            self._session.close()
