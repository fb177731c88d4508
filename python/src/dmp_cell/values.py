"""Checks of the numbers a caller passes (lists, tuples or numpy arrays; numpy is never required), each error
naming the argument and the index at fault."""

from __future__ import annotations

import math
from typing import Any, List, Tuple

from .errors import ArgumentError


def _plain(value: Any) -> Any:
    """A numpy array (or anything with `tolist`) as nested lists; other values as they are."""
    tolist = getattr(value, "tolist", None)
    return tolist() if callable(tolist) else value


def number(field: str, value: Any) -> float:
    """A finite float."""
    if isinstance(value, bool):
        raise ArgumentError(field, "must be a number")
    try:
        v = float(_plain(value))
    except (TypeError, ValueError):
        raise ArgumentError(field, "must be a number") from None
    if not math.isfinite(v):
        raise ArgumentError(field, "must be a finite number")
    return v


def vector(field: str, values: Any) -> List[float]:
    """A non-empty list of finite floats."""
    values = _plain(values)
    if isinstance(values, (str, bytes)) or not hasattr(values, "__iter__"):
        raise ArgumentError(field, "must be a list of numbers")
    out = [number(f"{field}[{i}]", v) for i, v in enumerate(values)]
    if not out:
        raise ArgumentError(field, "must not be empty")
    return out


def rows(field: str, values: Any) -> Tuple[List[float], int]:
    """A list of rows of the same length (a 2-D numpy array, or a list of lists), flattened row-major, and that
    length."""
    values = _plain(values)
    if isinstance(values, (str, bytes)) or not hasattr(values, "__iter__"):
        raise ArgumentError(field, "must be a list of rows (a list of lists or a 2-D array)")
    flat: List[float] = []
    dim = None
    for i, row in enumerate(values):
        r = vector(f"{field}[{i}]", row)
        if dim is None:
            dim = len(r)
        elif len(r) != dim:
            raise ArgumentError(f"{field}[{i}]", f"has {len(r)} values, the first row has {dim}")
        flat.extend(r)
    if dim is None:
        raise ArgumentError(field, "must not be empty")
    return flat, dim


def quaternion(field: str, values: Any) -> List[float]:
    """A unit quaternion (x, y, z, w): four finite floats whose norm is within 1e-6 of 1 (the server's rule)."""
    q = vector(field, values)
    if len(q) != 4:
        raise ArgumentError(field, f"must be 4 numbers (x, y, z, w), found {len(q)}")
    norm = math.sqrt(sum(v * v for v in q))
    if abs(norm - 1.0) > 1e-6:
        raise ArgumentError(field, f"must be a unit quaternion (x, y, z, w): its norm is {norm}")
    return q
