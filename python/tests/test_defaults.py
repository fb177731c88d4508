"""The server on its defaults (plaintext gRPC and Zenoh on loopback, no access control): nothing to configure,
and obstacles go to the Zenoh locators the server reports (GetInfo), in its default cell, as with dmpctl."""

from server import until


def test_a_plain_client_learns_streams_and_publishes_with_no_options(plain_server, demonstration):
    t, rows = demonstration
    with plain_server.client() as c:
        info = c.info()
        assert not info.tls and not info.access_control and info.cell == "default"
        assert c.learn("r9", "reach", t=t, positions=rows).version == 1
        # The server's default profile holds the 2 m/s reach to 1 m/s: it arrives after 3 tau, the default end.
        with c.stream("r9", "reach", max_duration_s=6.0, deadline_s=60) as s:
            last = list(s)[-1]
        assert s.status == "GOAL_REACHED"
        assert all(abs(a - b) < 1e-2 for a, b in zip(last.position, rows[-1])), last
        box = {"id": "plain-box", "center": [2.0, 2.0], "semi_axes": [0.1, 0.1]}
        key = c.publish_obstacle(None, box, wait_s=30.0)
        assert key == "dmp/default/obstacles/plain-box"
        until("the obstacle is in the default cell's scene",
              lambda: [o["id"] for o in c.list_obstacles()["obstacles"]] == ["plain-box"], 10.0)
