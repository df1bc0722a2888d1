"""Structured rectilinear Q4 meshes (uniform or graded).

Node (i, j) has id ``j * (nx + 1) + i``; cell (i, j) has id ``j * nx + i`` and
nodes counter-clockwise from its lower-left corner.  Every cell is an
axis-aligned rectangle, which the kernels exploit (affine map).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from xfemslip.geometry.box import Box

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class Mesh:
    x: np.ndarray  # (nx+1,) node x coordinates [m]
    y: np.ndarray  # (ny+1,) node y coordinates [m]
    nodes: np.ndarray  # (n_nodes, 2) float64 [m]
    cells: np.ndarray  # (n_cells, 4) int64, counter-clockwise
    bounds: np.ndarray  # (n_cells, 4) float64 [x0, x1, y0, y1] [m]

    @property
    def nx(self) -> int:
        return self.x.size - 1

    @property
    def ny(self) -> int:
        return self.y.size - 1

    @property
    def n_nodes(self) -> int:
        return self.nodes.shape[0]

    @property
    def n_cells(self) -> int:
        return self.cells.shape[0]

    @property
    def box(self) -> Box:
        """The domain the mesh covers [m]."""
        return Box.from_lines(self.x, self.y)

    @property
    def h_min(self) -> float:
        """Smallest element edge length [m]."""
        return float(min(np.diff(self.x).min(), np.diff(self.y).min()))

    def nodes_within(self, point, radius: float) -> np.ndarray:
        """Ids (increasing) of the nodes at most ``radius`` from ``point``
        [m]: the distance is tested on the grid lines' box around the point
        only (a test of every node per fracture tip took 0.17 s of the build
        of 100 branch-tipped fractures on 200 x 200 cells)."""
        px, py = float(point[0]), float(point[1])
        reach = radius * (1.0 + 1.0e-9)  # the box holds every node that passes
        i = np.arange(
            np.searchsorted(self.x, px - reach, "left"),
            np.searchsorted(self.x, px + reach, "right"),
        )
        j = np.arange(
            np.searchsorted(self.y, py - reach, "left"),
            np.searchsorted(self.y, py + reach, "right"),
        )
        ids = (j[:, None] * (self.nx + 1) + i[None, :]).ravel()
        dist = np.linalg.norm(self.nodes[ids] - np.array([px, py]), axis=1)
        return ids[dist <= radius]

    def edge_nodes(self, edge: str) -> np.ndarray:
        """Node ids on an edge, ordered by increasing coordinate along it."""
        nx, ny = self.nx, self.ny
        ids = np.arange(self.n_nodes).reshape(ny + 1, nx + 1)
        return {
            "bottom": ids[0, :],
            "top": ids[-1, :],
            "left": ids[:, 0],
            "right": ids[:, -1],
        }[edge].copy()

    def cell_of(self, i: np.ndarray, j: np.ndarray) -> np.ndarray:
        return j * self.nx + i

    def shape_at(self, cells: np.ndarray, xy: np.ndarray) -> np.ndarray:
        """Q4 shape functions N (n, 4) at points xy (n, 2) of the given cells (n,)."""
        b = self.bounds[cells]
        xi = (2.0 * xy[:, 0] - b[:, 0] - b[:, 1]) / (b[:, 1] - b[:, 0])
        eta = (2.0 * xy[:, 1] - b[:, 2] - b[:, 3]) / (b[:, 3] - b[:, 2])
        xa = np.array([-1.0, 1.0, 1.0, -1.0])
        ya = np.array([-1.0, -1.0, 1.0, 1.0])
        return 0.25 * (1.0 + xi[:, None] * xa) * (1.0 + eta[:, None] * ya)


def build_mesh(x: np.ndarray, y: np.ndarray) -> Mesh:
    """Mesh from strictly increasing node coordinates along x and y [m]."""
    x = np.ascontiguousarray(x, dtype=np.float64)
    y = np.ascontiguousarray(y, dtype=np.float64)
    nx, ny = x.size - 1, y.size - 1
    X, Y = np.meshgrid(x, y)
    nodes = np.column_stack([X.ravel(), Y.ravel()])
    gi, gj = np.meshgrid(np.arange(nx), np.arange(ny))
    i, j = gi.ravel(), gj.ravel()
    n0 = j * (nx + 1) + i
    cells = np.column_stack([n0, n0 + 1, n0 + nx + 2, n0 + nx + 1]).astype(np.int64)
    bounds = np.column_stack([x[i], x[i + 1], y[j], y[j + 1]])
    return Mesh(x=x, y=y, nodes=nodes, cells=cells, bounds=bounds)
