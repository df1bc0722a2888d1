"""Fields sampled on data points, evaluated anywhere: one or several scalar
fields (a pressure change at several times, say) given on a regular grid, on
scattered points or on the cells of a mesh, and the rule for a point outside
the data.

Interpolation rules (one per kind of data):

- ``GridField``, a full tensor grid of nodes: bilinear in each grid cell
  (exact for a + b x + c y + d x y);
- ``TriangleField`` with point values: linear in each triangle (barycentric)
  of a triangulation -- the Delaunay triangulation of scattered points, or a
  mesh's cells split into triangles (a quad along its diagonal from its first
  node, a polygon as a fan from its first node); exact for a + b x + c y;
- ``TriangleField`` with cell values: constant in each cell, the cell that
  contains the point (a point on an edge between two cells takes one of
  them).

Coverage: a point belongs to the data within COVER_TOL (of the grid's
extent, or barycentric in a triangle); elsewhere the outside rule applies:
``"error"`` (CaseError naming the file and the first such point),
``"nearest"`` (the value of the nearest data point: grid node, scattered
point, mesh node for point values, cell centroid for cell values) or a
number (that value [Pa], for every field).

The readers of the files are in ``xfemslip.case.pressure_field``.
"""

from __future__ import annotations

import numpy as np

from xfemslip.errors import CaseError

__all__ = ["COVER_TOL", "GridField", "TriangleField", "locate_triangles"]

# A point within this of the data (relative to the grid's extent, or as a
# barycentric coordinate, i.e. relative to the triangle's size) is covered:
# quadrature and contact points on the edge of the data lie on it up to the
# rounding of their coordinates.
COVER_TOL = 1.0e-9
# Points located at once (bounds the memory of the candidate pairs).
CHUNK = 65_536


def _point_text(p) -> str:
    return f"({float(p[0])!r}, {float(p[1])!r})"


