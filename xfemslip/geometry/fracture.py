"""Fracture geometry: polylines clipped to the domain, level sets, cell pieces, tips.

Frame (``output-format.md``): the tangent t of a segment points from vertex i
to vertex i+1; n = (-t_y, t_x).  The signed level set phi(x) is the distance to
the polyline, positive on the side n points to (paper eq. 13); at a vertex the
sign uses the pseudo-normal (the mean of the two segment normals), which makes
the sign consistent around kinks.  psi_k(x) = (x - tip_k) . d_k is the signed
distance along the outward tip direction d_k (positive ahead of the tip).

Where fractures meet, and how a whole network is built, is in
xfemslip.geometry.junctions.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from xfemslip.errors import GeometryError
from xfemslip.geometry.box import Box
from xfemslip.geometry.polyline import first_meeting, simplify

logger = logging.getLogger(__name__)

# Relative to the smallest element size: pieces of fracture shorter than this
# inside a cell are ignored (they touch the cell at a node or an edge only), and
# end points closer than this to the domain boundary are taken to lie on it.
GEOMETRY_TOL = 1.0e-9

# Fracture geometry below the mesh resolution (docs/method.md, *Fracture
# geometry*), in local cell sizes h (the smaller side of the cell holding a
# vertex).  A clipped polyline with a segment shorter than
# SIMPLIFY_MIN_SEGMENT h is simplified by
# Douglas-Peucker with a shortest segment (polyline.simplify): it keeps the
# vertices more than SIMPLIFY_DEVIATION h off the simplified line that lie at
# least SIMPLIFY_MIN_SEGMENT h from their neighbours in it, and the end points
# (on the domain boundary where the polyline is clipped).  A kink with arms
# of a quarter cell or more stays; finer detail (a digitised trace, a zigzag
# inside one cell) cannot be resolved by one enriched cell and would only
# multiply the sub-cells and contact points.  No vertex moves by more than
# h/4, about the error of standard XFEM's nodal level set, which makes each
# cut straight inside a cell.  Pieces of one fracture in one cell beyond
# MAX_PIECES_PER_CELL (a polyline folded many times inside a cell, with long
# strokes) are refused: their sub-cells grow like the square of the count.
SIMPLIFY_MIN_SEGMENT = 0.25
SIMPLIFY_DEVIATION = 0.05
MAX_PIECES_PER_CELL = 12
# Point-segment pairs per chunk of Fracture.signed_distance (its temporaries
# take about 100 B a pair).
DISTANCE_CHUNK = 1 << 19

# Crack-tip treatment when the case does not choose one (see enrichment.py and
# docs/method.md, *Enrichment*): branch functions on the nodes within a radius of each
# tip.  The automatic radius is geometric, TIP_RADIUS_FRACTION of the fracture's
# length (a fixed region as h -> 0 is what gives the optimal convergence order,
# Laborde et al. 2005, IJNME 64), kept between TIP_RADIUS_CELLS and
# TIP_RADIUS_MAX_CELLS tip-cell sizes: at least enough nodes for the functions to
# act, at most a bounded number of enriched nodes per tip (the cost and the
# conditioning grow with (radius / h)^2).  Measured on the inclined crack
# (docs/performance.md, *Accuracy against run time*), slip L2 error at
# h = a/10, a/20, a/40: 0.80 / 0.41 / 0.16 % with this 6-cell cap (order
# 1.18), 0.14 % with an 8-cell cap, 0.23 % with 5 cells (order 0.91), 0.29 %
# with a fixed 4-cell radius.  The cap of 8
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
    # junctions (build_fractures): the fracture is cut into arms at the X
    # crossings where it is the secondary; arm a covers arc lengths between
    # arm_splits[a-1] and arm_splits[a] and has its own Heaviside enrichment,
    # cut by the lines in arms[a].  junction_s: arc lengths of all junctions on
    # the fracture (contact patches and cell pieces are split there).
    arm_splits: tuple = ()
    arms: tuple = ((),)
    junction_s: tuple = ()
    junction_ends: tuple = ()  # ends (0 first, 1 last) lying on another fracture
    # slip weakening of friction and cohesion (case.specs.SlipWeakeningSpec),
    # or None for constant Coulomb friction; friction and cohesion above are
    # then the static values
    weakening: object = None

    def arm_of(self, s: np.ndarray) -> np.ndarray:
        """Arm of points at arc lengths s (n,) int64."""
        return np.searchsorted(np.asarray(self.arm_splits, float), s).astype(np.int64)

    def junction_factor(self, arm, probe, side, tol=0.0) -> np.ndarray:
        """J / H of an arm at points probe (n, 2) with H = side (n,) (Cut)."""
        J = np.asarray(side, float).copy()
        for cut in self.arms[arm]:
            beyond = cut.sign * ((np.atleast_2d(probe) - cut.point) @ cut.normal) < -tol
            J[beyond] = cut.far
        return J

    def signed_distance(self, pts: np.ndarray) -> np.ndarray:
        """phi at points (n, 2) [m] (eq. 13).

        Points x segments arrays are formed in chunks of at most
        DISTANCE_CHUNK pairs, so the memory stays bounded for a polyline of
        many segments; each point's value is that of a single pass.
        """
        pts = np.atleast_2d(np.asarray(pts, dtype=float))
        rows = max(1, DISTANCE_CHUNK // max(self.length.size, 1))
        if pts.shape[0] <= rows:
            return self._signed_distance(pts)
        return np.concatenate(
            [
                self._signed_distance(pts[i : i + rows])
                for i in range(0, pts.shape[0], rows)
            ]
        )

    def _signed_distance(self, pts: np.ndarray) -> np.ndarray:
        """signed_distance of one chunk of points (n, 2)."""
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
        lines += self.cut_lines()
        return lines

    def cut_lines(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """The junction lines across which an arm's function J jumps."""
        return [(c.point, c.normal) for arm in self.arms for c in arm]

    def point_at(self, s) -> tuple[np.ndarray, np.ndarray]:
        """(xy (n, 2), normal (n, 2)) at arc lengths s (n,) [m] along the
        (clipped) polyline; beyond its ends, on its first or last segment's
        line."""
        s = np.atleast_1d(np.asarray(s, float))
        ends = self.s_start + self.length
        seg = np.minimum(np.searchsorted(ends, s), self.length.size - 1)
        t = (s - self.s_start[seg])[:, None]
        return self.points[seg] + t * self.tangent[seg], self.normal[seg]

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
        # a direction of 1e-310 m overflows to +-inf: the right limits of a
        # segment that is all but parallel to the edge
        with np.errstate(over="ignore"):
            t_lo = (boxes[:, lo] - p0[k]) / d[k]
            t_hi = (boxes[:, hi] - p0[k]) / d[k]
        ta = np.maximum(ta, np.minimum(t_lo, t_hi))
        tb = np.minimum(tb, np.maximum(t_lo, t_hi))
    return ta, tb


