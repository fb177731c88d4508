"""Fixtures: one secured server for the session (tests/server.py), and a demonstration to learn."""

from __future__ import annotations

import math
import os
import sys
from pathlib import Path

# grpcio logs failed TLS handshakes at info level; some tests fail them on purpose.
os.environ.setdefault("GRPC_VERBOSITY", "ERROR")

import pytest

sys.path.insert(0, str(Path(__file__).parent))

import server as srv  # noqa: E402


@pytest.fixture(scope="session")
def server(tmp_path_factory):
    s = srv.start(tmp_path_factory.mktemp("dmp-server"))
    yield s
    s.stop()


@pytest.fixture(scope="session")
def plain_server(tmp_path_factory):
    """The server on its defaults: plaintext on loopback, no access control."""
    s = srv.start(tmp_path_factory.mktemp("dmp-server-plain"), secured=False)
    yield s
    s.stop()


@pytest.fixture(scope="session")
def demonstration():
    """A minimum-jerk reach from (0, 0) to (1, 0.5) in 1 s, 1001 samples: times and rows."""
    t = [i / 1000 for i in range(1001)]
    rows = []
    for ti in t:
        s = 10 * ti**3 - 15 * ti**4 + 6 * ti**5
        rows.append([s * 1.0, 0.5 * s + 0.05 * math.sin(math.pi * ti)])
    return t, rows


@pytest.fixture(scope="session")
def learned(server, demonstration):
    """The robot's primitive `reach`, learned once by the planner; returns its record."""
    t, rows = demonstration
    with server.client("planner") as c:
        return c.learn(srv.ROBOT, "reach", t=t, positions=rows)
