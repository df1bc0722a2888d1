"""Sub-triangles of enriched cells: each rectangle cut along its lines.

The rule (xfemslip.fem.quadrature, the NumPy twin in vectorized.py): the cell
is split, line after line, into convex pieces (a vertex within ``tol`` of a
line counts as on it, so a line through a vertex or along an edge makes no
sliver; a piece with fewer than 3 vertices or of area at most tol^2 is
dropped, and a line that leaves nothing is ignored); a piece with a vertex
within ``tol`` of one of the cell's apexes (crack tips) is rotated so that the
apex comes first (the Duffy rule's singular vertex); every piece is then
fanned from its first vertex, triangles of area at most 1e-3 tol^2 dropped.
"""

import numpy as np
from numba import njit

from xfemslip.kernels._config import NUMBA_CACHE


@njit(cache=NUMBA_CACHE)
def _polygon_area(poly, k):
    """Signed area of the polygon poly[:k] (counter-clockwise positive)."""
    s1 = 0.0
    s2 = 0.0
    for i in range(k):
        j = (i + 1) % k
        s1 += poly[i, 0] * poly[j, 1]
        s2 += poly[i, 1] * poly[j, 0]
    return 0.5 * (s1 - s2)


@njit(cache=NUMBA_CACHE)
def _split(poly, k, px, py, nx, ny, tol, d, out_a, out_b):
    """Split poly[:k] by the line through (px, py) with normal (nx, ny).

    Returns (ka, kb): the vertex counts of the pieces written to out_a (side
    d >= 0) and out_b (side d <= 0), 0 for a piece dropped; (-1, -1) when the
    polygon stays whole."""
    pos_any = False
    neg_any = False
    for i in range(k):
        v = (poly[i, 0] - px) * nx + (poly[i, 1] - py) * ny
        if abs(v) <= tol:
            v = 0.0
        d[i] = v
        if v > 0.0:
            pos_any = True
        elif v < 0.0:
            neg_any = True
    if not (pos_any and neg_any):
        return -1, -1
    ka = 0
    kb = 0
    for i in range(k):
        j = (i + 1) % k
        dp = d[i]
        dq = d[j]
        if dp >= 0.0:
            out_a[ka, 0] = poly[i, 0]
            out_a[ka, 1] = poly[i, 1]
            ka += 1
        if dp <= 0.0:
            out_b[kb, 0] = poly[i, 0]
            out_b[kb, 1] = poly[i, 1]
            kb += 1
        if dp * dq < 0.0:
            t = dp / (dp - dq)
            x = poly[i, 0] + t * (poly[j, 0] - poly[i, 0])
            y = poly[i, 1] + t * (poly[j, 1] - poly[i, 1])
            out_a[ka, 0] = x
            out_a[ka, 1] = y
            ka += 1
            out_b[kb, 0] = x
            out_b[kb, 1] = y
            kb += 1
    if ka < 3 or not _polygon_area(out_a, ka) > tol * tol:
        ka = 0
    if kb < 3 or not _polygon_area(out_b, kb) > tol * tol:
        kb = 0
    if ka == 0 and kb == 0:
        return -1, -1
    return ka, kb


