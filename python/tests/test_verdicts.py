"""How a run ended (`dmp_cell.Verdict`), on a plan and on a stream, and a goal inside an obstacle refused."""

import grpc
import pytest

import dmp_cell

DEADLINE_S = 60.0


@pytest.fixture(scope="module")
def plain(plain_server, demonstration):
    """A client of the unsecured server, with robot `v1`'s primitive `reach` (0, 0) to (1, 0.5) learned."""
    t, rows = demonstration
    with plain_server.client() as c:
        c.learn("v1", "reach", t=t, positions=rows)
        yield c


def test_a_plan_says_whether_it_reached_its_goal_and_how_far_it_stopped_short(plain):
    short = plain.plan("v1", "reach", ignore_scene=True, duration_s=0.3)
    v = short.verdict
    assert isinstance(v, dmp_cell.Verdict)
    assert v.outcome == "OUT_OF_TIME" and not v.goal_reached
    last = short.setpoints.positions[-1]
    left = ((last[0] - 1.0) ** 2 + (last[1] - 0.5) ** 2) ** 0.5
    assert v.goal_distance == pytest.approx(left, abs=1e-9) and left > 0.1
    assert f"{left:.3f} m short of the goal" in v.reason and "out of time" in v.reason
    assert v.collisions == () and v.min_clearance is None
    assert str(v).startswith("OUT_OF_TIME: ended ")
    reached = plain.plan("v1", "reach", ignore_scene=True, duration_s=4.0).verdict
    assert reached.outcome == "GOAL_REACHED" and reached.goal_reached and reached.goal_distance < 1e-3


def test_the_last_segment_of_a_stream_carries_its_verdict(plain):
    # The server's default profile holds the 2 m/s reach to 1 m/s: it arrives after 3 tau, the default end.
    with plain.stream("v1", "reach", goal=[0.9, 0.4], max_duration_s=6.0, deadline_s=DEADLINE_S) as s:
        assert s.verdict is None
        list(s)
    assert s.status == "GOAL_REACHED"
    assert s.verdict.outcome == "GOAL_REACHED" and s.verdict.goal_reached
    assert "reached the goal" in s.verdict.reason


def test_a_goal_inside_an_obstacle_is_refused_naming_it(plain):
    plain.put_obstacle({"id": "post", "center": [0.9, 0.4], "semi_axes": [0.05, 0.05]})
    try:
        with pytest.raises(dmp_cell.StatusError) as e:
            plain.plan("v1", "reach", goal=[0.9, 0.4])
        assert e.value.code == grpc.StatusCode.FAILED_PRECONDITION
        assert "GOAL_IN_COLLISION" in e.value.reason and "`post`" in e.value.reason
    finally:
        plain.delete_obstacle("post")
