"""``[mesh] size`` (with growth, max_size, refine): the graded mesh, built
around its refinement features once the case's fractures and regions are
read (xfemslip.geometry.grading places the nodes).

Refinement features, per axis (a tensor mesh refines whole rows and
columns):

- a fracture (``[[fractures]]``, ``[network]``): the x- and y-extent of its
  part inside the domain are fine intervals (cells at most ``size`` over
  them and one size beyond);
- a region edge (``[reservoir]`` boxes and polygon): an edge along y = c is
  the line c (a node row exactly) and the fine interval [c, c] of y; an edge
  along x = c likewise in x; an inclined edge has the fine intervals of its
  x- and y-extent (a line cannot follow it);
- a ``mesh.refine`` box: the fine intervals of its x- and y-extent.

``Refinement`` holds such features; ``combine`` adds more (unit horizons:
``horizon_refinement``) before ``graded_grid`` builds the mesh.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from xfemslip.case.grid import Grid, axis_resolves, check_element_count
from xfemslip.case.specs import MeshSpec
from xfemslip.case.tables import frozen
from xfemslip.geometry.box import Box
from xfemslip.geometry.grading import graded_axes

__all__ = [
    "Refinement",
    "box_refinement",
    "case_refinement",
    "combine",
    "fracture_refinement",
    "graded_grid",
    "horizon_refinement",
    "region_refinement",
]


class Refinement(NamedTuple):
    """Refinement features of a graded mesh, per axis.

    fine_x, fine_y : (k, 2) float64 intervals [a, b] [m] over which (and one
        size beyond) the cells are at most ``mesh.size``
    lines_x, lines_y : (l,) float64 coordinates [m] that are node lines
        exactly (inside the domain; the domain's edges are nodes anyway)
    """

    fine_x: np.ndarray
    fine_y: np.ndarray
    lines_x: np.ndarray
    lines_y: np.ndarray

    @property
    def empty(self) -> bool:
        return not (self.fine_x.size or self.fine_y.size)


def _refinement(fine_x=(), fine_y=(), lines_x=(), lines_y=()) -> Refinement:
    return Refinement(
        np.asarray(fine_x, dtype=np.float64).reshape(-1, 2),
        np.asarray(fine_y, dtype=np.float64).reshape(-1, 2),
        np.asarray(lines_x, dtype=np.float64).reshape(-1),
        np.asarray(lines_y, dtype=np.float64).reshape(-1),
    )


def combine(*parts: Refinement) -> Refinement:
    """All the features of ``parts`` together."""
    if not parts:
        return _refinement()
    return Refinement(*(np.concatenate([p[i] for p in parts]) for i in range(4)))


def _clip(a, b, lo, hi):
    """The part of segment a-b inside the closed box [lo, hi] (Liang-Barsky),
    as two points, or None."""
    t0, t1 = 0.0, 1.0
    for k in (0, 1):
        d = float(b[k]) - float(a[k])
        if d == 0.0:
            if not lo[k] <= a[k] <= hi[k]:
                return None
            continue
        ta, tb = sorted(((lo[k] - a[k]) / d, (hi[k] - a[k]) / d))
        t0, t1 = max(t0, ta), min(t1, tb)
    if t0 > t1:
        return None
    a, b = np.asarray(a, float), np.asarray(b, float)
    return a + t0 * (b - a), a + t1 * (b - a)


def fracture_refinement(polylines, origin, extent) -> Refinement:
    """The x- and y-extents of the parts of polylines ((k_i, 2) vertices
    [m]) inside the domain (origin, extent) as fine intervals."""
    box = Box.from_origin_size(origin, extent)
    lo, hi = box.lo, box.hi
    fx, fy = [], []
    for points in polylines:
        parts = [
            _clip(a, b, lo, hi) for a, b in zip(points[:-1], points[1:], strict=True)
        ]
        pts = np.array([p for part in parts if part is not None for p in part])
        if pts.size:
            fx.append([pts[:, 0].min(), pts[:, 0].max()])
            fy.append([pts[:, 1].min(), pts[:, 1].max()])
    return _refinement(fx, fy)


def region_refinement(boxes, polygon, origin, extent) -> Refinement:
    """The edges of a region (boxes (k, 4) [x0, y0, x1, y1] and/or a polygon
    (m, 2) [m]) inside the domain: an axis-parallel edge as a line and the
    point interval across it, an inclined one as the fine intervals of its
    extents."""
    box = Box.from_origin_size(origin, extent)
    lo, hi = box.lo, box.hi
    edges = []
    for x0, y0, x1, y1 in np.asarray(boxes, dtype=np.float64).reshape(-1, 4):
        corners = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]
        edges += list(zip(corners, corners[1:] + corners[:1], strict=True))
    if polygon is not None:
        P = [tuple(v) for v in np.asarray(polygon, dtype=np.float64)]
        edges += list(zip(P, P[1:] + P[:1], strict=True))
    fx, fy, lx, ly = [], [], [], []
    for a, b in edges:
        part = _clip(a, b, lo, hi)
        if part is None:
            continue
        (ax, ay), (bx, by) = part
        if a[1] == b[1]:  # along x: the row y = c
            if lo[1] < ay < hi[1] and ax != bx:
                ly.append(ay)
                fy.append([ay, ay])
        elif a[0] == b[0]:  # along y: the column x = c
            if lo[0] < ax < hi[0] and ay != by:
                lx.append(ax)
                fx.append([ax, ax])
        else:
            fx.append(sorted([ax, bx]))
            fy.append(sorted([ay, by]))
    return _refinement(fx, fy, lx, ly)


def horizon_refinement(elevations, origin, extent) -> Refinement:
    """Horizons y = c [m] (layer boundaries spanning the domain): each
    inside the domain is a node row and refined across."""
    box = Box.from_origin_size(origin, extent)
    lo, hi = box.lo, box.hi
    ys = [float(c) for c in elevations if lo[1] < c < hi[1]]
    return _refinement(fine_y=[[c, c] for c in ys], lines_y=ys)


def box_refinement(boxes) -> Refinement:
    """Boxes (k, 4) [x0, y0, x1, y1] [m] refined over their extents."""
    b = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    return _refinement(b[:, [0, 2]], b[:, [1, 3]])


def case_refinement(grid: Grid, fractures, reservoir) -> Refinement:
    """The features of a case: its fractures (FractureSpec), its
    ``[reservoir]`` (ReservoirSpec or None) and the ``mesh.refine`` boxes."""
    assert grid.grading is not None  # a graded mesh waiting for its features
    parts = [
        fracture_refinement([f.points for f in fractures], grid.origin, grid.size),
        box_refinement(grid.grading.refine),
    ]
    if reservoir is not None:
        parts.append(
            region_refinement(
                reservoir.boxes, reservoir.polygon, grid.origin, grid.size
            )
        )
    return combine(*parts)


def graded_grid(
    grid: Grid, refinement: Refinement, problems: list, key: str = "mesh.size"
) -> Grid | None:
    """The graded mesh of ``grid.grading`` around ``refinement``; None after
    recording a problem at ``key`` (nothing to refine, too many elements,
    coordinates that do not resolve).  The element count is checked before
    a node is placed."""
    g = grid.grading
    assert g is not None  # a graded mesh waiting for its features
    if refinement.empty:
        problems.append(
            (
                key,
                "a graded mesh needs something to refine: a fracture, a "
                "[reservoir] or mesh.refine = [[x0, y0, x1, y1]]",
            )
        )
        return None
    px, py = graded_axes(
        grid.origin,
        grid.size,
        g.size,
        g.growth,
        g.max_size,
        refinement.fine_x,
        refinement.fine_y,
        refinement.lines_x,
        refinement.lines_y,
    )
    if not check_element_count(px.n_cells, py.n_cells, key, problems):
        return None
    x, y = px.nodes(), py.nodes()
    if not (axis_resolves(x, key, problems) and axis_resolves(y, key, problems)):
        return None
    mesh = MeshSpec(x=frozen(x), y=frozen(y), grading=g)
    return Grid(grid.origin, grid.size, mesh, g)


def unit_refinement(units, origin, extent) -> Refinement:
    """The rock units' boundaries (UnitSpec): a layer's horizons as rows
    (those of a displaced layer on both sides of its fault), the edges of
    boxes and polygons as :func:`region_refinement` has them."""
    parts = []
    for unit in units:
        r = unit.region
        if r.kind == "layer":
            parts.append(horizon_refinement([r.top, r.base], origin, extent))
        elif r.kind == "offset":
            heights = [r.top, r.base, r.top - r.throw, r.base - r.throw]
            parts.append(horizon_refinement(heights, origin, extent))
        else:
            boxes = r.boxes if r.boxes is not None else np.zeros((0, 4))
            parts.append(region_refinement(boxes, r.polygon, origin, extent))
    return combine(*parts)
