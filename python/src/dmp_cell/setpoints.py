"""The setpoints in force after a stream of segments: supersession, as the Rust client's `Setpoints`.

The schema's rule (`motion.proto`, `Segment`): segment `k + 1` supersedes the points of earlier segments from its
`start_time` on, so the setpoint in force at time `t` is the one of the latest segment whose `start_time <= t`.
`Setpoints.push` applies it as segments arrive: each one cuts the rows at and after its start time (a later segment
replaces the not-yet-executed tail of earlier ones), then appends its own points. A segment without points (a final
status) supersedes nothing.
"""

from __future__ import annotations

import bisect
import math
from typing import Dict, List, NamedTuple, Optional, Tuple

from .pb import motion, types
from .errors import ProtocolError

#: Two times closer than this fraction of `dt` are the same row (times are computed as `start + k dt`).
SAME_TIME = 1e-6

#: The statuses that end a run: its last segment carries one of them.
FINAL_STATUSES = ("GOAL_REACHED", "STOPPED")


class Setpoint(NamedTuple):
    """One setpoint: run time `t` (seconds since the start of the run), position, velocity dx/dt and acceleration
    (one value per dimension), the `sequence` of the segment it came from, and in real-time pacing the wall clock
    (Unix seconds) at which it is due (None as fast as read)."""

    t: float
    position: Tuple[float, ...]
    velocity: Tuple[float, ...]
    acceleration: Tuple[float, ...]
    sequence: int
    due_unix_s: Optional[float] = None
    #: A pose run: the orientation (x, y, z, w), the angular velocity and acceleration (world frame, rad/s and
    #: rad/s²); empty tuples for a position run.
    orientation: Tuple[float, ...] = ()
    angular_velocity: Tuple[float, ...] = ()
    angular_acceleration: Tuple[float, ...] = ()


class ServerWarning(NamedTuple):
    """What the server could not use or had to change, and why; the run went on. `kind` is the name of
    `dmp.v1.Warning.Kind` (`OBSTACLE_IGNORED`, `COMMAND_REJECTED`, `SCENE_STALE`, `STATE_DROPPED`,
    `COMPUTE_OVER_BUDGET`), `field` the request field at fault, `obstacle_id` the obstacle concerned, `sequence` the
    segment that carried it (None for a plan)."""

    kind: str
    field: str
    reason: str
    obstacle_id: str
    sequence: Optional[int] = None

    def __str__(self) -> str:
        obstacle = f" (obstacle `{self.obstacle_id}`)" if self.obstacle_id else ""
        field = f" {self.field}:" if self.field else ""
        return f"{self.kind}{obstacle}{field} {self.reason}"


class Verdict(NamedTuple):
    """How a run ended (`dmp.v1.Verdict`: a plan's, or the last segment's of a stream). `outcome` is the name of
    `dmp.v1.Outcome` without its prefix: `GOAL_REACHED`, `STALLED`, `BLOCKED`, `COLLISION`, `BRAKED`, `OUT_OF_TIME`
    or `STOPPED`; `goal_reached` whether every robot was at its goal and at rest at the end; `reason` one line for a
    person (e.g. "ended 0.142 m short of the goal at 3 tau, t = 3.000 s (out of time)"); `goal_distance` the distance
    left at the last point (`goal_angle` a pose run's angle, radians); `min_clearance` the smallest clearance from the
    obstacles over the run, metres (None when the server did not measure it); `collisions` the ids of the obstacles
    a setpoint was inside of."""

    outcome: str
    goal_reached: bool
    reason: str
    goal_distance: float
    goal_angle: float
    min_clearance: Optional[float]
    collisions: Tuple[str, ...]

    def __str__(self) -> str:
        return f"{self.outcome}: {self.reason}"


class LimitsInForce(NamedTuple):
    """The limits a run keeps (`dmp.v1.LimitsInForce`: a plan's, or the first segment's of a stream), after its
    request, its robot's record and the server's default profile. `limits` maps each field of `dmp.v1.Limits`
    (`max_speed` m/s, `max_acceleration` m/s², `max_jerk` m/s³, and the angular ones in rad) to its bound, None where
    there is none; `profile` names where they came from (e.g. "request + server default"); `unlimited` the fields
    without a limit; `margin` the safety distance kept from every obstacle, metres (0: none)."""

    limits: Dict[str, Optional[float]]
    profile: str
    unlimited: Tuple[str, ...]
    margin: float

    def __str__(self) -> str:
        bounds = ", ".join(f"{k} {v:g}" if v is not None else f"no {k}" for k, v in self.limits.items())
        return f"{bounds}, margin {self.margin:g} m ({self.profile})"


#: The fields of `dmp.v1.Limits`, in the message's order.
LIMIT_FIELDS = ("max_speed", "max_acceleration", "max_jerk", "max_angular_speed", "max_angular_acceleration",
                "max_angular_jerk")


def limits_of(l: motion.LimitsInForce) -> LimitsInForce:
    """The `LimitsInForce` of a `dmp.v1.LimitsInForce` message."""
    bounds = {f: (getattr(l.limits, f) if getattr(l.limits, f) > 0 else None) for f in LIMIT_FIELDS}
    return LimitsInForce(bounds, l.profile, tuple(l.unlimited), l.margin)


def segment_limits(seg: motion.Segment) -> Optional[LimitsInForce]:
    """The limits in force a segment carries (only the first segment of a run has them), else None."""
    return limits_of(seg.limits) if seg.HasField("limits") else None


