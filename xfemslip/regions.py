"""Reservoir regions: axis-aligned boxes or one simple polygon (pure NumPy).

Used by case_pore.py (validation: does the region hold a cell centre, is the
polygon simple) and poro.py (which cells, quadrature points and fracture
faces lie in the reservoir).  Membership is strict for boxes; a point exactly
on a polygon edge may fall on either side (even-odd rule).
"""

from __future__ import annotations

import numpy as np


def in_boxes(xy: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """(n,) bool: points strictly inside one of the boxes (k, 4) [x0, y0, x1, y1]."""
    xy = np.asarray(xy, float).reshape(-1, 2)
    inside = np.zeros(xy.shape[0], bool)
    for x0, y0, x1, y1 in np.asarray(boxes, float).reshape(-1, 4):
        inside |= (xy[:, 0] > x0) & (xy[:, 0] < x1) & (xy[:, 1] > y0) & (xy[:, 1] < y1)
    return inside


def in_polygon(xy: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """(n,) bool: points inside the polygon (k, 2) [m] (even-odd crossings of a
    ray towards +x)."""
    xy = np.asarray(xy, float).reshape(-1, 2)
    P = np.asarray(polygon, float)
    Q = np.roll(P, -1, axis=0)
    x, y = xy[:, 0:1], xy[:, 1:2]
    straddles = (P[None, :, 1] > y) != (Q[None, :, 1] > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        x_cross = P[None, :, 0] + (y - P[None, :, 1]) * (
            Q[None, :, 0] - P[None, :, 0]
        ) / (Q[None, :, 1] - P[None, :, 1])
    crossings = np.count_nonzero(straddles & (x < x_cross), axis=1)
    return crossings % 2 == 1


def in_region(xy: np.ndarray, reservoir) -> np.ndarray:
    """(n,) bool: points in the reservoir (its polygon, else its boxes)."""
    if reservoir.polygon is not None:
        return in_polygon(xy, reservoir.polygon)
    return in_boxes(xy, reservoir.boxes)


def edges(reservoir) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """(name, start, end) of every edge of the region, named by case key."""
    if reservoir.polygon is not None:
        P = np.asarray(reservoir.polygon, float)
        return [(f"polygon edge {i}", P[i], P[(i + 1) % len(P)]) for i in range(len(P))]
    out = []
    for i, (x0, y0, x1, y1) in enumerate(np.asarray(reservoir.boxes, float)):
        out += [
            (f"box {i}: x0 = {x0:g}", np.array([x0, y0]), np.array([x0, y1])),
            (f"box {i}: x1 = {x1:g}", np.array([x1, y0]), np.array([x1, y1])),
            (f"box {i}: y0 = {y0:g}", np.array([x0, y0]), np.array([x1, y0])),
            (f"box {i}: y1 = {y1:g}", np.array([x0, y1]), np.array([x1, y1])),
        ]
    return out


def _cross(o, a, b) -> float:
    """z of (a - o) x (b - o)."""
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])


def _segments_meet(p1, p2, q1, q2) -> bool:
    """Whether the closed segments p1-p2 and q1-q2 share a point."""
    d1, d2 = _cross(q1, q2, p1), _cross(q1, q2, p2)
    d3, d4 = _cross(p1, p2, q1), _cross(p1, p2, q2)
    if ((d1 > 0) != (d2 > 0)) and ((d3 > 0) != (d4 > 0)) and 0 not in (d1, d2, d3, d4):
        return True

    def on(a, b, c):  # c collinear with a-b and within its box
        return (
            _cross(a, b, c) == 0
            and min(a[0], b[0]) <= c[0] <= max(a[0], b[0])
            and min(a[1], b[1]) <= c[1] <= max(a[1], b[1])
        )

    return on(q1, q2, p1) or on(q1, q2, p2) or on(p1, p2, q1) or on(p1, p2, q2)


def polygon_problem(polygon: np.ndarray) -> str | None:
    """Why the polygon (k >= 3, 2) is not simple, or None: zero area, or two
    edges that meet other than at their shared vertex."""
    P = np.asarray(polygon, float)
    k = len(P)
    area = 0.5 * np.sum(P[:, 0] * np.roll(P[:, 1], -1) - np.roll(P[:, 0], -1) * P[:, 1])
    for i in range(k):
        if np.all(P[i] == P[(i + 1) % k]):
            return f"repeats vertex {i} (vertices {i} and {(i + 1) % k} coincide)"
    for i in range(k):
        for j in range(i + 1, k):
            if j == i + 1 or (i == 0 and j == k - 1):
                continue  # neighbours share a vertex
            if _segments_meet(P[i], P[(i + 1) % k], P[j], P[(j + 1) % k]):
                return f"is not simple: edges {i} and {j} cross or touch"
    if area == 0.0:
        return "has zero area"
    return None
