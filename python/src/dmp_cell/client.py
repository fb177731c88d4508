"""`Client`: the server's gRPC services (primitives, motion, scene, server info) and the Zenoh obstacle publisher,
for Python robot drivers, planners and perception nodes."""

from __future__ import annotations

import atexit
import threading
import warnings
import weakref
from typing import Any, Dict, List, Mapping, NamedTuple, Optional, Sequence, Union

import grpc

from . import connect as conn
from .pb import (motion, motion_grpc, primitives, primitives_grpc, robots, robots_grpc, scene, scene_grpc, server,
                 server_grpc, types)
from .errors import ArgumentError, from_rpc
from .obstacles import check_name, check_obstacle, obstacle_to_dict, obstacle_to_proto
from .records import PrimitiveSummary, RobotRecord, ServerSummary, robot_record_of
from .setpoints import (LIMIT_FIELDS, LimitsInForce, ServerWarning, Setpoints, Verdict, limits_of, verdict_of,
                        warning_of)
from .stream import Stream
from .values import number, quaternion, rows, vector
from .zenoh_pub import SUBSCRIBER_WAIT_S, ObstaclePublisher

class Plan(NamedTuple):
    """A whole trajectory (`Client.plan`): its setpoints, the obstacles it touched, whether it stalled away from
    the goal, the server's warnings, the scene version it was computed with, and how it ended (`verdict`: whether
    the goal was reached and if not why; None from a server that does not say), and the limits it kept (`limits`:
    the bounds, their profile and the safety distance; None from a server that does not say)."""

    setpoints: Setpoints
    collisions: List[str]
    stalled: bool
    warnings: List[ServerWarning]
    scene_version: int
    verdict: Optional[Verdict] = None
    limits: Optional[LimitsInForce] = None


#: Limits that turn every limit off, explicitly (`plan` and `stream`'s `limits`): the DMP's own trajectory. A field
#: left out (or 0) takes the robot's record's, then the server's default profile.
NO_LIMITS: Mapping[str, float] = {f: -1.0 for f in LIMIT_FIELDS}

#: The server's address by default.
DEFAULT_ADDRESS = "127.0.0.1:50051"

#: How long a unary call may take by default, seconds.
CALL_TIMEOUT_S = 60.0


def motion_limits(limits: Mapping[str, float]) -> motion.Limits:
    """The `dmp.v1.Limits` of a mapping of its fields (`max_speed`, ...) to bounds; an unknown field or a value that
    is not a finite number raises `ArgumentError` naming `limits.<field>`."""
    for field in limits:
        if field not in LIMIT_FIELDS:
            raise ArgumentError(f"limits.{field}", f"is not a field of dmp.v1.Limits ({', '.join(LIMIT_FIELDS)})")
    return motion.Limits(**{f: number(f"limits.{f}", v) for f, v in limits.items()})


def _renamed(old: str, new: str, old_value: float, new_value: float) -> float:
    """The value of a keyword renamed from `old` to `new` (as the gRPC field and the CLI flag say): `new`'s, or
    `old`'s with a DeprecationWarning; both given is an error."""
    if old_value is None:
        return new_value
    if new_value:
        raise ArgumentError(old, f"give `{new}` only (`{old}` is its old name)")
    warnings.warn(f"`{old}` is now `{new}` (seconds, as the gRPC field and dmpctl's flag)", DeprecationWarning,
                  stacklevel=3)
    return old_value


class _Resources:
    """What a `Client` holds open: its channel and its Zenoh publishers. Apart from the client, so that the
    finaliser that closes them at exit does not keep the client alive."""

    def __init__(self, channel: grpc.Channel):
        self.channel = channel
        self.publishers: Dict[tuple, ObstaclePublisher] = {}
        self.lock = threading.Lock()
        self.closed = False

    def close(self) -> None:
        with self.lock:
            if self.closed:
                return
            self.closed = True
            publishers, self.publishers = self.publishers, {}
        for p in publishers.values():
            p.close()
        self.channel.close()


