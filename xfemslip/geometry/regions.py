"""Regions of rock units: boxes, one simple polygon, a layer between two
horizons, or a layer displaced across a fault (pure NumPy).

Used by xfemslip.case (validation: does the region hold a cell centre, is the
polygon simple) and xfemslip.fem.zones (which cells, quadrature points and
fracture faces lie in which unit).  Membership is strict for boxes and
layers; a point exactly on a polygon edge may fall on either side (even-odd
rule).  A displaced layer ("offset") takes its side of the fault from the
fault line itself, so its boundary along the fault is the fault, exactly.
"""

from __future__ import annotations

import numpy as np

from xfemslip.geometry.box import Box
from xfemslip.geometry.polyline import first_meeting


def in_boxes(xy: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """(n,) bool: points strictly inside one of the boxes (k, 4) [x0, y0, x1, y1]."""
    xy = np.asarray(xy, float).reshape(-1, 2)
    inside = np.zeros(xy.shape[0], bool)
    for corners in np.asarray(boxes, float).reshape(-1, 4):
        inside |= Box.from_corners(*corners).contains(xy)
    return inside


# Point-edge pairs tested at once by in_polygon (bounds a chunk's memory).
_PAIR_CHUNK = 1 << 20


def in_polygon(xy: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """(n,) bool: points inside the polygon (k, 2) [m] (even-odd crossings of a
    ray towards +x).

    An edge P-Q can only cross the ray of a point whose y lies in
    [min(P_y, Q_y), max(P_y, Q_y)); with the points sorted by y those points
    are a contiguous run, so only these (point, edge) pairs are formed, in
    chunks: the work follows the number of edges a horizontal line meets, not
    points x edges.
    """
    # matplotlib.path.Path.contains_points (a dependency) gives the same
    # answer off the edges (tests/unit/geometry/test_regions_polygon.py) but
    # tests every point against every edge: 11 times slower for 100,000
    # points in a polygon of 5,000 or 50,000 vertices (a digitised outline),
    # faster only for a few edges, where either takes well under a second.
    xy = np.asarray(xy, float).reshape(-1, 2)
    P = np.asarray(polygon, float)
    Q = np.roll(P, -1, axis=0)
    order = np.argsort(xy[:, 1], kind="stable")
    ys = xy[order, 1]
    first = np.searchsorted(ys, np.minimum(P[:, 1], Q[:, 1]), side="left")
    stop = np.searchsorted(ys, np.maximum(P[:, 1], Q[:, 1]), side="left")
    count = stop - first
    crossings = np.zeros(xy.shape[0], np.int64)
    edge = 0
    while edge < len(P):
        end = edge + max(
            1, int(np.searchsorted(np.cumsum(count[edge:]), _PAIR_CHUNK, "right"))
        )
        block = count[edge:end]
        e = np.repeat(np.arange(edge, end), block)
        pos = np.repeat(first[edge:end] - np.cumsum(block) + block, block)
        pt = order[pos + np.arange(e.size)]
        x, y = xy[pt, 0], xy[pt, 1]
        with np.errstate(divide="ignore", invalid="ignore"):
            x_cross = P[e, 0] + (y - P[e, 1]) * (Q[e, 0] - P[e, 0]) / (
                Q[e, 1] - P[e, 1]
            )
        crossings += np.bincount(pt[x < x_cross], minlength=xy.shape[0])
        edge = end
    return crossings % 2 == 1


def fault_x(y: np.ndarray, fault: np.ndarray) -> np.ndarray:
    """x [m] of the fault line at heights y: the polyline ``fault`` (k, 2),
    strictly monotone in y, extended straight beyond its ends."""
    P = np.asarray(fault, float)
    if P[-1, 1] < P[0, 1]:
        P = P[::-1]
    y = np.asarray(y, float)
    x = np.interp(y, P[:, 1], P[:, 0])
    below, above = y < P[0, 1], y > P[-1, 1]
    if below.any():
        slope = (P[1, 0] - P[0, 0]) / (P[1, 1] - P[0, 1])
        x = np.where(below, P[0, 0] + slope * (y - P[0, 1]), x)
    if above.any():
        slope = (P[-1, 0] - P[-2, 0]) / (P[-1, 1] - P[-2, 1])
        x = np.where(above, P[-1, 0] + slope * (y - P[-1, 1]), x)
    return x


def fault_side(xy: np.ndarray, fault: np.ndarray) -> np.ndarray:
    """(n,) bool: points right of the fault line (x > fault_x(y))."""
    xy = np.asarray(xy, float).reshape(-1, 2)
    return xy[:, 0] > fault_x(xy[:, 1], fault)


def in_layer(xy: np.ndarray, base: float, top: float) -> np.ndarray:
    """(n,) bool: points strictly between the horizons y = base < top."""
    y = np.asarray(xy, float).reshape(-1, 2)[:, 1]
    return (y > base) & (y < top)


def offset_span(region, right: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(base, top) [m] of a displaced layer on each point's side of its fault
    (``right``: (n,) bool from :func:`fault_side`)."""
    lowered = right if region.lowered == "right" else ~right
    shift = np.where(lowered, region.throw, 0.0)
    return region.base - shift, region.top - shift


def in_region(xy: np.ndarray, region) -> np.ndarray:
    """(n,) bool: points in the region (a RegionSpec, or a ReservoirSpec:
    its polygon, else its boxes)."""
    kind = getattr(region, "kind", None)
    if kind == "layer":
        return in_layer(xy, region.base, region.top)
    if kind == "offset":
        xy = np.asarray(xy, float).reshape(-1, 2)
        base, top = offset_span(region, fault_side(xy, region.fault))
        return (xy[:, 1] > base) & (xy[:, 1] < top)
    if region.polygon is not None:
        return in_polygon(xy, region.polygon)
    return in_boxes(xy, region.boxes)


def edges(region, box: Box | None = None) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """(name, start, end) of every edge of the region, named by case key.

    A layer's horizons (and a displaced layer's, each ending at the fault)
    run across ``box``, the domain; without it they are left out."""
    kind = getattr(region, "kind", None)
    if kind in ("layer", "offset"):
        return [] if box is None else _horizon_edges(region, box)
    if region.polygon is not None:
        P = np.asarray(region.polygon, float)
        return [(f"polygon edge {i}", P[i], P[(i + 1) % len(P)]) for i in range(len(P))]
    out = []
    for i, corners in enumerate(np.asarray(region.boxes, float)):
        x0, x1, y0, y1 = Box.from_corners(*corners)
        out += [
            (f"box {i}: x0 = {x0:g}", np.array([x0, y0]), np.array([x0, y1])),
            (f"box {i}: x1 = {x1:g}", np.array([x1, y0]), np.array([x1, y1])),
            (f"box {i}: y0 = {y0:g}", np.array([x0, y0]), np.array([x1, y0])),
            (f"box {i}: y1 = {y1:g}", np.array([x0, y1]), np.array([x1, y1])),
        ]
    return out


def polygon_problem(polygon: np.ndarray) -> str | None:
    """Why the polygon (k >= 3, 2) is not simple, or None: zero area, or two
    edges that meet other than at their shared vertex."""
    P = np.asarray(polygon, float)
    k = len(P)
    area = 0.5 * np.sum(P[:, 0] * np.roll(P[:, 1], -1) - np.roll(P[:, 0], -1) * P[:, 1])
    repeated = np.flatnonzero(np.all(P == np.roll(P, -1, axis=0), axis=1))
    if repeated.size:
        i = int(repeated[0])
        return f"repeats vertex {i} (vertices {i} and {(i + 1) % k} coincide)"
    pair = first_meeting(P, closed=True)
    if pair is not None:
        return f"is not simple: edges {pair[0]} and {pair[1]} cross or touch"
    if area == 0.0:
        return "has zero area"
    return None


def _horizon_edges(region, box: Box) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """The horizons of a layer across the domain ``box``; those of a
    displaced layer end at its fault, one piece per side."""
    x0, x1 = float(box[0]), float(box[1])
    if region.kind == "layer":
        return [
            (f"{name} = {y:g}", np.array([x0, y]), np.array([x1, y]))
            for name, y in (("top", region.top), ("base", region.base))
        ]
    out = []
    for side, right in (("left", False), ("right", True)):
        base, top = offset_span(region, np.array([right]))
        for name, y in (("top", float(top[0])), ("base", float(base[0]))):
            xf = float(fault_x(np.array([y]), region.fault)[0])
            a, b = (x0, min(xf, x1)) if not right else (max(xf, x0), x1)
            if a < b:
                out.append(
                    (
                        f"{name} on the {side} = {y:g}",
                        np.array([a, y]),
                        np.array([b, y]),
                    )
                )
    return out
