"""Obstacle dicts (the JSON of `dmpctl scene put`): checks naming the field, and the round trip through the
schema."""

import numpy as np
import pytest

import dmp_cell
from dmp_cell import check_obstacle, obstacle_to_dict, obstacle_to_proto


def test_a_full_obstacle_round_trips_through_the_schema():
    o = {"id": "e", "center": [0.5, 0.5], "semi_axes": [0.3, 0.2], "exponents": [1, 2],
         "rotation": [[0.0, -1.0], [1.0, 0.0]], "velocity": [0.1, 0.0], "margin": 0.05, "ttl_s": 2.5}
    m = obstacle_to_proto(o)
    assert list(m.rotation) == [0.0, -1.0, 1.0, 0.0]
    assert m.WhichOneof("shape") == "superquadric" and m.ttl_s == 2.5
    assert obstacle_to_dict(m) == check_obstacle(o) == o
    nested = {"id": "n", "center": [0, 0, 0], "semi_axes": [1, 2, 3], "nested": {"n": 1, "m": 2}}
    assert obstacle_to_dict(obstacle_to_proto(nested)) == nested
    # numpy arrays become plain lists; a zero margin or ttl is left out, as the Rust side writes it.
    o = check_obstacle({"id": "b", "center": np.array([0.1, 0.2]), "semi_axes": np.array([1, 1]), "ttl_s": 0})
    assert o == {"id": "b", "center": [0.1, 0.2], "semi_axes": [1.0, 1.0]}


@pytest.mark.parametrize(
    "obstacle, field",
    [
        ({"id": "a", "center": [0, 0], "semi_axes": [1, 1], "bogus": 1}, "bogus"),
        ({"center": [0, 0], "semi_axes": [1, 1]}, "id"),
        ({"id": "a b", "center": [0, 0], "semi_axes": [1, 1]}, "id"),
        ({"id": "a", "center": [0, 0]}, "semi_axes"),
        ({"id": "a", "center": [0, "x"], "semi_axes": [1, 1]}, "center[1]"),
        ({"id": "a", "center": [0, 0], "semi_axes": [1, 1, 1]}, "semi_axes"),
        ({"id": "a", "center": [0, 0], "semi_axes": [1, -1]}, "semi_axes[1]"),
        ({"id": "a", "center": [0, 0], "semi_axes": [1, 1], "exponents": [1, 0.5]}, "exponents[1]"),
        ({"id": "a", "center": [0, 0], "semi_axes": [1, 1], "rotation": [[1, 0]]}, "rotation"),
        ({"id": "a", "center": [0, 0], "semi_axes": [1, 1], "velocity": [1]}, "velocity"),
        ({"id": "a", "center": [0, 0], "semi_axes": [1, 1], "nested": {"n": 1, "m": 1}}, "nested"),
        ({"id": "a", "center": [0, 0], "semi_axes": [1, 1], "ttl_s": -1}, "ttl_s"),
        ({"id": "a", "center": [0, 0], "semi_axes": [1, 1], "margin": float("inf")}, "margin"),
    ],
)
def test_a_bad_obstacle_names_the_field(obstacle, field):
    with pytest.raises(dmp_cell.ArgumentError) as e:
        check_obstacle(obstacle)
    assert e.value.field == field
    assert e.value.is_bad_input()