#: The resources of the clients not closed yet, closed when the interpreter exits.
_OPEN: "weakref.WeakSet[_Resources]" = weakref.WeakSet()


def _close_all_at_exit() -> None:
    for resources in list(_OPEN):
        try:
            resources.close()
        except Exception:  # noqa: BLE001 - the interpreter is going: nothing can be done about it any more
            pass


# At exit the interpreter first waits for the threads that are not daemons (Zenoh's session has some), and only
# then runs `atexit`: a Zenoh session left open would make it wait for ever. `threading._register_atexit` runs
# before that wait (concurrent.futures closes its pools there); `atexit` is the fallback where it is missing.
_register = getattr(threading, "_register_atexit", None)
try:
    if _register is None:
        raise AttributeError
    _register(_close_all_at_exit)
except (AttributeError, RuntimeError):
    atexit.register(_close_all_at_exit)


class Client:
    """A client of the DMP cell's server.

    `address` is `HOST:PORT`, `http://HOST:PORT` or `https://HOST:PORT`. A secured server (see the repository's
    docs/security.md) wants TLS, as `dmpctl`'s flags: `tls_ca` (the CA that signed the server's certificate),
    optionally `tls_cert` and `tls_key` (this client's certificate for mutual TLS: its common name names an
    identity) and `server_name` (the name the server's certificate must have; default: the address's host); and
    an identity: a bearer `token` (or `token_file`), sent with every call in the `authorization` metadata, or the
    client certificate. `cell` is the cell of the scene requests and motions (None: the server's default).
    `zenoh_config` is a stock Zenoh configuration file (`zenoh-perception.json5` of `access init`) for
    `publish_obstacle`. Connecting waits at most `timeout` seconds; unary calls at most `call_timeout`.

    Every failure raises `dmp_cell.DmpError` (with the gRPC `code` and the server's `reason`).
    """

    def __init__(
        self,
        address: str = DEFAULT_ADDRESS,
        token: Optional[str] = None,
        *,
        token_file: Optional[conn.PathLike] = None,
        tls_ca: Optional[conn.PathLike] = None,
        tls_cert: Optional[conn.PathLike] = None,
        tls_key: Optional[conn.PathLike] = None,
        server_name: Optional[str] = None,
        cell: Optional[str] = None,
        zenoh_config: Optional[conn.PathLike] = None,
        timeout: float = conn.CONNECT_TIMEOUT_S,
        call_timeout: float = CALL_TIMEOUT_S,
    ):
        self._token = conn.read_token(token, token_file)
        self.cell = check_name("cell", cell) if cell is not None else ""
        self.zenoh_config = str(zenoh_config) if zenoh_config is not None else None
        self.call_timeout = call_timeout
        self._channel, self._target = conn.open_channel(
            address, tls_ca=tls_ca, tls_cert=tls_cert, tls_key=tls_key, server_name=server_name, timeout=timeout
        )
        self._metadata = conn.metadata(self._token)
        self._primitives = primitives_grpc.PrimitiveServiceStub(self._channel)
        self._motion = motion_grpc.MotionServiceStub(self._channel)
        self._scene = scene_grpc.SceneServiceStub(self._channel)
        self._server = server_grpc.ServerServiceStub(self._channel)
        self._robots = robots_grpc.RobotServiceStub(self._channel)
        self._resources = _Resources(self._channel)
        _OPEN.add(self._resources)
        # A client dropped without `close` closes its channel and sessions then, at the latest at exit.
        self._finalizer = weakref.finalize(self, self._resources.close)

    # --- Lifetime ---------------------------------------------------------------------------------------------

    def close(self) -> None:
        """Closes the Zenoh sessions (gracefully: what was published is sent first) and the channel. A script that
        never calls it exits all the same: what a client holds is closed when it is collected, or at exit."""
        self._resources.close()
        _OPEN.discard(self._resources)

    def __enter__(self) -> "Client":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def _call(self, method, request):
        try:
            return method(request, metadata=self._metadata, timeout=self.call_timeout)
        except grpc.RpcError as e:
            raise from_rpc(e) from None

    def _cell(self, cell: Optional[str]) -> str:
        return check_name("cell", cell) if cell is not None else self.cell

    # --- Server -----------------------------------------------------------------------------------------------

    def info(self) -> ServerSummary:
        """How the server is set up (TLS, access control, its default cell, Zenoh locators, limits) and who this
        client is to it: the `dmp.v1.ServerInfo` (its fields read as attributes, `.message` the message itself),
        printed as a one-line summary."""
        return ServerSummary(self._call(self._server.GetInfo, server.GetInfoRequest()))

    # --- Primitives -------------------------------------------------------------------------------------------

    def learn(
        self,
        robot: str,
        name: str,
        t: Sequence[float],
        positions: Any,
        *,
        n_basis: int = 0,
        k: Union[None, float, Sequence[float]] = None,
        d: Union[None, float, Sequence[float]] = None,
        alpha: float = 0.0,
        orientations: Any = None,
    ) -> PrimitiveSummary:
        """Learns a primitive from one demonstration and stores it as the next version of `(robot, name)`; returns
        the stored record once it is durable. `t` are the sample times (strictly increasing), `positions` one row
        per sample (a list of lists or a 2-D numpy array). `n_basis`, `k`, `d` (one value or one per dimension)
        and `alpha` default to the server's (N = 50, K = 1050, critical damping, alpha = 4). `orientations`, one
        unit quaternion (x, y, z, w) per sample, learns a pose primitive. The record returned reads as the
        `dmp.v1.PrimitiveRecord` (`.version`, `.primitive`, `.message`) and prints as a summary, not its weights."""
        times = vector("t", t)
        flat, dim = rows("positions", positions)
        if len(flat) // dim != len(times):
            raise ArgumentError("positions", f"has {len(flat) // dim} rows, t has {len(times)} samples")
        for i in range(1, len(times)):
            if times[i] <= times[i - 1]:
                raise ArgumentError(f"t[{i}]", "sample times must be strictly increasing")

        def gains(field: str, v) -> List[float]:
            if v is None:
                return []
            return [number(field, v)] if isinstance(v, (int, float)) else vector(field, v)

        q: List[float] = []
        if orientations is not None:
            for i, row in enumerate(list(orientations.tolist() if hasattr(orientations, "tolist") else orientations)):
                q.extend(quaternion(f"orientations[{i}]", row))
            if len(q) != 4 * len(times):
                raise ArgumentError("orientations", f"has {len(q) // 4} rows, t has {len(times)} samples")
        request = primitives.LearnRequest(
            robot_id=robot,
            name=name,
            demonstration=types.Demonstration(t=times, positions=flat, dim=dim, orientations=q),
            parameters=types.LearnParameters(
                n_basis=int(n_basis), k=gains("k", k), d=gains("d", d), alpha=number("alpha", alpha)
            ),
        )
        return PrimitiveSummary(self._call(self._primitives.Learn, request).record)

    def get_primitive(self, robot: str, name: str, version: int = 0) -> types.PrimitiveRecord:
        """One primitive: `version` 0 is the latest."""
        return self._call(self._primitives.Get, primitives.GetPrimitiveRequest(robot_id=robot, name=name,
                                                                               version=version))

    def list_primitives(self, robot: str) -> List[types.PrimitiveRecord]:
        """The latest version of each of the robot's primitives, sorted by name (every page)."""
        records: List[types.PrimitiveRecord] = []
        token = ""
        while True:
            page = self._call(self._primitives.List, primitives.ListPrimitivesRequest(robot_id=robot,
                                                                                      page_token=token))
            records.extend(page.records)
            # A token that does not move on would loop forever: the server's pages are sorted by name.
            if not page.next_page_token or page.next_page_token <= token:
                return records
            token = page.next_page_token

    def list_robots(self) -> List[primitives.RobotSummary]:
        """The robots that have primitives (those this client may read), sorted by id (every page): each with
        `robot_id`, `primitives` (its number of names) and `updated_unix_ms`."""
        robots: List[primitives.RobotSummary] = []
        token = ""
        while True:
            page = self._call(self._primitives.ListRobots, primitives.ListRobotsRequest(page_token=token))
            robots.extend(page.robots)
            # A token that does not move on would loop forever: the server's pages are sorted by id.
            if not page.next_page_token or page.next_page_token <= token:
                return robots
            token = page.next_page_token

    def delete_primitive(self, robot: str, name: str) -> int:
        """Deletes every version of `(robot, name)`; returns how many there were."""
        return self._call(self._primitives.Delete, primitives.DeletePrimitiveRequest(robot_id=robot, name=name)
                          ).versions_deleted

    # --- Motion -----------------------------------------------------------------------------------------------

    def plan(
        self,
        robot: str,
        name: str,
        goal: Optional[Sequence[float]] = None,
        *,
        start: Optional[Sequence[float]] = None,
        tau: float = 0.0,
        version: int = 0,
        cell: Optional[str] = None,
        ignore_scene: bool = False,
        dt_s: float = 0.0,
        duration_s: float = 0.0,
        goal_orientation: Optional[Sequence[float]] = None,
        start_orientation: Optional[Sequence[float]] = None,
        limits: Optional[Mapping[str, float]] = None,
        margin: float = 0.0,
        dt: Optional[float] = None,
        duration: Optional[float] = None,
    ) -> Plan:
        """The whole trajectory of the primitive `(robot, name)` at once, around the cell's obstacles: its
        setpoints, the contacts met, whether it stalled, the server's warnings, the limits it kept, and how it
        ended (`verdict`). `dt_s` defaults to 1 ms, `duration_s` to 1.2 tau (`dt` and `duration`, their old names,
        still work with a DeprecationWarning). `limits` maps fields of `dmp.v1.Limits` (`max_speed`, ...) to a bound, a
        negative value turning the limit off (`NO_LIMITS`: all off); a field left out takes the robot's record's,
        then the server's default profile. `margin` is the safety distance from the obstacles, metres (0: the
        record's or the server's, negative: none)."""
        request = motion.PlanRequest(
            motion=self._motion_spec(robot, name, goal, start, tau, version, cell, ignore_scene,
                                     goal_orientation, start_orientation, limits, margin),
            dt=number("dt_s", _renamed("dt", "dt_s", dt, dt_s)),
            duration=number("duration_s", _renamed("duration", "duration_s", duration, duration_s)),
        )
        r = self._call(self._motion.Plan, request)
        setpoints = Setpoints()
        setpoints.push(r.trajectory)
        verdict = verdict_of(r.verdict) if r.HasField("verdict") else None
        limits = limits_of(r.limits) if r.HasField("limits") else None
        return Plan(setpoints, list(r.collisions), r.stalled, [warning_of(w) for w in r.warnings],
                    r.trajectory.scene_version, verdict, limits)

    def _motion_spec(self, robot, name, goal, start, tau, version, cell, ignore_scene, goal_orientation=None,
                     start_orientation=None, limits=None, margin=0.0) -> motion.MotionSpec:
        return motion.MotionSpec(
            robot_id=robot,
            primitive=name,
            version=version,
            start=vector("start", start) if start is not None else [],
            goal=vector("goal", goal) if goal is not None else [],
            tau=number("tau", tau),
            ignore_scene=ignore_scene,
            cell=self._cell(cell),
            goal_orientation=quaternion("goal_orientation", goal_orientation) if goal_orientation is not None else [],
            start_orientation=(quaternion("start_orientation", start_orientation)
                               if start_orientation is not None else []),
            limits=motion_limits(limits) if limits is not None else None,
            margin=number("margin", margin),
        )

    def stream(
        self,
        robot: str,
        name: str,
        goal: Optional[Sequence[float]] = None,
        realtime: bool = False,
        *,
        start: Optional[Sequence[float]] = None,
        tau: float = 0.0,
        version: int = 0,
        cell: Optional[str] = None,
        ignore_scene: bool = False,
        dt_s: float = 0.0,
        segment_s: float = 0.0,
        lookahead_s: float = 0.0,
        max_duration_s: float = 0.0,
        take_over: bool = False,
        deadline_s: Optional[float] = None,
        goal_orientation: Optional[Sequence[float]] = None,
        start_orientation: Optional[Sequence[float]] = None,
        limits: Optional[Mapping[str, float]] = None,
        margin: float = 0.0,
        dt: Optional[float] = None,
    ) -> Stream:
        """Executes the primitive `(robot, name)` (latest `version` by default) as a session, and returns the
        `Stream`: iterate it for the setpoints in force (supersession applied), send it `set_goal`, `set_tau`,
        `pause`, `resume` or `stop` meanwhile. `goal`, `start` and `tau` default to the primitive's; `realtime`
        paces the segments (and the iteration) on the wall clock, otherwise they come as fast as they are read.
        `dt_s`, `segment_s`, `lookahead_s` and `max_duration_s` default to the server's (1 ms, 10 ms, 50 ms, until
        the goal; `dt`, the old name of `dt_s`, still works with a DeprecationWarning); `take_over` ends another
        stream of the robot; `deadline_s` bounds the whole call. A pose primitive's `goal_orientation` and
        `start_orientation` (x, y, z, w) default to its own. `limits` and `margin` as `plan`'s; the stream's
        `limits` says which it keeps, its `verdict` how it ended."""
        request = motion.ExecuteRequest(
            motion=self._motion_spec(robot, name, goal, start, tau, version, cell, ignore_scene, goal_orientation,
                                     start_orientation, limits, margin),
            dt=number("dt_s", _renamed("dt", "dt_s", dt, dt_s)),
            segment_s=number("segment_s", segment_s),
            pacing=motion.PACING_REALTIME if realtime else motion.PACING_AS_FAST_AS_READ,
            lookahead_s=number("lookahead_s", lookahead_s),
            max_duration_s=number("max_duration_s", max_duration_s),
            take_over=take_over,
        )
        return Stream(self._motion, request, self._metadata, realtime, deadline_s)

    # --- Robot records ------------------------------------------------------------------------------------------

    def put_robot(
        self,
        robot: str,
        *,
        limits: Optional[Mapping[str, float]] = None,
        margin: float = 0.0,
        footprint: Optional[Mapping[str, Sequence[float]]] = None,
    ) -> RobotRecord:
        """Stores the record of `robot`, replacing the one before: its `limits` (fields of `dmp.v1.Limits`, SI
        units, 0 or left out meaning no limit on a field), its safety distance `margin` from the obstacles, metres
        (0: the server's default, negative: none), and its `footprint` (`{"semi_axes": [...], "exponents": [...]}`),
        published with its state so that the other robots avoid it. Plans and streams of the robot keep these
        unless a request says otherwise. Returns the stored record."""
        record = robots.RobotRecord(robot_id=check_name("robot", robot), margin=number("margin", margin))
        if limits is not None:
            record.limits.CopyFrom(motion_limits(limits))
        if footprint is not None:
            unknown = set(footprint) - {"semi_axes", "exponents"}
            if unknown:
                raise ArgumentError(f"footprint.{sorted(unknown)[0]}", "expected `semi_axes` and `exponents`")
            record.footprint.CopyFrom(types.Superquadric(
                semi_axes=vector("footprint.semi_axes", footprint.get("semi_axes", [])),
                exponents=vector("footprint.exponents", footprint.get("exponents", [])),
            ))
        return robot_record_of(self._call(self._robots.PutRobot, robots.PutRobotRequest(robot=record)))

    def get_robot(self, robot: str) -> RobotRecord:
        """The record of `robot`; raises `DmpError` (code NOT_FOUND) when it has none."""
        return robot_record_of(self._call(self._robots.GetRobot, robots.GetRobotRequest(robot_id=robot)))

    def delete_robot(self, robot: str) -> None:
        """Deletes the record of `robot` (its primitives stay); raises `DmpError` (NOT_FOUND) when it has none."""
        self._call(self._robots.DeleteRobot, robots.DeleteRobotRequest(robot_id=robot))

    # --- Scene over gRPC --------------------------------------------------------------------------------------

    def put_obstacle(self, obstacle: Mapping[str, Any], cell: Optional[str] = None) -> int:
        """Adds or replaces an obstacle (a dict, see `dmp_cell.obstacles`) over gRPC; returns the scene's
        version."""
        request = scene.PutObstacleRequest(obstacle=obstacle_to_proto(obstacle), cell=self._cell(cell))
        return self._call(self._scene.PutObstacle, request).scene_version

    def delete_obstacle(self, obstacle_id: str, cell: Optional[str] = None) -> bool:
        """Removes an obstacle over gRPC; False when there was none of that id."""
        request = scene.DeleteObstacleRequest(id=obstacle_id, cell=self._cell(cell))
        return self._call(self._scene.DeleteObstacle, request).changed

    def list_obstacles(self, cell: Optional[str] = None) -> Dict[str, Any]:
        """The cell's scene, as `dmpctl scene list` prints it: `{"scene_version": .., "obstacles": [dicts]}`."""
        snapshot = self._call(self._scene.ListObstacles, scene.ListObstaclesRequest(cell=self._cell(cell)))
        return {"scene_version": snapshot.scene_version,
                "obstacles": [obstacle_to_dict(o) for o in snapshot.obstacles]}

    # --- Scene over Zenoh -------------------------------------------------------------------------------------

    def _zenoh_place(self, cell: Optional[str], zenoh_connect: Union[None, str, Sequence[str]]):
        """The cell and the Zenoh endpoints of a publication: the ones given, else the client's cell or the
        server's default cell, and the server's loopback Zenoh locators when the server is on this host and no
        Zenoh configuration file names endpoints (as dmpctl)."""
        connect = [zenoh_connect] if isinstance(zenoh_connect, str) else list(zenoh_connect or [])
        cell = self._cell(cell)
        need_locators = not connect and self.zenoh_config is None
        if not cell or need_locators:
            info = self.info()
            cell = cell or info.cell or "default"
            if need_locators and conn.is_loopback(self._target.host):
                connect = [
                    loc for loc in info.zenoh_locators
                    if "/" in loc and conn.is_loopback(conn.Target(loc.split("/", 1)[1], False).host)
                ]
        return cell, connect

    def _publisher(self, connect: List[str]) -> ObstaclePublisher:
        key = (tuple(connect), self.zenoh_config)
        r = self._resources
        with r.lock:
            if r.closed:
                raise ArgumentError("client", "is closed")
            if key not in r.publishers:
                r.publishers[key] = ObstaclePublisher(connect, self.zenoh_config)
            return r.publishers[key]

    def publish_obstacle(
        self,
        cell: Optional[str],
        obstacle: Mapping[str, Any],
        zenoh_connect: Union[None, str, Sequence[str]] = None,
        *,
        wait_s: float = SUBSCRIBER_WAIT_S,
    ) -> str:
        """Publishes an obstacle dict over Zenoh, as a perception node, on `dmp/<cell>/obstacles/<id>` (returned).
        `cell` None means the client's cell, else the server's default. `zenoh_connect` (an endpoint or a list,
        e.g. `tls/127.0.0.1:7447`) defaults to the endpoints of `zenoh_config`, else to the server's own loopback
        locators (see `info()`). Waits at most `wait_s` for the server's subscriber. The Zenoh session stays open
        for the next publications until `close`."""
        checked = check_obstacle(obstacle)
        cell, connect = self._zenoh_place(cell, zenoh_connect)
        return self._publisher(connect).put(cell, checked, wait_s)

    def unpublish_obstacle(
        self,
        cell: Optional[str],
        obstacle_id: str,
        zenoh_connect: Union[None, str, Sequence[str]] = None,
        *,
        wait_s: float = SUBSCRIBER_WAIT_S,
    ) -> str:
        """Publishes the deletion of an obstacle over Zenoh; returns its key."""
        check_name("id", obstacle_id)
        cell, connect = self._zenoh_place(cell, zenoh_connect)
        return self._publisher(connect).delete(cell, obstacle_id, wait_s)
