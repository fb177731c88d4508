"""Obstacles published over Zenoh as a perception node (mutual TLS with the perception certificate), seen in the
scene through gRPC; and the scene over gRPC."""

import pytest

import dmp_cell
from server import CELL, until

SEEN_WITHIN_S = 10.0
#: How long a put may wait for the server's subscriber (the mutual-TLS link of a busy machine).
WAIT_S = 30.0


def ids(c):
    return {o["id"]: o for o in c.list_obstacles()["obstacles"]}


def test_an_obstacle_published_over_zenoh_is_in_the_scene(server):
    box = {"id": "py-box", "center": [0.5, 0.25], "semi_axes": [0.1, 0.05], "exponents": [2, 2],
           "velocity": [0.0, 0.0], "margin": 0.01}
    perception = server.set_dir / "zenoh-perception.json5"
    with server.client("planner", cell=CELL, zenoh_config=perception) as c:
        before = c.list_obstacles()["scene_version"]
        key = c.publish_obstacle(CELL, box, zenoh_connect=server.zenoh_locator, wait_s=WAIT_S)
        assert key == f"dmp/{CELL}/obstacles/py-box"
        took = until("the published obstacle is in the scene", lambda: "py-box" in ids(c), SEEN_WITHIN_S)
        seen = ids(c)["py-box"]
        assert seen["center"] == pytest.approx(box["center"])
        assert seen["semi_axes"] == pytest.approx(box["semi_axes"])
        assert seen["exponents"] == pytest.approx(box["exponents"])
        assert seen["margin"] == pytest.approx(0.01)
        assert c.list_obstacles()["scene_version"] > before
        print(f"obstacle seen through gRPC {took * 1000:.0f} ms after the put")

        # A put of the same id replaces it; a delete removes it.
        moved = dict(box, center=[0.7, 0.2])
        c.publish_obstacle(CELL, moved, zenoh_connect=server.zenoh_locator, wait_s=WAIT_S)
        until("the obstacle moves", lambda: ids(c).get("py-box", {}).get("center") == pytest.approx([0.7, 0.2]),
              SEEN_WITHIN_S)
        c.unpublish_obstacle(CELL, "py-box", zenoh_connect=server.zenoh_locator, wait_s=WAIT_S)
        until("the obstacle is deleted", lambda: "py-box" not in ids(c), SEEN_WITHIN_S)


def test_a_bad_obstacle_is_refused_before_it_is_published(server):
    with server.client("planner", cell=CELL) as c:
        with pytest.raises(dmp_cell.ArgumentError) as e:
            c.publish_obstacle(CELL, {"id": "x", "center": [0, 0], "semi_axes": [0.1, 0]},
                               zenoh_connect=server.zenoh_locator, wait_s=WAIT_S)
        assert e.value.field == "semi_axes[1]"
        with pytest.raises(dmp_cell.ArgumentError) as e:
            c.publish_obstacle(CELL, {"id": "a/b", "center": [0, 0], "semi_axes": [1, 1]},
                               zenoh_connect=server.zenoh_locator, wait_s=WAIT_S)
        assert e.value.field == "id"


def test_without_the_perception_certificate_nothing_is_published(server):
    # A plain peer cannot open a link to the server's mutual-TLS endpoint: no subscriber, a bounded wait, an error.
    with server.client("planner", cell=CELL) as c:
        plain = "tcp/" + server.zenoh_locator.split("/", 1)[1]
        with pytest.raises(dmp_cell.ZenohError):
            c.publish_obstacle(CELL, {"id": "x", "center": [0, 0], "semi_axes": [1, 1]}, zenoh_connect=plain,
                               wait_s=1.0)
        assert "x" not in ids(c)


def test_the_scene_over_grpc(server):
    with server.client("planner", cell=CELL) as c:
        v = c.put_obstacle({"id": "py-grpc", "center": [0.1, 0.2, 0.3], "semi_axes": [0.1, 0.2, 0.3],
                            "nested": {"n": 1, "m": 2}, "rotation": [[0, -1, 0], [1, 0, 0], [0, 0, 1]]})
        assert v >= 1
        seen = ids(c)["py-grpc"]
        assert seen["nested"] == {"n": 1.0, "m": 2.0}
        assert seen["rotation"] == [[0, -1, 0], [1, 0, 0], [0, 0, 1]]
        assert c.delete_obstacle("py-grpc") is True
        assert c.delete_obstacle("py-grpc") is False
