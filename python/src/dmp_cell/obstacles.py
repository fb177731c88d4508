"""Obstacles as dicts, in the JSON form of `dmpctl scene put` and the scenario format (the Rust side is
`proto/src/obstacle_json.rs`): `id`, `center`, `semi_axes`, and optionally `exponents` (per axis, >= 1),
`rotation` (rows of a d x d matrix), `velocity` (constant, of the centre), `nested` (`{"n": .., "m": ..}`, the
paper's 3-D form), `margin` (added to every semi-axis) and `ttl_s` (seconds to live; 0: forever).

    {"id": "box", "center": [0.5, 0.5], "semi_axes": [0.1, 0.1]}

`check_obstacle` refuses what the server would (unknown keys, wrong types, lengths that differ from the centre's,
non-positive semi-axes, exponents below 1, ...), naming the field, before anything is sent: over Zenoh the server
could only log and drop it. The server's engine has the last word (e.g. on a rotation that is not orthonormal).
"""

from __future__ import annotations

import math
from typing import Any, Dict, List, Mapping

from .pb import types
from .errors import ArgumentError
from .values import number, vector

#: Keys of an obstacle dict.
OBSTACLE_KEYS = ("id", "center", "semi_axes", "exponents", "rotation", "velocity", "nested", "ttl_s", "margin")

#: Longest name (cell, robot id, obstacle id, primitive name).
MAX_NAME_CHARS = 128


def check_name(field: str, name: Any) -> str:
    """A name that goes into a Zenoh key: 1 to 128 characters of `[A-Za-z0-9_.-]` (`proto/src/keys.rs`)."""
    if not isinstance(name, str) or not 1 <= len(name) <= MAX_NAME_CHARS:
        raise ArgumentError(field, f"must have 1 to {MAX_NAME_CHARS} characters")
    for c in name:
        if not (c.isascii() and (c.isalnum() or c in "_-.")):
            raise ArgumentError(field, f"has `{c}`: only letters, digits, `_`, `-` and `.` are allowed")
    return name


def check_obstacle(obstacle: Mapping[str, Any]) -> Dict[str, Any]:
    """The obstacle as a plain JSON-ready dict (numpy arrays as lists, numbers as floats), checked (see the
    module); raises `ArgumentError` naming the field."""
    if not isinstance(obstacle, Mapping):
        raise ArgumentError("obstacle", "must be a dict")
    unknown = [k for k in obstacle if k not in OBSTACLE_KEYS]
    if unknown:
        raise ArgumentError(str(unknown[0]), f"unknown field, expected one of {list(OBSTACLE_KEYS)}")
    for key in ("id", "center", "semi_axes"):
        if obstacle.get(key) is None:
            raise ArgumentError(key, "missing field")
    out: Dict[str, Any] = {"id": check_name("id", obstacle["id"])}
    center = out["center"] = vector("center", obstacle["center"])
    d = len(center)
    semi_axes = out["semi_axes"] = vector("semi_axes", obstacle["semi_axes"])
    _same_length("semi_axes", semi_axes, d)
    for i, a in enumerate(semi_axes):
        if a <= 0:
            raise ArgumentError(f"semi_axes[{i}]", "must be a finite number greater than zero")
    if obstacle.get("exponents") is not None:
        exponents = out["exponents"] = vector("exponents", obstacle["exponents"])
        _same_length("exponents", exponents, d)
        for i, n in enumerate(exponents):
            if n < 1:
                raise ArgumentError(f"exponents[{i}]", "must be a finite number >= 1")
    if obstacle.get("rotation") is not None:
        rotation = obstacle["rotation"]
        rotation = rotation.tolist() if hasattr(rotation, "tolist") else rotation
        if isinstance(rotation, (str, bytes)) or not hasattr(rotation, "__len__") or len(rotation) != d:
            raise ArgumentError("rotation", f"must have {d} rows of {d} values (the centre's dimension)")
        out["rotation"] = []
        for i, row in enumerate(rotation):
            r = vector(f"rotation[{i}]", row)
            _same_length(f"rotation[{i}]", r, d)
            out["rotation"].append(r)
    if obstacle.get("velocity") is not None:
        out["velocity"] = vector("velocity", obstacle["velocity"])
        _same_length("velocity", out["velocity"], d)
    if obstacle.get("nested") is not None:
        nested = obstacle["nested"]
        if not isinstance(nested, Mapping) or set(nested) != {"n", "m"}:
            raise ArgumentError("nested", "must be {\"n\": .., \"m\": ..}")
        if d != 3:
            raise ArgumentError("nested", "the nested form is 3-D: the centre must have 3 values")
        if "exponents" in out:
            raise ArgumentError("nested", "give exponents or nested, not both")
        out["nested"] = {k: number(f"nested.{k}", nested[k]) for k in ("n", "m")}
        for k, v in out["nested"].items():
            if v < 1:
                raise ArgumentError(f"nested.{k}", "must be a finite number >= 1")
    for key in ("margin", "ttl_s"):
        if obstacle.get(key) is not None:
            v = number(key, obstacle[key])
            if v < 0:
                raise ArgumentError(key, "must be a finite number >= 0")
            if v:
                out[key] = v
    return out


def _same_length(field: str, values: List[float], d: int) -> None:
    if len(values) != d:
        raise ArgumentError(field, f"has {len(values)} values, the centre has {d}")


def obstacle_to_proto(obstacle: Mapping[str, Any]) -> types.Obstacle:
    """The `dmp.v1.Obstacle` of an obstacle dict (checked first)."""
    o = check_obstacle(obstacle)
    m = types.Obstacle(id=o["id"], center=o["center"], velocity=o.get("velocity", []),
                       margin=o.get("margin", 0.0), ttl_s=o.get("ttl_s", 0.0))
    if "nested" in o:
        m.nested.CopyFrom(types.NestedSuperquadric(semi_axes=o["semi_axes"], **o["nested"]))
    else:
        m.superquadric.CopyFrom(types.Superquadric(semi_axes=o["semi_axes"], exponents=o.get("exponents", [])))
    if "rotation" in o:
        m.rotation.extend(v for row in o["rotation"] for v in row)
    return m


def obstacle_to_dict(m: types.Obstacle) -> Dict[str, Any]:
    """The dict of a `dmp.v1.Obstacle` (what `dmpctl scene list` prints); a solid primitive reads
    `"solid": {"type": "BOX", "dimensions": [..]}`."""
    out: Dict[str, Any] = {"id": m.id, "center": list(m.center)}
    shape = m.WhichOneof("shape")
    if shape == "superquadric":
        out["semi_axes"] = list(m.superquadric.semi_axes)
        if m.superquadric.exponents:
            out["exponents"] = list(m.superquadric.exponents)
    elif shape == "nested":
        out["semi_axes"] = list(m.nested.semi_axes)
        out["nested"] = {"n": m.nested.n, "m": m.nested.m}
    elif shape == "solid":
        try:
            kind = types.SolidPrimitive.Type.Name(m.solid.type)
        except ValueError:
            kind = str(m.solid.type)
        out["solid"] = {"type": kind, "dimensions": list(m.solid.dimensions)}
    d = len(m.center)
    if m.rotation and d:
        r = list(m.rotation)
        out["rotation"] = [r[i : i + d] for i in range(0, len(r), d)]
    if m.velocity:
        out["velocity"] = list(m.velocity)
    for key in ("margin", "ttl_s"):
        v = getattr(m, key)
        if v != 0 and math.isfinite(v):
            out[key] = v
    return out
