"""Refused requests raise the package's exception with the gRPC status and the server's reason."""

import grpc
import pytest

import dmp_cell
from server import ROBOT


def test_an_invalid_argument_names_the_field(server):
    with server.client("planner") as c:
        with pytest.raises(dmp_cell.StatusError) as e:
            c.learn("bad robot!", "reach", t=[0.0, 0.5, 1.0], positions=[[0.0], [0.5], [1.0]])
    err = e.value
    assert isinstance(err, dmp_cell.DmpError) and err.is_bad_input()
    assert err.code == grpc.StatusCode.INVALID_ARGUMENT
    assert err.field == "robot_id"
    assert "robot_id" in err.reason and "INVALID_ARGUMENT" in str(err)


def test_a_missing_primitive_ends_the_stream_with_not_found(server, learned):
    with server.client(ROBOT) as c, c.stream(ROBOT, "no-such-primitive", deadline_s=30) as s:
        with pytest.raises(dmp_cell.StatusError) as e:
            list(s)
    assert e.value.code == grpc.StatusCode.NOT_FOUND
    assert "no-such-primitive" in e.value.reason


def test_a_goal_of_the_wrong_dimension_is_refused(server, learned):
    with server.client(ROBOT) as c, c.stream(ROBOT, "reach", goal=[1.0, 2.0, 3.0], deadline_s=30) as s:
        with pytest.raises(dmp_cell.StatusError) as e:
            list(s)
    assert e.value.code == grpc.StatusCode.INVALID_ARGUMENT
    assert e.value.field and "goal" in e.value.field


def test_a_robot_cannot_steer_another_robot(server, learned):
    with server.client(ROBOT) as c, c.stream("r2", "reach", deadline_s=30) as s:
        with pytest.raises(dmp_cell.StatusError) as e:
            list(s)
    assert e.value.code == grpc.StatusCode.PERMISSION_DENIED
    assert ROBOT in e.value.reason


def test_a_robot_cannot_learn(server, demonstration):
    t, rows = demonstration
    with server.client(ROBOT) as c:
        with pytest.raises(dmp_cell.StatusError) as e:
            c.learn(ROBOT, "mine", t=t, positions=rows)
    assert e.value.code == grpc.StatusCode.PERMISSION_DENIED
