"""A streamed execution: the `MotionService.Session` call, its commands, and its setpoints with supersession applied.

Iterating a `Stream` yields each setpoint in force once, in time order:
- as fast as read, the rows of a segment are released once the next segment has arrived (from its start time on,
  they are superseded) or the stream has ended;
- in real time, each setpoint is released when it is due on the wall clock (`due_unix_s`): a superseding segment
  that arrives before then (a goal change, a scene change) has replaced it, so what is yielded is what the robot
  should execute, and nothing yielded is ever taken back.

Commands (`set_goal`, `set_tau`, `pause`, `resume`, `stop`, `report_state`) can be sent while iterating; the
server applies them from the robot's current time and, in real time, sends a segment that supersedes the points
already sent. A command the server refuses does not end the run: it comes back as a `COMMAND_REJECTED` warning.
The server's warnings are collected in `warnings` and logged on the `dmp_cell` logger.
"""

from __future__ import annotations

import bisect
import logging
import math
import queue
import threading
import time
from typing import Any, Iterator, List, Optional, Sequence

import grpc

from .pb import motion, types
from .errors import DmpError, from_rpc
from .setpoints import (LimitsInForce, ServerWarning, Setpoint, Setpoints, Verdict, segment_limits, segment_verdict,
                        warning_of)
from .values import number, quaternion, vector

log = logging.getLogger("dmp_cell")

_END = object()

#: Rows closer in time than this are the same row (a superseding segment may start at the last row yielded).
_SAME_ROW_S = 1e-9

#: Segments received and not yet applied, at most: a reader that falls behind holds the server back (its stream
#: is bounded too, and so is the transport's window: `connect.STREAM_LOOKAHEAD_BYTES`) rather than growing memory,
#: so that as fast as read a command applies close to the setpoint being read.
QUEUE_SEGMENTS = 16


