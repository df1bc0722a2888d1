"""Checks of a fracture polyline: zero-length segments, self-intersection,
a fracture that misses the domain.

Private helper of :mod:`xfemslip.case`, which stays the ONLY entry point for
validating user input (house style: case.py is the only place user input is
validated); import the public names from ``xfemslip.case``, not from here.
"""

from __future__ import annotations

import numpy as np

from xfemslip.case_grid import _Grid
from xfemslip.case_tables import _exact, _fmt, _Table
from xfemslip.polyline import first_meeting


def _self_intersection(points: np.ndarray) -> tuple[int, int] | None:
    """First pair (i, j) of segments that cross, touch or fold back, else None
    (a sweep over the segments' boxes: the cost follows the pairs that come
    close, not all pairs)."""
    return first_meeting(points)


def _segment_meets_box(a: np.ndarray, b: np.ndarray, lo, hi) -> bool:
    """Whether segment a-b has a point in the closed box [lo, hi] (Liang-Barsky)."""
    t0, t1 = 0.0, 1.0
    for axis in (0, 1):
        # Python floats: an overflow gives inf, which the min/max below handle.
        d = float(b[axis]) - float(a[axis])
        if d == 0.0:
            if not lo[axis] <= a[axis] <= hi[axis]:
                return False
            continue
        ta = (float(lo[axis]) - float(a[axis])) / d
        tb = (float(hi[axis]) - float(a[axis])) / d
        t0, t1 = max(t0, min(ta, tb)), min(t1, max(ta, tb))
    return t0 <= t1


@np.errstate(over="ignore")
def _check_polyline(table: _Table, points: np.ndarray, grid: _Grid | None) -> None:
    """Zero-length segments, self-intersection, and a fracture off the domain."""
    name = "points" if table.has("points") else "length"
    lengths = np.hypot(*np.diff(points, axis=0).T)
    if not lengths.any():
        table.error(name, "fracture has zero length (all its points coincide)")
        return
    for j in np.flatnonzero(lengths == 0.0):
        x, y = points[j]
        table.error(
            f"points[{j + 1}]",
            f"repeats the previous point ({_exact(x)}, {_exact(y)}): "
            "zero-length segment",
        )
    if not lengths.all():
        return
    pair = _self_intersection(points)
    if pair is not None:
        table.error(
            "points",
            f"self-intersecting polyline: segments {pair[0]} and "
            f"{pair[1]} touch or cross",
        )
    if grid is None:
        return
    lo = grid.origin
    hi = (lo[0] + grid.size[0], lo[1] + grid.size[1])
    if not any(
        _segment_meets_box(a, b, lo, hi)
        for a, b in zip(points[:-1], points[1:], strict=True)
    ):
        table.error(
            None,
            f"lies outside the domain [{_fmt(lo[0])}, {_fmt(hi[0])}] x "
            f"[{_fmt(lo[1])}, {_fmt(hi[1])}]",
        )