@njit(cache=NUMBA_CACHE, nogil=True)
def cell_subtriangles(
    bounds, line_offsets, line_point, line_normal, apex_offsets, apex_xy, tol
):
    """Sub-triangles of rectangles cut along their lines (module docstring).

    Parameters
    ----------
    bounds : (nc, 4) float64, [x0, x1, y0, y1] of each cell [m]
    line_offsets : (nc + 1,) int64, the lines of cell e are
        line_offsets[e]:line_offsets[e + 1], applied in that order
    line_point, line_normal : (nl, 2) float64, a point [m] and the unit normal
    apex_offsets : (nc + 1,) int64; apex_xy : (na, 2) float64 [m], the apexes
        of each cell (the first one within tol of a piece's vertex wins)
    tol : float64 [m]

    Returns
    -------
    tri_offsets : (nc + 1,) int64, triangles of each cell
    tris : (nt, 3, 2) float64 [m], counter-clockwise
    """
    nc = bounds.shape[0]
    max_lines = 0
    for e in range(nc):
        max_lines = max(max_lines, line_offsets[e + 1] - line_offsets[e])
    # L lines cut a convex cell into at most 1 + L + L (L - 1) / 2 pieces,
    # each with at most 4 + L vertices (twice that room: the tolerance can
    # keep a vertex a line has passed)
    max_poly = 2 * (max_lines + 1) * (max_lines + 1)
    max_vert = 6 + 2 * max_lines
    polys = np.empty((max_poly, max_vert, 2))
    counts = np.empty(max_poly, np.int64)
    new_polys = np.empty((max_poly, max_vert, 2))
    new_counts = np.empty(max_poly, np.int64)
    d = np.empty(max_vert)
    piece = np.empty((max_vert, 2))
    cap = 8 * nc + 16
    tris = np.empty((cap, 3, 2))
    tri_offsets = np.zeros(nc + 1, np.int64)
    min_area = tol * tol * 1e-3
    nt = 0
    for e in range(nc):
        x0, x1, y0, y1 = bounds[e, 0], bounds[e, 1], bounds[e, 2], bounds[e, 3]
        polys[0, 0, 0] = x0
        polys[0, 0, 1] = y0
        polys[0, 1, 0] = x1
        polys[0, 1, 1] = y0
        polys[0, 2, 0] = x1
        polys[0, 2, 1] = y1
        polys[0, 3, 0] = x0
        polys[0, 3, 1] = y1
        counts[0] = 4
        n_poly = 1
        for li in range(line_offsets[e], line_offsets[e + 1]):
            px, py = line_point[li, 0], line_point[li, 1]
            nx, ny = line_normal[li, 0], line_normal[li, 1]
            n_new = 0
            for p in range(n_poly):
                k = counts[p]
                ka, kb = _split(
                    polys[p],
                    k,
                    px,
                    py,
                    nx,
                    ny,
                    tol,
                    d,
                    new_polys[n_new],
                    piece,
                )
                if ka < 0:  # whole
                    new_polys[n_new, :k] = polys[p, :k]
                    new_counts[n_new] = k
                    n_new += 1
                    continue
                if ka > 0:
                    new_counts[n_new] = ka
                    n_new += 1
                if kb > 0:
                    new_polys[n_new, :kb] = piece[:kb]
                    new_counts[n_new] = kb
                    n_new += 1
            polys, new_polys = new_polys, polys
            counts, new_counts = new_counts, counts
            n_poly = n_new
        for p in range(n_poly):
            k = counts[p]
            for a in range(apex_offsets[e], apex_offsets[e + 1]):
                j = 0
                best = np.inf
                for i in range(k):
                    dx = polys[p, i, 0] - apex_xy[a, 0]
                    dy = polys[p, i, 1] - apex_xy[a, 1]
                    dist = np.sqrt(dx * dx + dy * dy)
                    if dist < best:
                        best = dist
                        j = i
                if best <= tol:
                    for i in range(k):
                        piece[i] = polys[p, (i + j) % k]
                    polys[p, :k] = piece[:k]
                    break
            for i in range(1, k - 1):
                ax, ay = polys[p, 0, 0], polys[p, 0, 1]
                e1x = polys[p, i, 0] - ax
                e1y = polys[p, i, 1] - ay
                e2x = polys[p, i + 1, 0] - ax
                e2y = polys[p, i + 1, 1] - ay
                if not 0.5 * (e1x * e2y - e1y * e2x) > min_area:
                    continue
                if nt == cap:
                    grown = np.empty((2 * cap, 3, 2))
                    grown[:cap] = tris
                    tris = grown
                    cap *= 2
                tris[nt, 0] = polys[p, 0]
                tris[nt, 1] = polys[p, i]
                tris[nt, 2] = polys[p, i + 1]
                nt += 1
        tri_offsets[e + 1] = nt
    return tri_offsets, tris[:nt].copy()
