"""Streams through the package against the real server: to the goal, and with a goal change mid-stream, as fast as
read and in real time (supersession)."""

import math
import time

import pytest

import dmp_cell
from server import ROBOT

DEADLINE_S = 60.0

#: The DMP's own timing, which these tests check: no limits, no safety distance (the server's default profile
#: would hold the 2 m/s reach back).
EXACT = dict(limits=dmp_cell.NO_LIMITS, margin=-1.0)


def norm(v):
    return math.sqrt(sum(x * x for x in v))


def check_continuous(sps, dt):
    """Setpoints one dt apart, strictly in time order, whose positions and velocities change by what one step of
    the largest acceleration allows: no jump anywhere, across segments and supersessions alike."""
    assert len(sps) > 10
    max_acc = max(norm(sp.acceleration) for sp in sps)
    assert max_acc < 1e3, f"implausible acceleration {max_acc}"
    for a, b in zip(sps, sps[1:]):
        step = b.t - a.t
        assert step == pytest.approx(dt, rel=1e-6), f"gap of {step} s at t = {a.t}"
        for i in range(len(a.position)):
            dx = b.position[i] - a.position[i] - a.velocity[i] * step
            assert abs(dx) <= max_acc * step * step + 1e-9, f"position jump at t = {b.t}"
            assert abs(b.velocity[i] - a.velocity[i]) <= max_acc * step * 1.01 + 1e-9, f"velocity jump at {b.t}"


def test_a_stream_reaches_the_goal_with_continuous_setpoints(server, learned):
    goal = [0.9, 0.4]
    with server.client(ROBOT) as c, c.stream(ROBOT, "reach", goal=goal, deadline_s=DEADLINE_S, **EXACT) as s:
        sps = list(s)
    assert s.status == "GOAL_REACHED"
    assert s.setpoints.segments > 10
    # Every setpoint in force was yielded once, in order.
    assert [sp.t for sp in sps] == s.setpoints.t
    assert sps[0].t == pytest.approx(0.0, abs=1e-12)
    assert list(sps[0].position) == pytest.approx(list(learned.primitive.start), abs=1e-9)
    assert norm([a - b for a, b in zip(sps[-1].position, goal)]) < 1e-2
    assert norm(sps[-1].velocity) < 0.05
    assert all(sp.due_unix_s is None for sp in sps)
    check_continuous(sps, 0.001)
    # The motion is the learned one, not a straight line: it bulges off the line from start to goal.
    off_line = max(abs(sp.position[1] - sp.position[0] * goal[1] / goal[0]) for sp in sps)
    assert off_line > 0.01


def test_a_goal_change_mid_stream_is_honoured_even_by_a_reader_that_fell_behind(server, learned):
    new_goal = [0.6, 0.9]
    with server.client(ROBOT) as c, c.stream(ROBOT, "reach", tau=2.0, deadline_s=DEADLINE_S, **EXACT) as s:
        # A robot that is slow to read: the server must not run ahead to the end of the run meanwhile (the
        # stream's buffers are bounded), or the goal change below would come too late.
        time.sleep(0.3)
        sps = []
        for sp in s:
            sps.append(sp)
            if len(sps) == 300:
                s.set_goal(new_goal)
    assert s.status == "GOAL_REACHED"
    assert norm([a - b for a, b in zip(sps[-1].position, new_goal)]) < 2e-3
    check_continuous(sps, 0.001)
    assert not s.warnings


def test_a_goal_change_in_real_time_supersedes_the_points_already_sent(server, learned):
    new_goal = [0.3, 0.8]
    with server.client(ROBOT) as c:
        with c.stream(ROBOT, "reach", realtime=True, deadline_s=DEADLINE_S, **EXACT) as s:
            sps = []
            for sp in s:
                sps.append(sp)
                if len(sps) == 250:
                    s.set_goal(new_goal)
    assert s.status == "GOAL_REACHED"
    # The server had sent points ahead of the wall clock; the superseding segment replaced them, and only the
    # points in force were yielded, each when it was due.
    assert s.setpoints.rows_superseded > 0
    assert [sp.t for sp in sps] == s.setpoints.t
    assert all(sp.due_unix_s is not None for sp in sps)
    due = [sp.due_unix_s for sp in sps]
    assert all(b > a for a, b in zip(due, due[1:]))
    assert norm([a - b for a, b in zip(sps[-1].position, new_goal)]) < 2e-3
    check_continuous(sps, 0.001)


def test_a_refused_command_is_a_warning_and_the_run_goes_on(server, learned):
    with server.client(ROBOT) as c, c.stream(ROBOT, "reach", deadline_s=DEADLINE_S, **EXACT) as s:
        for i, _ in enumerate(s):
            if i == 100:
                s.set_goal([1.0, 2.0, 3.0])
    assert s.status == "GOAL_REACHED"
    rejected = [w for w in s.warnings if w.kind == "COMMAND_REJECTED"]
    assert len(rejected) == 1, s.warnings
    assert rejected[0].field.startswith("set_goal.goal") and rejected[0].reason
    assert list(s.setpoints.positions[-1]) == pytest.approx(list(learned.primitive.goal), abs=1e-2)
    with pytest.raises(dmp_cell.DmpError):
        s.set_goal([0.0, 0.0])


def test_stop_ends_the_stream_at_rest(server, learned):
    # In real time: read as fast as possible, the server may have computed the whole reach before the stop
    # arrives, and the stop then applies at the goal.
    with server.client(ROBOT) as c, c.stream(ROBOT, "reach", realtime=True, deadline_s=DEADLINE_S, **EXACT) as s:
        for i, _ in enumerate(s):
            if i == 200:
                s.stop()
    assert s.status == "STOPPED"
    assert norm(s.setpoints.velocities[-1]) < 0.05
    assert norm([a - b for a, b in zip(s.setpoints.positions[-1], learned.primitive.goal)]) > 0.1


def test_a_plan_is_the_whole_trajectory_at_once(server, learned):
    goal = [0.9, 0.4]
    with server.client(ROBOT) as c:
        plan = c.plan(ROBOT, "reach", goal=goal, dt_s=0.002, **EXACT)
        with c.stream(ROBOT, "reach", goal=goal, dt_s=0.002, deadline_s=DEADLINE_S, **EXACT) as s:
            streamed = s.collect()
    assert not plan.collisions and not plan.stalled and not plan.warnings
    sps = list(plan.setpoints)
    assert sps[-1].t == pytest.approx(1.2, abs=2e-3)  # 1.2 tau
    assert norm([a - b for a, b in zip(sps[-1].position, goal)]) < 2e-2
    check_continuous(sps, 0.002)
    # The plan and the stream are the same motion, point for point.
    n = min(len(sps), len(streamed))
    assert n > 500
    for k in range(n):
        assert plan.setpoints.positions[k] == pytest.approx(streamed.positions[k], abs=1e-9)


def test_measured_states_are_reported_and_a_stale_one_is_dropped(server, learned):
    with server.client(ROBOT) as c, c.stream(ROBOT, "reach", deadline_s=DEADLINE_S, **EXACT) as s:
        for i, sp in enumerate(s):
            if i == 100:
                s.report_state(sp.position, sp.velocity)
            if i == 200:
                s.report_state(sp.position, sp.velocity, stamp_unix_s=time.time() - 3600.0)
    assert s.status == "GOAL_REACHED"
    assert [(w.kind, w.field) for w in s.warnings] == [("STATE_DROPPED", "state.stamp_unix_s")], s.warnings
