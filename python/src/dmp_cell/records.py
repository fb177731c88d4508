"""What `Client.learn`, `Client.info` and the robot calls return: the server's messages, readable. A learned record
and the server's information read as their `dmp.v1` messages (every field an attribute) and print as one summary
line, not as the primitive's weights; a robot's record is a plain tuple."""

from __future__ import annotations

from typing import Any, Dict, NamedTuple, Optional, Tuple

from .pb import robots, server, types
from .setpoints import LIMIT_FIELDS


class _Message:
    """A message read through: `x.field` is the message's field, `x.message` the message itself."""

    def __init__(self, message: Any):
        object.__setattr__(self, "message", message)

    def __getattr__(self, name: str) -> Any:
        return getattr(self.message, name)

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError(f"{type(self).__name__} is read-only (change `.message`)")

    def __eq__(self, other: object) -> bool:
        other = other.message if isinstance(other, _Message) else other
        return self.message == other

    __hash__ = None  # type: ignore[assignment]


class PrimitiveSummary(_Message):
    """A stored primitive's record (`dmp.v1.PrimitiveRecord`), printed as
    `PrimitiveRecord(robot/name v3: 2-D, N 50, tau 1.0 s, goal [1.0, 0.5])`."""

    message: types.PrimitiveRecord

    def __repr__(self) -> str:
        r = self.message
        p = r.primitive
        # A pose primitive's last three dimensions are its orientation's chart: the position is the rest.
        pose = len(p.orientation_reference) > 0
        dim = p.dim - 3 if pose else p.dim
        goal = [round(g, 6) for g in list(p.goal)[:dim]]
        kind = f"{dim}-D pose" if pose else f"{dim}-D"
        return (f"PrimitiveRecord({r.robot_id}/{r.name} v{r.version}: {kind}, N {p.n_basis}, tau {p.tau:g} s, "
                f"goal {goal})")

    __str__ = __repr__


class ServerSummary(_Message):
    """The server's information (`dmp.v1.ServerInfo`), printed as
    `ServerInfo(version 0.1.0, cell default, TLS, access control, identity planner (planner), zenoh [...])`."""

    message: server.ServerInfo

    def __repr__(self) -> str:
        i = self.message
        security = []
        if i.tls:
            security.append("mutual TLS" if i.mutual_tls else "TLS")
        if i.access_control:
            security.append("access control")
        if i.insecure:
            security.append("INSECURE")
        who = f", identity {i.identity} ({i.role})" if i.identity else ""
        sec = ", " + ", ".join(security) if security else ", plaintext"
        return f"ServerInfo(version {i.version}, cell {i.cell}{sec}{who}, zenoh {list(i.zenoh_locators)})"

    __str__ = __repr__


class RobotRecord(NamedTuple):
    """A robot's record (`Client.get_robot`): its `limits` (the fields of `dmp.v1.Limits` that are set, SI units),
    its safety distance `margin` (metres; 0: the server's default, negative: none), its `footprint`
    (`{"semi_axes": .., "exponents": ..}`, or None) and when it was stored (`updated_unix_ms`)."""

    robot_id: str
    limits: Dict[str, float]
    margin: float
    footprint: Optional[Dict[str, Tuple[float, ...]]]
    updated_unix_ms: int


def robot_record_of(r: robots.RobotRecord) -> RobotRecord:
    """The tuple of a `dmp.v1.RobotRecord`."""
    limits = {f: getattr(r.limits, f) for f in LIMIT_FIELDS if getattr(r.limits, f)} if r.HasField("limits") else {}
    footprint = ({"semi_axes": tuple(r.footprint.semi_axes), "exponents": tuple(r.footprint.exponents)}
                 if r.HasField("footprint") else None)
    return RobotRecord(r.robot_id, limits, r.margin, footprint, r.updated_unix_ms)