def verdict_of(v: motion.Verdict) -> Verdict:
    """The `Verdict` of a `dmp.v1.Verdict` message."""
    try:
        outcome = motion.Outcome.Name(v.outcome)
    except ValueError:
        outcome = f"UNKNOWN({v.outcome})"
    if outcome.startswith("OUTCOME_"):
        outcome = outcome[len("OUTCOME_"):]
    clearance = v.min_clearance if v.HasField("min_clearance") else None
    return Verdict(outcome, v.goal_reached, v.reason, v.goal_distance, v.goal_angle, clearance, tuple(v.collisions))


def segment_verdict(seg: motion.Segment) -> Optional[Verdict]:
    """The verdict a segment carries (only the last segment of a run has one), else None."""
    return verdict_of(seg.verdict) if seg.HasField("verdict") else None


def warning_of(w: types.Warning, sequence: Optional[int] = None) -> ServerWarning:
    try:
        kind = types.Warning.Kind.Name(w.kind)
    except ValueError:
        kind = str(w.kind)
    return ServerWarning(kind, w.field, w.reason, w.obstacle_id, sequence)


def status_name(status: int) -> str:
    """The name of a `dmp.v1.SegmentStatus` value (`RUNNING`, `GOAL_REACHED`, ...)."""
    try:
        return motion.SegmentStatus.Name(status)
    except ValueError:
        return f"UNKNOWN({status})"


class Setpoints:
    """The setpoints in force after the segments pushed so far, as parallel lists: `t`, and per row `positions`,
    `velocities`, `accelerations` (tuples of `dim` values) and `sequences` (the segment each row came from)."""

    def __init__(self) -> None:
        self.dim: Optional[int] = None
        self.t: List[float] = []
        self.positions: List[Tuple[float, ...]] = []
        self.velocities: List[Tuple[float, ...]] = []
        self.accelerations: List[Tuple[float, ...]] = []
        self.sequences: List[int] = []
        #: A pose run's rows (empty tuples for a position run).
        self.orientations: List[Tuple[float, ...]] = []
        self.angular_velocities: List[Tuple[float, ...]] = []
        self.angular_accelerations: List[Tuple[float, ...]] = []
        self.segments = 0
        self.last_status: Optional[str] = None
        #: Rows of earlier segments that later ones replaced.
        self.rows_superseded = 0

    def __len__(self) -> int:
        return len(self.t)

    def push(self, seg: motion.Segment) -> int:
        """Applies one segment; returns the index of its first row (where the cut was made). A segment that is
        inconsistent (a value count that is not `points x dim`, a dimension other than the earlier segments', a bad
        `dt`) raises `ProtocolError` and changes nothing."""
        d = seg.dim

        def bad(message: str) -> ProtocolError:
            return ProtocolError(f"segment {seg.sequence}: {message}")

        if d == 0:
            if seg.positions or seg.velocities or seg.accelerations:
                raise bad("dim is 0 but it has points")
            self._note(seg)
            return len(self.t)
        n = len(seg.positions)
        rows = n // d
        for name, values in (("positions", seg.positions), ("velocities", seg.velocities),
                             ("accelerations", seg.accelerations)):
            if len(values) != rows * d or n % d:
                raise bad(f"{name} has {len(values)} values, expected points x dim = {rows} x {d}")
        pose = bool(seg.orientations)
        for name, values, width in (("orientations", seg.orientations, 4),
                                    ("angular_velocities", seg.angular_velocities, 3),
                                    ("angular_accelerations", seg.angular_accelerations, 3)):
            if pose and len(values) != rows * width:
                raise bad(f"{name} has {len(values)} values, expected points x {width} = {rows * width}")
        if self.dim is not None and self.dim != d:
            raise bad(f"dim is {d}, earlier segments had {self.dim}")
        if rows == 0:
            self._note(seg)
            return len(self.t)
        if not (math.isfinite(seg.dt) and seg.dt > 0 and math.isfinite(seg.start_time)):
            raise bad(f"start_time {seg.start_time} and dt {seg.dt} must be finite, dt > 0")
        self.dim = d
        keep = bisect.bisect_left(self.t, seg.start_time - SAME_TIME * seg.dt)
        self.rows_superseded += len(self.t) - keep
        for column in (self.t, self.positions, self.velocities, self.accelerations, self.sequences,
                       self.orientations, self.angular_velocities, self.angular_accelerations):
            del column[keep:]
        q, w, wd = list(seg.orientations), list(seg.angular_velocities), list(seg.angular_accelerations)
        x, v, a = list(seg.positions), list(seg.velocities), list(seg.accelerations)
        for k in range(rows):
            r = slice(k * d, (k + 1) * d)
            self.t.append(seg.start_time + k * seg.dt)
            self.positions.append(tuple(x[r]))
            self.velocities.append(tuple(v[r]))
            self.accelerations.append(tuple(a[r]))
            self.sequences.append(seg.sequence)
            self.orientations.append(tuple(q[4 * k:4 * k + 4]) if pose else ())
            self.angular_velocities.append(tuple(w[3 * k:3 * k + 3]) if pose else ())
            self.angular_accelerations.append(tuple(wd[3 * k:3 * k + 3]) if pose else ())
        self._note(seg)
        return keep

    def _note(self, seg: motion.Segment) -> None:
        self.segments += 1
        self.last_status = status_name(seg.status)

    def setpoint(self, i: int, due_unix_s: Optional[float] = None) -> Setpoint:
        """Row `i` as a `Setpoint`."""
        return Setpoint(self.t[i], self.positions[i], self.velocities[i], self.accelerations[i], self.sequences[i],
                        due_unix_s, self.orientations[i], self.angular_velocities[i], self.angular_accelerations[i])

    def __iter__(self):
        return (self.setpoint(i) for i in range(len(self.t)))