def clip_to_domain(points, box: Box, tol, key):
    """Clip a polyline to the domain box; it must stay in one connected piece."""
    boxes = np.asarray(box, float)[None, :]
    # per segment: (start, end, t_start, t_end) of its part inside, or None
    kept: list[tuple[np.ndarray, np.ndarray, float, float] | None] = []
    for p0, p1 in zip(points[:-1], points[1:], strict=True):
        ta, tb = clip_segment(p0, p1, boxes)
        if tb[0] - ta[0] <= 0.0:
            kept.append(None)
            continue
        kept.append((p0 + ta[0] * (p1 - p0), p0 + tb[0] * (p1 - p0), ta[0], tb[0]))
    idx = [k for k, piece in enumerate(kept) if piece is not None]
    inside = [piece for piece in kept if piece is not None]  # those of idx
    if not idx:
        raise GeometryError(f"{key}: the fracture misses the domain")
    if idx != list(range(idx[0], idx[-1] + 1)) or any(
        (piece[3] < 1.0 and k != idx[-1]) or (piece[2] > 0.0 and k != idx[0])
        for k, piece in zip(idx, inside, strict=True)
    ):
        raise GeometryError(
            f"{key}: the fracture leaves and re-enters the domain; "
            "split it into separate fractures"
        )
    pts = np.array([inside[0][0]] + [piece[1] for piece in inside])
    seg_len = np.linalg.norm(np.diff(points, axis=0), axis=1)
    s_offset = float(seg_len[: idx[0]].sum() + inside[0][2] * seg_len[idx[0]])
    # drop segments that became (nearly) zero length by clipping
    keep = np.concatenate([[True], np.linalg.norm(np.diff(pts, axis=0), axis=1) > tol])
    if keep.sum() < 2:
        raise GeometryError(
            f"{key}: the fracture is shorter than the geometric tolerance "
            f"({tol:.3g} m) inside the domain; give it a length of at least a "
            "fraction of a cell"
        )
    return pts[keep], s_offset


def _cell_sizes(mesh, pts) -> np.ndarray:
    """(k,) smaller side [m] of the cell holding each point (k, 2)."""
    i = np.clip(np.searchsorted(mesh.x, pts[:, 0], side="right") - 1, 0, mesh.nx - 1)
    j = np.clip(np.searchsorted(mesh.y, pts[:, 1], side="right") - 1, 0, mesh.ny - 1)
    return np.minimum(np.diff(mesh.x)[i], np.diff(mesh.y)[j])


