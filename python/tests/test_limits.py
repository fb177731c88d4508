"""The limits a run keeps (`dmp_cell.LimitsInForce`): on a plan and on the first segment of a stream."""

import dmp_cell

DEADLINE_S = 60.0

#: The server's default profile (`[defaults.limits]`): what a robot without a record keeps.
DEFAULT = {
    "max_speed": 1.0,
    "max_acceleration": 5.0,
    "max_jerk": 50.0,
    "max_angular_speed": 2.0,
    "max_angular_acceleration": 10.0,
    "max_angular_jerk": 100.0,
}


def test_a_plan_and_a_stream_say_which_limits_they_keep(plain_server, demonstration):
    t, rows = demonstration
    with plain_server.client() as c:
        c.learn("l1", "reach", t=t, positions=rows)
        plan = c.plan("l1", "reach", ignore_scene=True, duration_s=4.0)
        assert isinstance(plan.limits, dmp_cell.LimitsInForce)
        assert plan.limits.limits == DEFAULT
        assert plan.limits.profile == "server default"
        assert plan.limits.unlimited == () and plan.limits.margin == 0.01
        assert "max_speed 1, " in str(plan.limits)
        with c.stream("l1", "reach", deadline_s=DEADLINE_S) as s:
            assert s.limits is None
            list(s)
        assert s.limits == plan.limits
