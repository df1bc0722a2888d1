"""Quadrature: sub-cell rules of enriched cells and interface points on fractures.

Enriched cells are cut into convex sub-polygons along every line across which
an enrichment function is not smooth (the fracture segments, the two kink
lines of each tip ramp and the junction lines, see ``Fracture.kink_lines``
and ``enrichment._cell_lines_table``; the kernel kernels.cell_subtriangles
cuts every cell at once), each sub-polygon is
fan-triangulated and integrated with the 7-point degree-5 Dunavant rule, which
is exact for the degree-4 integrand of B^T D B inside a sub-cell (bilinear N
times linear F).  The side of the fracture (H in eq. 12) is taken at each
sub-cell's centroid, never at a point on the fracture.

split_polygon, polygon_area and fan_triangles are the kernels' NumPy
functions (xfemslip.kernels.vectorized), named here for their callers.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from xfemslip.geometry.fracture import GEOMETRY_TOL
from xfemslip.kernels import vectorized
from xfemslip.kernels.vectorized import fan_triangles, polygon_area, split_polygon

__all__ = [
    "InterfacePoints",
    "cell_subtriangles",
    "duffy_rule",
    "fan_triangles",
    "interface_points",
    "polygon_area",
    "split_polygon",
    "triangle_rule",
]

# Dunavant (1985) degree-5 rule on the reference triangle: barycentric points and
# weights (summing to 1).
_A1, _B1 = 0.059715871789770, 0.470142064105115
_A2, _B2 = 0.797426985353087, 0.101286507323456
TRI_BARY = np.array(
    [
        [1 / 3, 1 / 3, 1 / 3],
        [_A1, _B1, _B1],
        [_B1, _A1, _B1],
        [_B1, _B1, _A1],
        [_A2, _B2, _B2],
        [_B2, _A2, _B2],
        [_B2, _B2, _A2],
    ]
)
TRI_W = np.array([0.225] + [0.132394152788506] * 3 + [0.125939180544827] * 3)

# Gauss-Legendre points per fracture piece: exact for the degree-6 penalty
# integrand (jump = 2 R N a is at most cubic along a piece).
LINE_POINTS, LINE_WEIGHTS = np.polynomial.legendre.leggauss(4)


def cell_subtriangles(bounds: np.ndarray, lines, tol: float, apexes=()) -> np.ndarray:
    """Sub-triangles (t, 3, 2) of a rectangle cut along the given lines
    ((point, normal) pairs, applied in order).

    A sub-polygon with a vertex at one of the ``apexes`` (crack tips) is fanned
    from that vertex, so the tip is vertex 0 of its triangles (Duffy rule).
    The rule is the kernel's (xfemslip.kernels.subcells, its NumPy twin
    here for one cell).
    """
    pts = np.array([p for p, _ in lines], float).reshape(-1, 2)
    nrm = np.array([n for _, n in lines], float).reshape(-1, 2)
    apx = np.array(list(apexes), float).reshape(-1, 2)
    return vectorized.cell_subtriangles(
        np.asarray(bounds, float)[None, :],
        np.array([0, len(pts)], np.int64),
        pts,
        nrm,
        np.array([0, len(apx)], np.int64),
        apx,
        tol,
    )[1]


# Collapsed (Duffy) product rule for triangles with a 1/sqrt(r) gradient
# singularity at vertex 0: x = v0 + u (v1 - v0 + v (v2 - v1)), dA = 2 A u du dv,
# with u = s^2 so that both the 1/r of |grad B|^2 and the 1/sqrt(r) of
# grad N . grad B become polynomials in (s, v): dA = 4 A s^3 ds dv.
DUFFY_POINTS = 8
_g, _gw = np.polynomial.legendre.leggauss(DUFFY_POINTS)
_DS, _DV = np.meshgrid(0.5 * (_g + 1.0), 0.5 * (_g + 1.0), indexing="ij")
_DW = np.outer(0.5 * _gw, 0.5 * _gw)


def duffy_rule(tris: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Collapsed Gauss points (t*P, 2) and weights (t*P,) on triangles (t, 3, 2)."""
    v0, v1, v2 = tris[:, 0], tris[:, 1], tris[:, 2]
    e1 = v1 - v0
    e2 = v2 - v0
    area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    sq = _DS.ravel()
    u = sq * sq
    v = _DV.ravel()
    xy = v0[:, None, :] + u[None, :, None] * (
        (v1 - v0)[:, None, :] + v[None, :, None] * (v2 - v1)[:, None, :]
    )
    w = 4.0 * area[:, None] * (sq**3 * _DW.ravel())[None, :]
    return xy.reshape(-1, 2), w.reshape(-1)