def at_mesh_resolution(mesh, pts, key):
    """The clipped polyline pts (k, 2) at the mesh's resolution (see
    SIMPLIFY_MIN_SEGMENT); logs a warning when vertices are dropped."""
    h = _cell_sizes(mesh, pts)
    kept = simplify(pts, h, SIMPLIFY_MIN_SEGMENT, SIMPLIFY_DEVIATION)
    if kept.size == len(pts):
        return pts
    out = pts[kept]
    h_text = f"{h.min():.3g} m"
    if f"{h.max():.3g}" != f"{h.min():.3g}":  # a graded mesh
        h_text = f"{h.min():.3g} to {h.max():.3g} m"
    logger.warning(
        "%s: %s points simplified to %d below the mesh resolution (tolerance: "
        "segments of at least %g h, vertices within %g h of the line dropped; "
        "h = %s)",
        key,
        f"{len(pts):,}",
        len(out),
        SIMPLIFY_MIN_SEGMENT,
        SIMPLIFY_DEVIATION,
        h_text,
    )
    pair = first_meeting(out)
    if pair is not None:
        raise GeometryError(
            f"{key}: simplified below the mesh resolution ({len(pts):,} points to "
            f"{len(out)}), the polyline crosses itself (segments {pair[0]} and "
            f"{pair[1]}); smooth the polyline or refine the mesh"
        )
    return out


def on_boundary(p, box: Box, tol):
    return (
        min(
            abs(p[0] - box[0]),
            abs(p[0] - box[1]),
            abs(p[1] - box[2]),
            abs(p[1] - box[3]),
        )
        <= tol
    )


def cell_pieces(mesh, points, tol):
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


def _check_pieces_per_cell(mesh, piece_cell, key) -> None:
    """Refuse a fracture folded into more than MAX_PIECES_PER_CELL pieces in
    one cell (GeometryError naming the cell)."""
    count = np.bincount(piece_cell)
    c = int(np.argmax(count))
    if count[c] > MAX_PIECES_PER_CELL:
        b = mesh.bounds[c]
        raise GeometryError(
            f"{key}: {count[c]} pieces of the fracture in the cell [{b[0]:.4g}, "
            f"{b[1]:.4g}] x [{b[2]:.4g}, {b[3]:.4g}], more than the "
            f"{MAX_PIECES_PER_CELL} a cell can resolve; smooth the polyline or "
            "refine the mesh"
        )


def build_fracture(
    mesh, spec, box: Box, points=None, s_offset=0.0, junction_ends=(), reach=None
) -> Fracture:
    """Fracture from a FractureSpec on a mesh; box: the domain.

    points / s_offset : the polyline already clipped (and snapped to its
    junctions, build_fractures); junction_ends : ends lying on another fracture
    (no tip there); reach : {end: arc length from that tip to the nearest
    junction} (the branch functions must not reach past a junction).
    """
    key = f"fractures[{spec.index}]"
    tol = GEOMETRY_TOL * mesh.h_min
    if points is None:
        raw = np.asarray(spec.points, dtype=float)
        pts, s_offset = clip_to_domain(raw, box, tol, key)
        pts = at_mesh_resolution(mesh, pts, key)
    else:
        pts = np.asarray(points, dtype=float)
    if pts.shape[0] < 2:
        raise GeometryError(
            f"{key}: less than {tol:.1e} m of the fracture lies in the domain"
        )
    d = np.diff(pts, axis=0)
    length = np.linalg.norm(d, axis=1)
    tangent = d / length[:, None]
    normal = np.column_stack([-tangent[:, 1], tangent[:, 0]])
    s_start = s_offset + np.concatenate([[0.0], np.cumsum(length)[:-1]])
    piece_cell, piece_seg, piece_t = cell_pieces(mesh, pts, tol)
    if piece_cell.size == 0:
        raise GeometryError(f"{key}: no part of the fracture lies inside an element")
    _check_pieces_per_cell(mesh, piece_cell, key)
    tips = []
    for end in (0, 1):
        p = pts[0] if end == 0 else pts[-1]
        if on_boundary(p, box, tol) or end in junction_ends:
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
    tip_mode, radius = _tip_enrichment(spec, key, tips, length, reach or {})
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
        junction_ends=tuple(sorted(junction_ends)),
        weakening=spec.weakening,
    )
    logger.debug(
        "%s: %d segment(s), %d tip(s), %d cut cells",
        key,
        length.size,
        len(tips),
        len(np.unique(piece_cell)),
    )
    return frac


def _tip_enrichment(spec, key, tips, length, reach):
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
        limit = min(limit, reach.get(tip.end, np.inf) - diag)
        if limit < diag:
            logger.warning(
                '%s: tip = "branch" needs a straight tip segment of at least 2 cell '
                "diagonals (%.3g m) on each side of a tip; this fracture is too short, "
                'kinked or meets another fracture near a tip, so it uses tip = "ramp"',
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
