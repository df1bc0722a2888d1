"""Fracture geometry: polylines clipped to the domain, level sets, cell pieces, tips.

Frame (``output-format.md``): the tangent t of a segment points from vertex i
to vertex i+1; n = (-t_y, t_x).  The signed level set phi(x) is the distance to
the polyline, positive on the side n points to (paper eq. 13); at a vertex the
sign uses the pseudo-normal (the mean of the two segment normals), which makes
the sign consistent around kinks.  psi_k(x) = (x - tip_k) . d_k is the signed
distance along the outward tip direction d_k (positive ahead of the tip).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from xfemslip.errors import GeometryError

logger = logging.getLogger(__name__)

# Relative to the smallest element size: pieces of fracture shorter than this
# inside a cell are ignored (they touch the cell at a node or an edge only), and
# end points closer than this to the domain boundary are taken to lie on it.
GEOMETRY_TOL = 1.0e-9

# Crack-tip treatment when the case does not choose one (see enrichment.py and
# benchmarks/RESULTS.md): branch functions on the nodes within a radius of each
# tip.  The automatic radius is geometric, TIP_RADIUS_FRACTION of the fracture's
# length (a fixed region as h -> 0 is what gives the optimal convergence order,
# Laborde et al. 2005, IJNME 64), kept between TIP_RADIUS_CELLS and
# TIP_RADIUS_MAX_CELLS tip-cell sizes: at least enough nodes for the functions to
# act, at most a bounded number of enriched nodes per tip (the cost and the
# conditioning grow with (radius / h)^2).  Measured on the inclined crack
# (benchmarks/RESULTS.md), slip L2 error at h = a/10, a/20, a/40: 0.80 / 0.41 /
# 0.16 % with this 6-cell cap (order 1.18), 0.14 % with an 8-cell cap, 0.23 %
# with 5 cells (order 0.91), 0.29 % with a fixed 4-cell radius.  The cap of 8
# made the SuperLU factorization of the 160 x 160 reservoir case 3x slower than
# 4 cells (its band of changed dofs too wide to keep the factorization); 6
# costs 2x, the price of order >= 1.
DEFAULT_TIP = "branch"
TIP_RADIUS_CELLS = 4.0
TIP_RADIUS_MAX_CELLS = 6.0
TIP_RADIUS_FRACTION = 0.1


@dataclass(frozen=True)
class Tip:
    point: np.ndarray  # (2,) [m]
    direction: np.ndarray  # (2,) unit, pointing ahead of the tip (out of the fracture)
    end: int  # 0: first point of the polyline, 1: last point
    ramp_length: float  # length of fracture inside the tip cell [m] (see enrichment.py)
    cell_size: float  # larger side of the tip cell [m] (scale of the branch functions)
    sign: float  # n_d . n: +1 at the last point, -1 at the first (see branch.py)


@dataclass(frozen=True)
class Fracture:
    index: int  # position in the case file
    points: np.ndarray  # (k, 2) polyline clipped to the domain [m]
    tangent: np.ndarray  # (k-1, 2) unit segment tangents
    normal: np.ndarray  # (k-1, 2) unit segment normals, n = (-t_y, t_x)
    length: np.ndarray  # (k-1,) segment lengths [m]
    s_start: (
        np.ndarray
    )  # (k-1,) arc length at each segment's start, from the case file's first point [m]
    tips: tuple[Tip, ...]
    piece_cell: np.ndarray  # (p,) int64: cell holding each piece
    piece_seg: np.ndarray  # (p,) int64: segment of each piece
    piece_t: np.ndarray  # (p, 2) float64: segment parameters [ta, tb] of each piece
    friction: float
    cohesion: float
    kn: float | None  # [Pa/m]; None = automatic (contact.build_contact)
    kt: float | None
    tip_mode: str = "branch"  # "branch" | "ramp" (enrichment.py)
    tip_radius: float = 0.0  # branch enrichment radius around each tip [m]

    def signed_distance(self, pts: np.ndarray) -> np.ndarray:
        """phi at points (n, 2) [m] (eq. 13)."""
        pts = np.atleast_2d(np.asarray(pts, dtype=float))
        a = self.points[:-1]
        d = self.points[1:] - a
        rel = pts[:, None, :] - a[None, :, :]
        t = np.clip(
            np.einsum("nmk,mk->nm", rel, d) / (self.length**2)[None, :], 0.0, 1.0
        )
        diff = rel - t[..., None] * d[None, :, :]
        dist = np.linalg.norm(diff, axis=2)
        j = np.argmin(dist, axis=1)
        rows = np.arange(pts.shape[0])
        tj = t[rows, j]
        nrm = self.normal[j].copy()
        m = self.normal.shape[0]
        # pseudo-normal at interior vertices
        at_start = (tj <= 0.0) & (j > 0)
        at_end = (tj >= 1.0) & (j < m - 1)
        nrm[at_start] += self.normal[j[at_start] - 1]
        nrm[at_end] += self.normal[j[at_end] + 1]
        side = np.einsum("nk,nk->n", diff[rows, j], nrm)
        return np.where(side >= 0.0, 1.0, -1.0) * dist[rows, j]

    def side(self, pts: np.ndarray) -> np.ndarray:
        """H(phi) of eq. 12 at points (n, 2): +1 where phi >= 0, else -1.

        Points within round-off of the fracture (|phi| <= 1e-12 of its length)
        count as phi = 0, i.e. +1.
        """
        tol = 1e-12 * float(self.length.sum())
        return np.where(self.signed_distance(pts) >= -tol, 1.0, -1.0)

    def ramp(self, pts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Tip ramp R (n,) in [0, 1] and its gradient (n, 2) [1/m].

        R = prod_k clip(-psi_k / l_k, 0, 1): 1 away from the tips, falling
        linearly to 0 at each tip over the fracture's length l_k in the tip
        cell, and 0 ahead of it.  The jump of F = H R across the fracture is
        2 R, so the modelled discontinuity ends exactly at the tip.
        """
        pts = np.atleast_2d(np.asarray(pts, dtype=float))
        R = np.ones(pts.shape[0])
        grad = np.zeros((pts.shape[0], 2))
        for tip in self.tips:
            psi = (pts - tip.point) @ tip.direction
            r = np.clip(-psi / tip.ramp_length, 0.0, 1.0)
            inside = (r > 0.0) & (r < 1.0)
            dr = np.where(inside, -1.0 / tip.ramp_length, 0.0)[:, None] * tip.direction
            grad = grad * r[:, None] + R[:, None] * dr
            R = R * r
        return R, grad

    def kink_lines(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """Lines (point, unit normal) across which F is not smooth.

        The segment lines (the jump) and, at each tip, the lines psi = 0 and
        psi = -l where the ramp has kinks.  Sub-cells are cut along them.
        """
        lines = [(self.points[k], self.normal[k]) for k in range(self.normal.shape[0])]
        for tip in self.tips:
            lines.append((tip.point, tip.direction))
            lines.append((tip.point - tip.ramp_length * tip.direction, tip.direction))
        return lines

    def arc_length(self, seg: np.ndarray, t: np.ndarray) -> np.ndarray:
        """Arc length [m] of the points at parameter t of segments seg."""
        return self.s_start[seg] + t * self.length[seg]


def clip_segment(p0, p1, boxes):
    """Liang-Barsky: parameters [ta, tb] of segment p0-p1 inside each box.

    boxes : (m, 4) [x0, x1, y0, y1].  Returns ta, tb (m,); empty where ta >= tb.
    """
    d = np.asarray(p1, float) - np.asarray(p0, float)
    ta = np.zeros(boxes.shape[0])
    tb = np.ones(boxes.shape[0])
    for k, (lo, hi) in enumerate(((0, 1), (2, 3))):
        if d[k] == 0.0:
            outside = (p0[k] < boxes[:, lo]) | (p0[k] > boxes[:, hi])
            ta[outside] = 1.0
            tb[outside] = 0.0
            continue
        t_lo = (boxes[:, lo] - p0[k]) / d[k]
        t_hi = (boxes[:, hi] - p0[k]) / d[k]
        ta = np.maximum(ta, np.minimum(t_lo, t_hi))
        tb = np.minimum(tb, np.maximum(t_lo, t_hi))
    return ta, tb


def _clip_to_domain(points, box, tol, key):
    """Clip a polyline to the domain box; it must stay in one connected piece."""
    kept = []
    for p0, p1 in zip(points[:-1], points[1:], strict=True):
        ta, tb = clip_segment(p0, p1, box[None, :])
        if tb[0] - ta[0] <= 0.0:
            kept.append(None)
            continue
        kept.append((p0 + ta[0] * (p1 - p0), p0 + tb[0] * (p1 - p0), ta[0], tb[0]))
    idx = [k for k, piece in enumerate(kept) if piece is not None]
    if not idx:
        raise GeometryError(f"{key}: the fracture misses the domain")
    if idx != list(range(idx[0], idx[-1] + 1)) or any(
        (kept[k][3] < 1.0 and k != idx[-1]) or (kept[k][2] > 0.0 and k != idx[0])
        for k in idx
    ):
        raise GeometryError(
            f"{key}: the fracture leaves and re-enters the domain; "
            "split it into separate fractures"
        )
    pts = [kept[idx[0]][0]] + [kept[k][1] for k in idx]
    pts = np.array(pts)
    seg_len = np.linalg.norm(np.diff(points, axis=0), axis=1)
    s_offset = float(seg_len[: idx[0]].sum() + kept[idx[0]][2] * seg_len[idx[0]])
    # drop segments that became (nearly) zero length by clipping
    keep = np.concatenate([[True], np.linalg.norm(np.diff(pts, axis=0), axis=1) > tol])
    return pts[keep], s_offset


def _on_boundary(p, box, tol):
    return (
        min(
            abs(p[0] - box[0]),
            abs(p[0] - box[1]),
            abs(p[1] - box[2]),
            abs(p[1] - box[3]),
        )
        <= tol
    )


def _cell_pieces(mesh, points, tol):
    """Pieces of each segment in each cell, deduplicated, in polyline order."""
    cells, segs, tas, tbs = [], [], [], []
    for k, (p0, p1) in enumerate(zip(points[:-1], points[1:], strict=True)):
        lo, hi = np.minimum(p0, p1) - tol, np.maximum(p0, p1) + tol
        i0 = max(np.searchsorted(mesh.x, lo[0], side="right") - 1, 0)
        i1 = min(np.searchsorted(mesh.x, hi[0], side="left"), mesh.nx)
        j0 = max(np.searchsorted(mesh.y, lo[1], side="right") - 1, 0)
        j1 = min(np.searchsorted(mesh.y, hi[1], side="left"), mesh.ny)
        ii, jj = np.meshgrid(np.arange(i0, i1), np.arange(j0, j1))
        cand = mesh.cell_of(ii.ravel(), jj.ravel())
        ta, tb = clip_segment(p0, p1, mesh.bounds[cand])
        seg_len = np.linalg.norm(p1 - p0)
        ok = (tb - ta) * seg_len > tol
        order = np.argsort(ta[ok], kind="stable")
        seen = set()
        for c, a, b in zip(cand[ok][order], ta[ok][order], tb[ok][order], strict=True):
            key = (round(a * seg_len / tol), round(b * seg_len / tol))
            if key in seen:  # the same piece on the edge shared by two cells
                continue
            seen.add(key)
            cells.append(c)
            segs.append(k)
            tas.append(a)
            tbs.append(b)
    return (
        np.array(cells, dtype=np.int64),
        np.array(segs, dtype=np.int64),
        np.column_stack([tas, tbs]) if tas else np.zeros((0, 2)),
    )


def build_fracture(mesh, spec, box) -> Fracture:
    """Fracture from a FractureSpec on a mesh; box = [x0, x1, y0, y1] of the domain."""
    key = f"fractures[{spec.index}]"
    tol = GEOMETRY_TOL * mesh.h_min
    raw = np.asarray(spec.points, dtype=float)
    pts, s_offset = _clip_to_domain(raw, box, tol, key)
    if pts.shape[0] < 2:
        raise GeometryError(
            f"{key}: less than {tol:.1e} m of the fracture lies in the domain"
        )
    d = np.diff(pts, axis=0)
    length = np.linalg.norm(d, axis=1)
    tangent = d / length[:, None]
    normal = np.column_stack([-tangent[:, 1], tangent[:, 0]])
    s_start = s_offset + np.concatenate([[0.0], np.cumsum(length)[:-1]])
    piece_cell, piece_seg, piece_t = _cell_pieces(mesh, pts, tol)
    if piece_cell.size == 0:
        raise GeometryError(f"{key}: no part of the fracture lies inside an element")
    tips = []
    for end in (0, 1):
        p = pts[0] if end == 0 else pts[-1]
        if _on_boundary(p, box, tol):
            continue
        direction = -tangent[0] if end == 0 else tangent[-1]
        k = 0 if end == 0 else -1
        ramp = (piece_t[k, 1] - piece_t[k, 0]) * length[piece_seg[k]]
        b = mesh.bounds[piece_cell[k]]
        tips.append(
            Tip(
                point=p.copy(),
                direction=direction,
                end=end,
                ramp_length=float(ramp),
                cell_size=float(max(b[1] - b[0], b[3] - b[2])),
                sign=1.0 if end == 1 else -1.0,
            )
        )
    tip_mode, radius = _tip_enrichment(spec, key, tips, length)
    frac = Fracture(
        index=spec.index,
        points=pts,
        tangent=tangent,
        normal=normal,
        length=length,
        s_start=s_start,
        tips=tuple(tips),
        piece_cell=piece_cell,
        piece_seg=piece_seg,
        piece_t=piece_t,
        friction=spec.friction,
        cohesion=spec.cohesion,
        kn=spec.kn,
        kt=spec.kt,
        tip_mode=tip_mode,
        tip_radius=float(radius),
    )
    logger.debug(
        "%s: %d segment(s), %d tip(s), %d cut cells",
        key,
        length.size,
        len(tips),
        len(np.unique(piece_cell)),
    )
    return frac


def _tip_enrichment(spec, key, tips, length):
    """Tip mode and branch radius of a fracture, within what its geometry allows.

    B1 jumps along the whole straight ray behind its tip, so the supports of
    branch-enriched nodes (radius + one cell diagonal from the tip) must stay
    on the tip segment and short of the fracture's middle; otherwise the ray
    would cut the body where there is no fracture (past a kink or past the
    other tip).  A larger radius is reduced to that limit, and a fracture
    whose tip cells do not fit at all falls back to the ramp; both are logged
    as warnings.
    """
    mode = getattr(spec, "tip", None) or DEFAULT_TIP
    given = getattr(spec, "tip_radius", None)
    if mode != "branch" or not tips:
        return mode, float(given or 0.0)
    h_tip = max(t.cell_size for t in tips)
    radius = (
        given
        if given is not None
        else min(
            max(TIP_RADIUS_FRACTION * float(length.sum()), TIP_RADIUS_CELLS * h_tip),
            TIP_RADIUS_MAX_CELLS * h_tip,
        )
    )
    limit = np.inf
    for tip in tips:
        seg = length[0] if tip.end == 0 else length[-1]
        diag = np.sqrt(2.0) * tip.cell_size
        limit = min(limit, min(seg, 0.5 * float(length.sum())) - diag)
        if limit < diag:
            logger.warning(
                '%s: tip = "branch" needs a straight tip segment of at least 2 cell '
                "diagonals (%.3g m) on each side of a tip; this fracture is too short "
                "or "
                'kinked near a tip, so it uses tip = "ramp"',
                key,
                2 * diag,
            )
            return "ramp", 0.0
    if radius > limit:
        level = logging.WARNING if given is not None else logging.INFO
        logger.log(
            level,
            "%s: branch enrichment radius %.3g m reduced to %.3g m so that "
            "the tip functions stay on the fracture's tip segments",
            key,
            radius,
            limit,
        )
        radius = limit
    return mode, float(radius)


def _segments_cross(a0, a1, b0, b1):
    """True if closed segments a and b intersect."""

    def orient(p, q, r):
        return (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])

    o1, o2 = orient(a0, a1, b0), orient(a0, a1, b1)
    o3, o4 = orient(b0, b1, a0), orient(b0, b1, a1)
    if o1 * o2 < 0 and o3 * o4 < 0:
        return True

    def on(p, q, r):
        return min(p[0], q[0]) <= r[0] <= max(p[0], q[0]) and min(p[1], q[1]) <= r[
            1
        ] <= max(p[1], q[1])

    return any(
        o == 0 and on(p, q, r)
        for o, p, q, r in (
            (o1, a0, a1, b0),
            (o2, a0, a1, b1),
            (o3, b0, b1, a0),
            (o4, b0, b1, a1),
        )
    )


def build_fractures(mesh, specs, box) -> tuple[Fracture, ...]:
    """All fractures of a case; intersecting fractures are refused (no networks yet)."""
    fracs = tuple(build_fracture(mesh, s, np.asarray(box, float)) for s in specs)
    for a in range(len(fracs)):
        for b in range(a + 1, len(fracs)):
            pa, pb = fracs[a].points, fracs[b].points
            for i in range(len(pa) - 1):
                for j in range(len(pb) - 1):
                    if _segments_cross(pa[i], pa[i + 1], pb[j], pb[j + 1]):
                        raise GeometryError(
                            f"fractures[{fracs[a].index}] and "
                            f"fractures[{fracs[b].index}] "
                            "intersect: intersecting fractures (networks) are not "
                            "supported "
                            "yet; move one so they do not touch"
                        )
    return fracs