class _Field:
    """The outside rule and ``values`` shared by the field kinds."""

    source: str
    outside: str | float
    description: str

    def _inside(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(values (n_fields, n), covered (n,) bool) at points xy (n, 2)."""
        raise NotImplementedError

    def _tree(self):
        """A KD-tree of the data's locations (the "nearest" rule)."""
        raise NotImplementedError

    def _nearest_values(self) -> np.ndarray:
        """(n_fields, m) values at the locations of ``_tree``."""
        raise NotImplementedError

    def _outside_values(self, xy: np.ndarray, missing: np.ndarray, out: np.ndarray):
        """Fill out[:, missing] by the outside rule (or raise CaseError)."""
        if not missing.any():
            return out
        if self.outside == "error":
            first = xy[np.flatnonzero(missing)[0]]
            raise CaseError(
                self.source,
                [
                    (
                        "",
                        f"point {_point_text(first)} lies outside the data "
                        f"({self.description}); give pore_pressure.field.outside "
                        '= "nearest" or a value in Pa to fill such points',
                    )
                ],
            )
        if self.outside == "nearest":
            if getattr(self, "_nearest", None) is None:
                self._nearest = self._tree()
            _, k = self._nearest.query(xy[missing])
            out[:, missing] = self._nearest_values()[:, k]
        else:
            out[:, missing] = float(self.outside)
        return out

    def values(self, xy) -> np.ndarray:
        """(n_fields, n) float64 field values [Pa] at points ``xy`` (n, 2) [m]."""
        xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
        out, covered = self._inside(xy)
        return self._outside_values(xy, ~covered, out)

    def covers(self, xy) -> np.ndarray:
        """(n,) bool: whether the data covers each point (before any outside
        rule) [points (n, 2), m]."""
        xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
        return self._inside(xy)[1]


class GridField(_Field):
    """Fields on a full tensor grid of nodes, bilinear in each grid cell.

    x : (nx,) float64 strictly increasing [m], nx >= 2
    y : (ny,) float64 strictly increasing [m], ny >= 2
    grid_values : (n_fields, ny, nx) float64 [Pa], finite
    outside : "error" | "nearest" | a value [Pa]
    source : the file, for messages
    """

    def __init__(self, x, y, grid_values, outside="error", source=""):
        self.x = np.ascontiguousarray(x, dtype=np.float64)
        self.y = np.ascontiguousarray(y, dtype=np.float64)
        self.grid_values = np.ascontiguousarray(grid_values, dtype=np.float64)
        assert self.grid_values.shape[1:] == (self.y.size, self.x.size)
        assert self.x.size >= 2 and self.y.size >= 2
        self.outside, self.source = outside, source
        self.description = (
            f"a regular grid of {self.x.size} x {self.y.size} nodes over "
            f"[{self.x[0]:g}, {self.x[-1]:g}] x [{self.y[0]:g}, {self.y[-1]:g}] m"
        )

    @property
    def n_fields(self) -> int:
        return self.grid_values.shape[0]

    def _axis(self, nodes, v):
        """(cell index, local coordinate in [0, 1], covered) along one axis."""
        tol = COVER_TOL * (nodes[-1] - nodes[0])
        covered = (v >= nodes[0] - tol) & (v <= nodes[-1] + tol)
        v = np.clip(v, nodes[0], nodes[-1])
        i = np.clip(np.searchsorted(nodes, v, side="right") - 1, 0, nodes.size - 2)
        t = (v - nodes[i]) / (nodes[i + 1] - nodes[i])
        return i, t, covered

    def _inside(self, xy):
        i, t, cx = self._axis(self.x, xy[:, 0])
        j, u, cy = self._axis(self.y, xy[:, 1])
        V = self.grid_values
        out = (
            (1 - t) * (1 - u) * V[:, j, i]
            + t * (1 - u) * V[:, j, i + 1]
            + (1 - t) * u * V[:, j + 1, i]
            + t * u * V[:, j + 1, i + 1]
        )
        return out, cx & cy

    def _tree(self):
        from scipy.spatial import cKDTree  # lazily, as below

        X, Y = np.meshgrid(self.x, self.y)
        return cKDTree(np.column_stack([X.ravel(), Y.ravel()]))

    def _nearest_values(self):
        return self.grid_values.reshape(self.n_fields, -1)


class TriangleField(_Field):
    """Fields on triangles: linear from point values, or constant per cell.

    points : (m, 2) float64 [m]
    triangles : (t, 3) int64 point indices
    point_values : (n_fields, m) float64 [Pa], or None with cell values
    cell_values : (n_fields, c) float64 [Pa], with ``cell_of`` (t,) int64 the
        cell each triangle belongs to, or None with point values
    outside, source : as ``GridField``; description : what the data is, for
        messages
    """

    def __init__(
        self,
        points,
        triangles,
        point_values=None,
        cell_values=None,
        cell_of=None,
        outside="error",
        source="",
        description="triangles",
    ):
        self.points = np.ascontiguousarray(points, dtype=np.float64)
        self.triangles = np.ascontiguousarray(triangles, dtype=np.int64)
        assert (point_values is None) != (cell_values is None)
        self.point_values = (
            None if point_values is None else np.asarray(point_values, np.float64)
        )
        self.cell_values = (
            None if cell_values is None else np.asarray(cell_values, np.float64)
        )
        self.cell_of = None if cell_of is None else np.asarray(cell_of, np.int64)
        self.outside, self.source, self.description = outside, source, description
        self._locator = _Buckets(self.points, self.triangles)

    @property
    def n_fields(self) -> int:
        v = self.point_values if self.point_values is not None else self.cell_values
        return v.shape[0]

    def _inside(self, xy):
        tri, bary = self._locator.locate(xy)
        covered = tri >= 0
        out = np.zeros((self.n_fields, xy.shape[0]))
        t = tri[covered]
        if self.point_values is not None:
            corners = self.triangles[t]  # (n_in, 3)
            out[:, covered] = np.einsum(
                "fnk,nk->fn", self.point_values[:, corners], bary[covered]
            )
        else:
            out[:, covered] = self.cell_values[:, self.cell_of[t]]
        return out, covered

    def _tree(self):
        # scipy.spatial costs about 0.2 s to import; only a case with a
        # pressure field from a file (and a point outside its data) builds
        # a tree
        from scipy.spatial import cKDTree

        if self.point_values is not None:
            return cKDTree(self.points)
        return cKDTree(self._centroids())

    def _centroids(self):
        """(c,) centroid of each cell: the area-weighted mean of its triangles'."""
        P = self.points[self.triangles]
        area = 0.5 * np.abs(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]))
        c = self.cell_values.shape[1]
        w = np.bincount(self.cell_of, weights=area, minlength=c)
        cx = np.bincount(self.cell_of, weights=area * P[:, :, 0].mean(1), minlength=c)
        cy = np.bincount(self.cell_of, weights=area * P[:, :, 1].mean(1), minlength=c)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.column_stack([cx / w, cy / w])

    def _nearest_values(self):
        if self.point_values is not None:
            return self.point_values
        return self.cell_values


