"""Python client of the DMP cell server (`dmp-server`): learn primitives, stream their setpoints with
supersession applied, change the goal mid-stream, and publish obstacles over Zenoh as a perception node.

    import dmp_cell
    c = dmp_cell.Client("127.0.0.1:50051", token=None)
    c.learn("r1", "reach", t=ts, positions=rows)
    for sp in c.stream("r1", "reach", goal=None, realtime=False):
        sp.t, sp.position, sp.velocity, sp.acceleration
    c.publish_obstacle(cell, {"id": "box", "center": [0.5, 0.5], "semi_axes": [0.1, 0.1]})

The gRPC stubs are generated from the repository's `proto/` when the package is built; `dmp_cell.pb` holds them.
"""

from . import pb
from .client import NO_LIMITS, Client, Plan
from .errors import ArgumentError, ConnectError, DmpError, ProtocolError, StatusError, ZenohError
from .obstacles import check_obstacle, obstacle_to_dict, obstacle_to_proto
from .records import PrimitiveSummary, RobotRecord, ServerSummary
from .setpoints import FINAL_STATUSES, LimitsInForce, ServerWarning, Setpoint, Setpoints, Verdict
from .stream import Stream

__all__ = [
    "ArgumentError",
    "Client",
    "ConnectError",
    "DmpError",
    "FINAL_STATUSES",
    "LimitsInForce",
    "NO_LIMITS",
    "Plan",
    "PrimitiveSummary",
    "ProtocolError",
    "RobotRecord",
    "ServerSummary",
    "Setpoint",
    "Setpoints",
    "StatusError",
    "Stream",
    "ServerWarning",
    "Verdict",
    "ZenohError",
    "check_obstacle",
    "obstacle_to_dict",
    "obstacle_to_proto",
    "pb",
]
