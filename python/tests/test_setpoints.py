"""Supersession (the setpoints in force after a stream of segments), as the Rust client's `Setpoints` tests."""

import pytest

import dmp_cell
from dmp_cell import Setpoints
from dmp_cell.pb import motion


def seg(sequence, t0, n, base, status=motion.RUNNING):
    """A 2-D segment of n points from t0, dt 0.1, position (base + k, -(base + k))."""
    s = motion.Segment(sequence=sequence, start_time=t0, dt=0.1, dim=2, status=status)
    for k in range(n):
        v = base + k
        s.positions.extend([v, -v])
        s.velocities.extend([1.0, -1.0])
        s.accelerations.extend([0.0, 0.0])
    return s


def of(*segments):
    s = Setpoints()
    for x in segments:
        s.push(x)
    return s


def test_consecutive_segments_concatenate():
    s = of(seg(0, 0.0, 3, 0.0), seg(1, 0.3, 3, 3.0))
    assert len(s) == 6 and s.dim == 2 and s.rows_superseded == 0
    for k, sp in enumerate(s):
        assert sp.t == pytest.approx(0.1 * k, abs=1e-12)
        assert sp.position == (k, -k)
        assert sp.sequence == (0 if k < 3 else 1)


def test_a_later_segment_supersedes_from_its_start_time():
    # Segment 0 covers 0.0..=0.9; segment 1 (after a scene change) starts at 0.4: the first four rows stay.
    s = of(seg(0, 0.0, 10, 0.0), seg(1, 0.4, 3, 100.0))
    assert len(s) == 7 and s.rows_superseded == 6
    assert s.positions[3] == (3.0, -3.0)
    assert s.positions[4] == (100.0, -100.0) and s.t[4] == pytest.approx(0.4)
    assert s.positions[6] == (102.0, -102.0)
    # A time that differs from a row's by rounding (0.1 * 3 != 0.3) still supersedes that row.
    s = of(seg(0, 0.0, 5, 0.0), seg(1, 0.1 * 3.0 - 1e-12, 2, 50.0))
    assert len(s) == 5 and s.positions[3] == (50.0, -50.0)
    # A segment starting before everything replaces everything.
    s = of(seg(0, 0.5, 5, 0.0), seg(1, 0.0, 2, 9.0))
    assert len(s) == 2 and s.positions[0] == (9.0, -9.0)


def test_empty_segments_carry_a_status_and_supersede_nothing():
    s = of(seg(0, 0.0, 4, 0.0))
    s.push(motion.Segment(sequence=1, start_time=0.2, dt=0.1, dim=2, status=motion.GOAL_REACHED))
    assert len(s) == 4 and s.segments == 2 and s.last_status == "GOAL_REACHED"


def test_inconsistent_segments_are_refused_and_change_nothing():
    s = of(seg(0, 0.0, 4, 0.0))
    bad = seg(1, 0.4, 2, 0.0)
    del bad.velocities[-1]
    with pytest.raises(dmp_cell.ProtocolError, match="velocities"):
        s.push(bad)
    bad = seg(1, 0.4, 2, 0.0)
    bad.dim = 4
    with pytest.raises(dmp_cell.ProtocolError, match="dim"):
        s.push(bad)
    bad = seg(1, 0.4, 2, 0.0)
    bad.dt = 0.0
    with pytest.raises(dmp_cell.ProtocolError):
        s.push(bad)
    assert len(s) == 4 and s.segments == 1