def locate_triangles(points, triangles, xy) -> tuple[np.ndarray, np.ndarray]:
    """The triangle containing each point (within COVER_TOL) and the point's
    barycentric coordinates in it.

    points : (m, 2) [m]; triangles : (t, 3) int64; xy : (n, 2) [m].
    Returns (n,) int64 triangle index (-1: none) and (n, 3) float64.
    """
    return _Buckets(
        np.asarray(points, np.float64), np.asarray(triangles, np.int64)
    ).locate(np.asarray(xy, np.float64).reshape(-1, 2))


class _Buckets:
    """Point location in a set of triangles through a uniform grid of buckets
    (each bucket lists the triangles whose bounding box meets it)."""

    def __init__(self, points: np.ndarray, triangles: np.ndarray):
        self.P = points[triangles]  # (t, 3, 2)
        lo, hi = self.P.min(axis=1), self.P.max(axis=1)
        self.lo, span = points.min(axis=0), np.ptp(points, axis=0)
        span = np.where(span > 0, span, 1.0)
        # buckets the size of the median triangle's box, at most ~4 per triangle
        typical = np.maximum(np.median(hi - lo, axis=0), span / 4096)
        n = np.clip(np.ceil(span / typical), 1, None).astype(np.int64)
        while n[0] * n[1] > 4 * max(len(triangles), 1) and n.max() > 1:
            n = np.maximum(n // 2, 1)
        self.n, self.step = n, span / n
        i0, j0 = self._cell(lo)
        i1, j1 = self._cell(hi)
        wi, wj = i1 - i0 + 1, j1 - j0 + 1
        counts = wi * wj
        tri = np.repeat(np.arange(len(triangles)), counts)
        k = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
        rep_wj = np.repeat(wj, counts)
        bucket = (np.repeat(i0, counts) + k // rep_wj) * n[1] + (
            np.repeat(j0, counts) + k % rep_wj
        )
        order = np.argsort(bucket, kind="stable")
        self.tri = tri[order]
        self.offsets = np.searchsorted(bucket[order], np.arange(n[0] * n[1] + 1))

    def _cell(self, xy):
        ij = np.floor((xy - self.lo) / self.step).astype(np.int64)
        return (
            np.clip(ij[:, 0], 0, self.n[0] - 1),
            np.clip(ij[:, 1], 0, self.n[1] - 1),
        )

    def locate(self, xy: np.ndarray):
        tri = np.full(xy.shape[0], -1, dtype=np.int64)
        bary = np.zeros((xy.shape[0], 3))
        for start in range(0, xy.shape[0], CHUNK):
            part = slice(start, start + CHUNK)
            tri[part], bary[part] = self._locate(xy[part])
        return tri, bary

    def _locate(self, xy):
        i, j = self._cell(xy)
        b = i * self.n[1] + j
        first, last = self.offsets[b], self.offsets[b + 1]
        counts = last - first
        point = np.repeat(np.arange(xy.shape[0]), counts)
        k = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
        cand = self.tri[np.repeat(first, counts) + k]
        lam = _barycentric(self.P[cand], xy[point])
        ok = lam.min(axis=1) >= -COVER_TOL
        tri = np.full(xy.shape[0], -1, dtype=np.int64)
        bary = np.zeros((xy.shape[0], 3))
        hit_points, first_hit = np.unique(point[ok], return_index=True)
        rows = np.flatnonzero(ok)[first_hit]
        tri[hit_points] = cand[rows]
        bary[hit_points] = lam[rows]
        return tri, bary


def _barycentric(T: np.ndarray, p: np.ndarray) -> np.ndarray:
    """(k, 3) barycentric coordinates of points p (k, 2) in triangles T
    (k, 3, 2); a degenerate triangle gives NaN (never contains a point)."""
    a, b, c = T[:, 0], T[:, 1], T[:, 2]
    v0, v1, v2 = b - a, c - a, p - a
    det = v0[:, 0] * v1[:, 1] - v0[:, 1] * v1[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        l1 = (v2[:, 0] * v1[:, 1] - v2[:, 1] * v1[:, 0]) / det
        l2 = (v0[:, 0] * v2[:, 1] - v0[:, 1] * v2[:, 0]) / det
    lam = np.column_stack([1.0 - l1 - l2, l1, l2])
    return np.where(np.isfinite(lam), lam, -np.inf)