def triangle_rule(tris: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Quadrature points (t*7, 2) and weights (t*7,) on triangles (t, 3, 2)."""
    e1 = tris[:, 1] - tris[:, 0]
    e2 = tris[:, 2] - tris[:, 0]
    area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    xy = np.einsum("qk,tkd->tqd", TRI_BARY, tris).reshape(-1, 2)
    w = (area[:, None] * TRI_W[None, :]).reshape(-1)
    return xy, w


@dataclass(frozen=True)
class InterfacePoints:
    """Contact integration points of all fractures (flat arrays, n points)."""

    fracture: np.ndarray  # (n,) int64, position in the fracture list
    cell: np.ndarray  # (n,) int64
    xy: np.ndarray  # (n, 2) [m]
    s: np.ndarray  # (n,) arc length from the fracture's first point [m]
    weight: np.ndarray  # (n,) [m]
    normal: np.ndarray  # (n, 2)
    tangent: np.ndarray  # (n, 2)
    ramp: np.ndarray  # (n,) tip ramp R [-]

    @property
    def n(self) -> int:
        return self.fracture.size


def interface_points(
    fractures, min_cell: float | None = None, breaks=None
) -> InterfacePoints:
    """Gauss points on every piece of every fracture, split at the ramp kinks
    and at the arc lengths ``breaks[f]`` (n_f,) [m] of each fracture f (where
    its loading jumps: :func:`xfemslip.fem.zones.loading_breaks`), so that
    no quadrature segment straddles a jump.

    min_cell : smallest element size [m]; sub-pieces shorter than
    GEOMETRY_TOL * min_cell (a kink falling on a piece's end) are skipped
    (default: 1e-12 of the segment length).
    """
    cols: dict[str, list[np.ndarray]] = {
        k: [] for k in ("fracture", "cell", "xy", "s", "weight", "normal", "tangent")
    }
    for fi, fr in enumerate(fractures):
        lo, hi, sub_cell, sub_seg = [], [], [], []  # sub-pieces [lo, hi] of t
        for cell, seg, (ta, tb) in zip(
            fr.piece_cell, fr.piece_seg, fr.piece_t, strict=True
        ):
            p0 = fr.points[seg]
            d = fr.points[seg + 1] - p0
            found = [ta, tb]
            if breaks is not None and len(breaks[fi]):
                t = (np.asarray(breaks[fi]) - fr.s_start[seg]) / fr.length[seg]
                found.extend(t[(t > ta) & (t < tb)])
            for tip in fr.tips:
                dd = d @ tip.direction
                if abs(dd) > 0.0:
                    t = (-tip.ramp_length - (p0 - tip.point) @ tip.direction) / dd
                    if ta < t < tb:
                        found.append(t)
            cuts = np.sort(found)
            tol = GEOMETRY_TOL * min_cell if min_cell else 1e-12 * fr.length[seg]
            keep = np.diff(cuts) * fr.length[seg] > tol
            lo.append(cuts[:-1][keep])
            hi.append(cuts[1:][keep])
            sub_cell.append(np.full(lo[-1].size, cell))
            sub_seg.append(np.full(lo[-1].size, seg))
        # the fracture's sub-pieces at once (per sub-piece, these small arrays
        # took half of the function's 0.2 s on a 100-fracture network)
        if not lo:
            continue
        a, b = np.concatenate(lo), np.concatenate(hi)
        seg_of, k = np.concatenate(sub_seg), LINE_POINTS.size
        t = 0.5 * (a + b)[:, None] + (0.5 * (b - a))[:, None] * LINE_POINTS
        p0 = fr.points[seg_of]
        d = fr.points[seg_of + 1] - p0
        seg_q = np.repeat(seg_of, k)
        cols["fracture"].append(np.full(t.size, fi))
        cols["cell"].append(np.repeat(np.concatenate(sub_cell), k))
        cols["xy"].append(
            (p0[:, None, :] + t[:, :, None] * d[:, None, :]).reshape(-1, 2)
        )
        cols["s"].append(fr.arc_length(seg_q, t.ravel()))
        cols["weight"].append(
            ((0.5 * (b - a) * fr.length[seg_of])[:, None] * LINE_WEIGHTS).ravel()
        )
        cols["normal"].append(fr.normal[seg_q])
        cols["tangent"].append(fr.tangent[seg_q])
    if not cols["fracture"]:
        empty2 = np.zeros((0, 2))
        return InterfacePoints(
            np.zeros(0, np.int64),
            np.zeros(0, np.int64),
            empty2,
            np.zeros(0),
            np.zeros(0),
            empty2,
            empty2,
            np.zeros(0),
        )
    arr = {k: np.concatenate(v) for k, v in cols.items()}
    ramp = np.empty(arr["s"].size)
    for fi, fr in enumerate(fractures):
        m = arr["fracture"] == fi
        ramp[m] = fr.ramp(arr["xy"][m])[0]
    return InterfacePoints(
        fracture=arr["fracture"].astype(np.int64),
        cell=arr["cell"].astype(np.int64),
        xy=arr["xy"],
        s=arr["s"],
        weight=arr["weight"],
        normal=arr["normal"],
        tangent=arr["tangent"],
        ramp=ramp,
    )