class Stream:
    """An open session; iterate it for `Setpoint`s. Use it as a context manager (or call `close`) to end the call
    early. After iteration: `status` is the last segment's status (`GOAL_REACHED`, `STOPPED`, ...), `setpoints` all
    setpoints in force (`Setpoints`), `warnings` the server's warnings, `scene_version` and `scene_stale` those of
    the last segment, `verdict` how the run ended (`Verdict`, carried by its last segment; None until then), and
    `limits` the limits it keeps (`LimitsInForce`, carried by its first segment; None until then)."""

    def __init__(self, stub: Any, start: motion.ExecuteRequest, metadata, realtime: bool,
                 deadline_s: Optional[float]):
        self.robot_id = start.motion.robot_id
        self.realtime = realtime
        self.setpoints = Setpoints()
        self.warnings: List[ServerWarning] = []
        self.scene_version = 0
        self.scene_stale = False
        self.verdict: Optional[Verdict] = None
        self.limits: Optional[LimitsInForce] = None
        self._requests: "queue.Queue[object]" = queue.Queue()
        self._segments: "queue.Queue[object]" = queue.Queue(QUEUE_SEGMENTS)
        self._closing = False
        self._ended = False
        self._iterating = False
        self._latest_start = -math.inf
        self._clock_offset: Optional[float] = None
        self._requests.put(motion.SessionRequest(start=start))
        try:
            self._call = stub.Session(self._outgoing(), metadata=metadata, timeout=deadline_s)
        except grpc.RpcError as e:
            raise from_rpc(e) from None
        self._reader = threading.Thread(target=self._read, name=f"dmp_cell stream {self.robot_id}", daemon=True)
        self._reader.start()

    # --- The call ---------------------------------------------------------------------------------------------

    def _outgoing(self) -> Iterator[motion.SessionRequest]:
        while True:
            r = self._requests.get()
            if r is _END:
                return
            yield r

    def _read(self) -> None:
        try:
            for seg in self._call:
                self._segments.put(seg)
        except grpc.RpcError as e:
            if not self._closing:
                self._segments.put(from_rpc(e))
        finally:
            self._segments.put(_END)
            self._requests.put(_END)

    @property
    def status(self) -> Optional[str]:
        """The status of the last segment received (None before the first)."""
        return self.setpoints.last_status

    def close(self) -> None:
        """Ends the call (the server stops the run); idempotent."""
        self._closing = True
        self._call.cancel()
        self._requests.put(_END)
        # The reader may wait for room in the queue: what it holds is dropped.
        deadline = time.monotonic() + 10.0
        while self._reader.is_alive() and time.monotonic() < deadline:
            try:
                self._segments.get(timeout=0.05)
            except queue.Empty:
                pass

    def __enter__(self) -> "Stream":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # --- Commands ---------------------------------------------------------------------------------------------

    def _send(self, request: motion.SessionRequest) -> None:
        if self._ended or self._closing:
            raise DmpError("the session has ended")
        self._requests.put(request)

    def set_goal(self, goal: Optional[Sequence[float]], orientation: Optional[Sequence[float]] = None) -> None:
        """Changes the goal, from the current state (a list, a tuple or a numpy array); a pose run's `orientation`
        (x, y, z, w) too. `goal=None` with an orientation keeps the position goal."""
        request = motion.SetGoal(
            goal=vector("goal", goal) if goal is not None else [],
            goal_orientation=quaternion("orientation", orientation) if orientation is not None else [],
        )
        self._send(motion.SessionRequest(set_goal=request))

    def set_tau(self, tau: float) -> None:
        """Changes tau (larger is slower), from the current state."""
        self._send(motion.SessionRequest(set_tau=motion.SetTau(tau=number("tau", tau))))

    def pause(self) -> None:
        """Holds position."""
        self._send(motion.SessionRequest(pause=motion.Pause()))

    def resume(self) -> None:
        """Resumes after a pause."""
        self._send(motion.SessionRequest(resume=motion.Resume()))

    def stop(self) -> None:
        """Ends the run: the robot decelerates to rest and the stream closes."""
        self._send(motion.SessionRequest(stop=motion.Stop()))

    def report_state(self, position: Sequence[float], velocity: Optional[Sequence[float]] = None,
                     stamp_unix_s: Optional[float] = None) -> None:
        """Reports the robot's measured state (published to the cell; the plan continues from the commanded
        state)."""
        state = types.RobotState(
            robot_id=self.robot_id,
            stamp_unix_s=time.time() if stamp_unix_s is None else float(stamp_unix_s),
            position=vector("position", position),
            velocity=vector("velocity", velocity) if velocity is not None else [],
        )
        self._send(motion.SessionRequest(state=state))

    # --- Setpoints --------------------------------------------------------------------------------------------

    def _apply(self, seg: motion.Segment) -> None:
        self.setpoints.push(seg)
        if len(seg.positions):
            self._latest_start = seg.start_time
        if seg.start_unix_s > 0:
            self._clock_offset = seg.start_unix_s - seg.start_time
        self.scene_version = seg.scene_version
        self.scene_stale = seg.scene_stale
        limits = segment_limits(seg)
        if limits is not None and self.limits is None:
            self.limits = limits
        verdict = segment_verdict(seg)
        if verdict is not None:
            # Real time: a later final segment (a change after the run had ended) supersedes it.
            self.verdict = verdict
        for w in seg.warnings:
            warning = warning_of(w, seg.sequence)
            self.warnings.append(warning)
            log.warning("%s: segment %d: %s", self.robot_id, seg.sequence, warning)

    def _next_item(self, timeout: Optional[float]) -> bool:
        """Applies the next item the reader received, waiting at most `timeout` (None: until one comes; 0: only
        one already there); False when none came. An error of the call is raised."""
        try:
            item = self._segments.get(timeout=timeout) if timeout != 0 else self._segments.get_nowait()
        except queue.Empty:
            return False
        if item is _END:
            self._ended = True
        elif isinstance(item, DmpError):
            self._ended = True
            raise item
        else:
            self._apply(item)
        return True

    def __iter__(self) -> Iterator[Setpoint]:
        if self._iterating:
            raise DmpError("a stream is iterated once")
        self._iterating = True
        return self._run()

    def _run(self) -> Iterator[Setpoint]:
        s = self.setpoints
        last_t = -math.inf
        while True:
            # Every segment already received first: one may supersede the next setpoint.
            while not self._ended and self._next_item(0):
                pass
            # The next row after the last one yielded (a superseding segment never sends time backwards).
            i = bisect.bisect_right(s.t, last_t + _SAME_ROW_S)
            if i < len(s.t):
                if not self.realtime:
                    # As fast as read: final once a later segment starts after it, or the stream has ended.
                    if self._ended or s.t[i] < self._latest_start - _SAME_ROW_S:
                        last_t = s.t[i]
                        yield s.setpoint(i)
                        continue
                else:
                    # Real time: final when it is due.
                    due = None if self._clock_offset is None else self._clock_offset + s.t[i]
                    wait = 0.0 if due is None else due - time.time()
                    if wait <= 0:
                        last_t = s.t[i]
                        yield s.setpoint(i, due)
                        continue
                    if self._ended:
                        time.sleep(wait)  # the pacing itself: nothing more can supersede it
                    else:
                        self._next_item(wait)
                    continue
            elif self._ended:
                return
            self._next_item(None)

    def collect(self) -> Setpoints:
        """Reads the stream to its end (yielding nothing) and returns the setpoints in force."""
        for _ in self:
            pass
        return self.setpoints

