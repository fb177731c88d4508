"""Learning through the package against the real server."""

import numpy as np
import pytest

import dmp_cell
from server import ROBOT


def test_learn_stores_the_demonstration_as_the_next_version(server, demonstration, learned):
    t, rows = demonstration
    assert learned.robot_id == ROBOT and learned.name == "reach" and learned.version >= 1
    p = learned.primitive
    assert p.dim == 2 and p.n_basis == 50
    assert list(p.start) == pytest.approx(rows[0], abs=1e-12)
    assert list(p.goal) == pytest.approx(rows[-1], abs=1e-12)
    assert p.tau == pytest.approx(1.0, abs=1e-9)
    with server.client("planner") as c:
        # A numpy array (and numpy times) is taken as the list of rows is; the next version is stored.
        again = c.learn(ROBOT, "reach-np", t=np.asarray(t), positions=np.asarray(rows), n_basis=30, k=800.0)
        assert again.version == 1 and again.primitive.n_basis == 30
        assert list(again.primitive.k) == [800.0, 800.0]
        second = c.learn(ROBOT, "reach-np", t=t, positions=rows)
        assert second.version == 2
        names = {r.name: r.version for r in c.list_primitives(ROBOT)}
        assert names["reach-np"] == 2 and names["reach"] == learned.version
        robots = {r.robot_id: r for r in c.list_robots()}
        assert robots[ROBOT].primitives == len(names) and robots[ROBOT].updated_unix_ms > 0
        assert c.get_primitive(ROBOT, "reach-np", version=1).primitive.n_basis == 30
        assert c.delete_primitive(ROBOT, "reach-np") == 2


def test_a_demonstration_that_breaks_a_rule_is_refused_before_it_is_sent(server):
    with server.client("planner") as c:
        with pytest.raises(dmp_cell.ArgumentError) as e:
            c.learn(ROBOT, "bad", t=[0.0, 0.1, 0.2], positions=[[0, 0], [1, 1], [2]])
        assert e.value.field == "positions[2]"
        with pytest.raises(dmp_cell.ArgumentError) as e:
            c.learn(ROBOT, "bad", t=[0.0, 0.2, 0.1], positions=[[0], [1], [2]])
        assert e.value.field == "t[2]"
        with pytest.raises(dmp_cell.ArgumentError) as e:
            c.learn(ROBOT, "bad", t=[0.0, 0.1], positions=[[0, float("nan")], [1, 1]])
        assert e.value.field == "positions[0][1]"
