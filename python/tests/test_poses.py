"""Poses through the package against the real server: learn a pose primitive from positions and quaternions,
stream it to a new goal orientation, change the orientation mid-stream, and refuse a quaternion that is not one."""

import math

import pytest

import dmp_cell
from server import ROBOT

DEADLINE_S = 60.0


def about_z(angle):
    """The unit quaternion (x, y, z, w) of `angle` radians about z."""
    return [0.0, 0.0, math.sin(angle / 2), math.cos(angle / 2)]


def angle_between(a, b):
    """The angle of the rotation between two orientations, whatever their signs."""
    dot = abs(sum(x * y for x, y in zip(a, b)))
    return 2 * math.acos(min(1.0, dot))


@pytest.fixture(scope="module")
def turn(server, demonstration):
    """The demonstration's reach, turning 90° about z as it goes: the robot's pose primitive `turn`."""
    t, rows = demonstration
    q = [about_z(math.pi / 2 * (10 * ti**3 - 15 * ti**4 + 6 * ti**5)) for ti in t]
    with server.client("planner") as c:
        return c.learn(ROBOT, "turn", t=t, positions=rows, orientations=q)


def test_a_pose_stream_reaches_its_goal_orientation_with_unit_quaternions(server, turn):
    assert turn.primitive.dim == 5 and len(turn.primitive.orientation_reference) == 4
    goal = about_z(-0.7)
    # The server's default profile holds the 2 m/s reach to 1 m/s: it arrives after 3 tau, the default end.
    with server.client(ROBOT) as c, c.stream(ROBOT, "turn", goal_orientation=goal, max_duration_s=6.0,
                                             deadline_s=DEADLINE_S) as s:
        sps = list(s)
    assert s.status == "GOAL_REACHED"
    assert all(len(sp.position) == 2 and len(sp.orientation) == 4 for sp in sps)
    assert all(abs(math.sqrt(sum(v * v for v in sp.orientation)) - 1) < 1e-12 for sp in sps)
    assert all(len(sp.angular_velocity) == 3 and len(sp.angular_acceleration) == 3 for sp in sps)
    assert math.degrees(angle_between(sps[-1].orientation, goal)) <= 0.1


def test_a_goal_orientation_changed_mid_stream_is_reached(server, turn):
    goal = about_z(2.0)
    with server.client(ROBOT) as c, c.stream(ROBOT, "turn", tau=2.0, deadline_s=DEADLINE_S) as s:
        sps = []
        for sp in s:
            sps.append(sp)
            if len(sps) == 300:
                s.set_goal(None, orientation=goal)
    assert s.status == "GOAL_REACHED"
    assert math.degrees(angle_between(sps[-1].orientation, goal)) <= 0.1
    assert not s.warnings


def test_orientations_that_are_not_unit_quaternions_are_refused_naming_the_argument(server, turn):
    with server.client(ROBOT) as c:
        with pytest.raises(dmp_cell.ArgumentError) as e:
            c.plan(ROBOT, "turn", goal_orientation=[0, 0, 0, 2])
        assert "goal_orientation" in str(e.value)
        with pytest.raises(dmp_cell.ArgumentError) as e:
            c.learn(ROBOT, "bad", t=[0, 1, 2], positions=[[0], [1], [2]], orientations=[[0, 0, 0, 1]] * 2)
        assert "orientations" in str(e.value)
