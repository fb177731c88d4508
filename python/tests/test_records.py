"""What learn() and info() return prints as a summary; the keywords say their units as the gRPC fields and dmpctl
do (the old names warn); robot records hold limits and a margin."""

import warnings

import pytest

import dmp_cell


def test_learn_and_info_print_a_summary_and_read_as_their_messages(plain_server, demonstration):
    t, rows = demonstration
    with plain_server.client() as c:
        record = c.learn("rec1", "reach", t=t, positions=rows, n_basis=30)
        text = repr(record)
        assert text.startswith("PrimitiveRecord(rec1/reach v1: 2-D, N 30, tau 1 s, goal [1.0, 0.5"), text
        assert len(text) < 200 and "weights" not in text
        assert record.version == 1 and record.primitive.n_basis == 30
        assert record == c.get_primitive("rec1", "reach")
        info = c.info()
        assert repr(info).startswith("ServerInfo(version ") and "plaintext" in repr(info), repr(info)
        assert info.cell == info.message.cell


def test_keywords_in_seconds_and_the_old_names_warn(plain_server, demonstration):
    t, rows = demonstration
    with plain_server.client() as c:
        c.learn("rec2", "reach", t=t, positions=rows)
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            new = c.plan("rec2", "reach", ignore_scene=True, dt_s=0.002, duration_s=0.5)
        assert len(new.setpoints) == 251
        with pytest.warns(DeprecationWarning, match="`duration` is now `duration_s`"):
            old = c.plan("rec2", "reach", ignore_scene=True, dt_s=0.002, duration=0.5)
        assert len(old.setpoints) == 251
        with pytest.raises(dmp_cell.ArgumentError, match="dt_s"):
            c.plan("rec2", "reach", dt=0.001, dt_s=0.002)
        assert new.verdict is not None and new.verdict.outcome == "OUT_OF_TIME"


def test_robot_records_hold_limits_margin_and_footprint(plain_server):
    with plain_server.client() as c:
        stored = c.put_robot("rec3", limits={"max_speed": 0.5, "max_acceleration": 2.0}, margin=0.02,
                             footprint={"semi_axes": [0.1, 0.1], "exponents": [1, 1]})
        assert stored.robot_id == "rec3" and stored.updated_unix_ms > 0
        got = c.get_robot("rec3")
        assert got.limits == {"max_speed": 0.5, "max_acceleration": 2.0}
        assert got.margin == pytest.approx(0.02)
        assert got.footprint == {"semi_axes": (0.1, 0.1), "exponents": (1.0, 1.0)}
        with pytest.raises(dmp_cell.ArgumentError, match="limits.max_sped"):
            c.put_robot("rec3", limits={"max_sped": 1.0})
        c.delete_robot("rec3")
        with pytest.raises(dmp_cell.DmpError) as e:
            c.get_robot("rec3")
        assert "NOT_FOUND" in str(e.value.code)
