"""Junctions of fractures: where fractures meet (X, T/Y, V), the snapping of
ends onto nearby fractures, the cuts of each arm's Heaviside, and
``build_fractures``, which builds all fractures of a case with them.

The rules are stated above JUNCTION_SNAP_CELLS; the single fracture (its
clipping, level sets, cell pieces and tips) is in ``fracture``.  The module
stays whole (about 650 lines): the snapping is one algorithm whose helpers
each serve one of those rules, and build_fractures applies its result;
split, the rules would be stated in one file and enforced in another.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, replace

import numpy as np

from xfemslip.errors import GeometryError
from xfemslip.geometry.box import Box
from xfemslip.geometry.fracture import (
    GEOMETRY_TOL,
    Fracture,
    at_mesh_resolution,
    build_fracture,
    cell_pieces,
    clip_to_domain,
    on_boundary,
)

logger = logging.getLogger(__name__)

# Distinct fractures that may cut one cell.  Each brings its own enrichment
# functions to the cell's nodes, so the cell's matrix and sub-cells grow with
# the square of the count, and the junction search with the pairs of nearby
# ends; beyond this the mesh cannot tell the fractures apart (measured: at
# most 7 in generated networks of 200 fractures on 50 x 50 cells, 2 in the
# shipped network).  Checked before the junction search.
MAX_FRACTURES_PER_CELL = 16


@dataclass(frozen=True)
class Cut:
    """A junction's cut of one arm's Heaviside (Daux et al. 2000, eq. 8).

    The arm's function is J = H(phi) on the side ``sign`` of the line through
    ``point`` with unit normal ``normal`` (the main fracture's segment at the
    junction), and the constant ``far`` on the other side.
    """

    point: np.ndarray  # (2,) junction point [m]
    normal: np.ndarray  # (2,) unit normal of the main fracture's segment
    sign: float  # +1/-1: side of that line where the arm lies
    far: float  # value of J beyond the line (0 at T and X; outer side at V)


def _check_fractures_per_cell(mesh, polylines, names, tol) -> None:
    """Refuse more than MAX_FRACTURES_PER_CELL fractures in one cell
    (GeometryError naming the cell and the first fractures in it)."""
    cells = [np.unique(cell_pieces(mesh, pts, tol)[0]) for pts in polylines]
    if not cells:
        return
    count = np.bincount(np.concatenate(cells), minlength=mesh.n_cells)
    c = int(np.argmax(count))
    if count[c] <= MAX_FRACTURES_PER_CELL:
        return
    b = mesh.bounds[c]
    inside = [names[f] for f, mine in enumerate(cells) if c in mine]
    raise GeometryError(
        f"{count[c]} fractures cut the cell [{b[0]:.4g}, {b[1]:.4g}] x "
        f"[{b[2]:.4g}, {b[3]:.4g}] ({', '.join(inside[:3])}, ...), more than the "
        f"{MAX_FRACTURES_PER_CELL} a cell can tell apart; refine the mesh or thin "
        "the network"
    )


# ------------------------------------------------------------------ junctions
#
# Junction rules (h: the smallest cell size, snap = JUNCTION_SNAP_CELLS h,
# tol = GEOMETRY_TOL h).
#
# 0. Fractures that overlap as given (within tol of each other along a common
#    stretch longer than tol: collinear, at whatever tiny angle) are refused
#    with one line naming both.
# 1. Snapping.  An end of a fracture (not on the domain boundary) closer than
#    snap to another fracture is moved onto it, each end at most once, pairs
#    in listing order:
#    - two ends closer than snap to each other are a shared end point (V):
#      the secondary's end (the shorter fracture's) moves onto the main's;
#    - an end closer than snap to the other's body ends on it (T/Y): trimmed
#      back to the crossing if it overshoots by less than snap measured along
#      itself (a longer overshoot is an X), else moved to the nearest point.
#      A dangling arm shorter than half a cell cannot be resolved by the mesh
#      (its tip enrichment would sit in the junction cell), so it is not an X.
#    A move is made only if afterwards
#    - the end segment is at least JUNCTION_MIN_SEGMENT_CELLS h long, and
#      still meets every fracture it met before (snapping joins fractures,
#      it never parts them);
#    - for a move that turns the end segment (a V, a move to the nearest
#      point; a trim keeps the fracture's own direction): that segment makes
#      an angle of at least JUNCTION_MIN_ANGLE with every segment of another
#      fracture leaving the junction point, and lies along no other fracture.
#    So snapping never lays a fracture onto another nor makes it meet one
#    tangentially: an end of a near-parallel fracture (or of a narrow V)
#    stays where it is, a tip beside the other fracture.  The angle is that
#    of the smallest wedge a snap may create; smaller ones occur only where
#    the fractures are drawn so.
# 2. Junctions are then found on the snapped polylines, within tol only:
#    where two fractures meet at an end of both it is a V, at an end of one
#    a T (that one is the secondary), elsewhere an X (the secondary is the
#    lower-ranked, _rank_key).  An end within tol of the other fracture is
#    where they meet, however small their angle (_segment_crossing).  So
#    every junction point lies on both fractures, and two fractures that
#    meet have a junction.
# A junction at any angle can be built: the cut of an arm (Cut) needs only
# the side of the main's line the arm lies on, defined wherever two fractures
# meet without overlapping (for two collinear fractures meeting end to end,
# the side where the junction function is not constant).
# A junction on a mesh node or edge needs no special case: cell pieces are
# split at the junction only where it lies strictly inside a piece.
JUNCTION_SNAP_CELLS = 0.5
# A snap turns an end segment by up to atan(snap / its length); below 10 deg
# it would join fractures that run alongside each other (a near-parallel
# pair, en echelon ends, a near copy) into a sliver a few cells long, which
# the cells cannot resolve either way (docs/performance.md, "Buildable
# networks": the snaps this refuses and what they change).
JUNCTION_MIN_ANGLE = 10.0  # [deg]
# A snap may shorten an end segment (a trim, a V); it must not make it vanish
# or leave a stub far below the cell size.
JUNCTION_MIN_SEGMENT_CELLS = 0.1


def _to_segments(pts, p):
    """Distances (m,), parameters (m,) and nearest points (m, 2) of the
    polyline's m segments to the point p."""
    a = pts[:-1]
    d = pts[1:] - a
    t = np.clip(np.einsum("mk,mk->m", p - a, d) / np.einsum("mk,mk->m", d, d), 0, 1)
    q = a + t[:, None] * d
    return np.linalg.norm(q - p, axis=1), t, q


def _closest_on_polyline(pts, p):
    """Distance, segment, parameter and point of the polyline nearest to p."""
    dist, t, q = _to_segments(pts, p)
    j = int(np.argmin(dist))
    return float(dist[j]), j, float(t[j]), q[j]


def _arc(pts, seg, t):
    """Arc length from the polyline's first point of (seg, t)."""
    seg_len = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    return float(seg_len[:seg].sum() + t * seg_len[seg])


def _overlap(p0, p1, q0, q1, tol):
    """Whether segments p0-p1 and q0-q1 ((2,) float sequences) lie within tol
    of each other along a common stretch longer than tol (a collinear
    overlap, at whatever tiny angle)."""
    dx, dy = p1[0] - p0[0], p1[1] - p0[1]
    length = math.hypot(dx, dy)
    ux, uy = dx / length, dy / length
    ax, ay, bx, by = q0[0] - p0[0], q0[1] - p0[1], q1[0] - p0[0], q1[1] - p0[1]
    s0, s1 = ax * ux + ay * uy, bx * ux + by * uy  # q's ends along p
    lo, hi = max(min(s0, s1), 0.0), min(max(s0, s1), length)
    if hi - lo <= tol:
        return False
    # q's offset from p's line is linear along the stretch: check its two ends
    h0, h1 = ax * uy - ay * ux, bx * uy - by * ux
    slope = (h1 - h0) / (s1 - s0)
    return max(abs(h0 + slope * (lo - s0)), abs(h0 + slope * (hi - s0))) <= tol


def _apart(p0, p1, q0, q1, tol):
    """Whether the boxes of two segments are further apart than tol."""
    return (
        max(p0[0], p1[0]) < min(q0[0], q1[0]) - tol
        or max(q0[0], q1[0]) < min(p0[0], p1[0]) - tol
        or max(p0[1], p1[1]) < min(q0[1], q1[1]) - tol
        or max(q0[1], q1[1]) < min(p0[1], p1[1]) - tol
    )


def _segment_crossing(p0, p1, q0, q1, tol):
    """Parameters [(ta, tb)] where segments p0-p1 and q0-q1 ((2,) float
    sequences, not overlapping) meet: the end points of one lying within tol
    of the other (a T, a shared end, a near miss), else their crossing; []
    where they are further apart than tol.

    An end within tol of the other segment lies in the stretch where the two
    meet, so it is the same meeting as their crossing, and the one to report:
    at an angle theta the crossing's place along the segments is uncertain by
    the coordinates' round-off / theta (more than tol = 1e-9 h below about
    1e-6 rad ten cells from the origin), the end's distance to the other
    segment is not.  So two ends trimmed onto one crossing, or an end lying
    on the other fracture, are found at those ends (a V, a T), however small
    the angle.
    """
    d1x, d1y, d2x, d2y = p1[0] - p0[0], p1[1] - p0[1], q1[0] - q0[0], q1[1] - q0[1]
    hits = _end_hits(p0, p1, q0, q1, d1x, d1y, d2x, d2y, tol)
    if hits:
        return hits
    l1, l2 = math.hypot(d1x, d1y), math.hypot(d2x, d2y)
    cross = d1x * d2y - d1y * d2x
    if abs(cross) > 1e-12 * l1 * l2:
        rx, ry = q0[0] - p0[0], q0[1] - p0[1]
        ta = (rx * d2y - ry * d2x) / cross
        tb = (rx * d1y - ry * d1x) / cross
        if 0.0 <= ta <= 1.0 and 0.0 <= tb <= 1.0:
            return [(ta, tb)]
    return []


def _end_hits(p0, p1, q0, q1, d1x, d1y, d2x, d2y, tol):
    """Parameters [(ta, tb)] of the end points of segment p or q lying within
    tol of the other (d1, d2: their directions p1 - p0, q1 - q0)."""
    hits = []
    for ta, p in ((0.0, p0), (1.0, p1)):
        tb = _nearest_parameter(q0, d2x, d2y, p)
        if math.dist(p, (q0[0] + tb * d2x, q0[1] + tb * d2y)) <= tol:
            hits.append((ta, tb))
    for tb, q in ((0.0, q0), (1.0, q1)):
        ta = _nearest_parameter(p0, d1x, d1y, q)
        if math.dist(q, (p0[0] + ta * d1x, p0[1] + ta * d1y)) <= tol:
            hits.append((ta, tb))
    return hits


def _nearest_parameter(a, dx, dy, p):
    """Parameter in [0, 1] of the point of segment a + t (dx, dy) nearest p."""
    t = ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / (dx * dx + dy * dy)
    return min(max(t, 0.0), 1.0)


def _refuse_overlap(pa, pb, tol, names):
    """GeometryError naming both if two polylines overlap along a stretch."""
    A, B = pa.tolist(), pb.tolist()
    for i in range(len(A) - 1):
        for j in range(len(B) - 1):
            if _apart(A[i], A[i + 1], B[j], B[j + 1], tol):
                continue
            if _overlap(A[i], A[i + 1], B[j], B[j + 1], tol) or _overlap(
                B[j], B[j + 1], A[i], A[i + 1], tol
            ):
                raise GeometryError(
                    f"{names[0]} and {names[1]} overlap along a common line "
                    f"(segments {i} and {j}); merge them into one fracture "
                    "or move one"
                )


def _crossings(pa, pb, tol, names):
    """Crossing points of two polylines: list of (arc_a, arc_b, point).

    Fractures overlapping along a common line raise GeometryError.
    """
    _refuse_overlap(pa, pb, tol, names)
    out = []
    A, B = pa.tolist(), pb.tolist()
    for i in range(len(A) - 1):
        for j in range(len(B) - 1):
            if _apart(A[i], A[i + 1], B[j], B[j + 1], tol):
                continue
            for ta, tb in _segment_crossing(A[i], A[i + 1], B[j], B[j + 1], tol):
                x = pa[i] + ta * (pa[i + 1] - pa[i])
                if all(np.linalg.norm(x - q[2]) > tol for q in out):
                    out.append((_arc(pa, i, ta), _arc(pb, j, tb), x))
    return out


def _rank_key(pts, h):
    """Order-independent rank of a fracture for the choice of the main one at
    an X or V: the longer one (to 1e-6 h), then the smaller end point."""
    length = float(np.linalg.norm(np.diff(pts, axis=0), axis=1).sum())
    ends = sorted([tuple(pts[0]), tuple(pts[-1])])
    return (-round(length / (1e-6 * h)), ends[0], ends[1])


def _pairs_near(polylines, margin):
    """Pairs (a, b), a < b, of polylines whose boxes grown by margin meet."""
    lo = np.array([p.min(axis=0) for p in polylines]) - margin
    hi = np.array([p.max(axis=0) for p in polylines]) + margin
    out = []
    for a in range(len(polylines) - 1):
        near = np.nonzero(
            np.all(lo[a + 1 :] <= hi[a], 1) & np.all(hi[a + 1 :] >= lo[a], 1)
        )[0]
        out += [(a, b) for b in (near + a + 1).tolist()]
    return out


@dataclass
class _Snapping:
    """State of rule 1 over a set of polylines (find_junctions)."""

    polylines: list  # (k, 2) arrays, moved in place
    free_ends: list  # [bool, bool] per polyline
    names: list
    rank: list
    neighbours: list  # polylines that may come within snap of each one
    snap: float  # [m]
    tol: float  # [m]
    min_segment: float  # [m]
    taken: list | None = None  # [bool, bool] per polyline: ends snapped
    near: set | None = None  # (polyline, end) within snap of another one

    def __post_init__(self):
        self.taken = [[False, False] for _ in self.polylines]
        self.near = set()


def find_junctions(polylines, free_ends, names, h, tol):
    """Junctions between clipped polylines; snaps ends in place (see above).

    polylines : list of (k, 2) arrays (modified in place when an end snaps);
    free_ends : list of [bool, bool], ends not on the domain boundary.
    Returns a list of (kind, main, secondary, point).
    """
    snap = JUNCTION_SNAP_CELLS * h
    if len(polylines) < 2:
        return []
    for a, b in _pairs_near(polylines, tol):  # as given, before any snapping
        _refuse_overlap(polylines[a], polylines[b], tol, (names[a], names[b]))
    rank = [_rank_key(p, h) for p in polylines]
    # ends move by at most snap: the boxes as given, grown by snap, meet for
    # every pair that may come near or meet after snapping
    pairs = _pairs_near(polylines, snap)
    neighbours = [[] for _ in polylines]
    for a, b in pairs:
        neighbours[a].append(b)
        neighbours[b].append(a)
    state = _Snapping(
        polylines,
        free_ends,
        names,
        rank,
        neighbours,
        snap,
        tol,
        JUNCTION_MIN_SEGMENT_CELLS * h,
    )
    for a, b in pairs:
        _snap_pair(state, a, b)
    apart = sum(not state.taken[f][end] for f, end in state.near)
    if apart:
        logger.info(
            "%d fracture end(s) within %.3g m (h/2) of another fracture left as "
            "tips: the snap would meet it at under %g deg, part a crossing or "
            "leave an end segment under h/10 (docs/networks.md)",
            apart,
            snap,
            JUNCTION_MIN_ANGLE,
        )
    out = []
    for a, b in pairs:
        pa, pb = polylines[a], polylines[b]
        for _, _, x in _crossings(pa, pb, tol, (names[a], names[b])):
            end_a, end_b = _end_at(pa, x, tol), _end_at(pb, x, tol)
            if end_a is not None and end_b is not None:
                main, sec = (a, b) if rank[a] <= rank[b] else (b, a)
                end = end_a if main == a else end_b
                out.append(("V", main, sec, _end_point(polylines[main], end)))
            elif end_a is not None:
                out.append(("T", b, a, _end_point(pa, end_a)))
            elif end_b is not None:
                out.append(("T", a, b, _end_point(pb, end_b)))
            else:
                main, sec = (a, b) if rank[a] <= rank[b] else (b, a)
                out.append(("X", main, sec, x.copy()))
    return out


def _end_point(pts, end):
    """A copy of the polyline's first (end 0) or last (end 1) point."""
    return (pts[0] if end == 0 else pts[-1]).copy()


def _end_at(pts, x, tol):
    """The end of the polyline at x (0 first, 1 last; within tol), or None."""
    for end in (0, 1):
        if np.linalg.norm(_end_point(pts, end) - x) <= tol:
            return end
    return None


def _move_end(pts, end, target):
    if end == 0:
        pts[0] = target
    else:
        pts[-1] = target


def _leaving(pts, x, tol):
    """Unit directions (m, 2) of the polyline's segments leaving the point x:
    both ways inside a segment, one way at an end; none if x is off it."""
    out = []
    for j in range(len(pts) - 1):
        d = pts[j + 1] - pts[j]
        length = float(np.linalg.norm(d))
        t = float(np.clip((x - pts[j]) @ d / length**2, 0.0, 1.0))
        if np.linalg.norm(pts[j] + t * d - x) > tol:
            continue
        if t * length > tol:
            out.append(-d / length)
        if (1.0 - t) * length > tol:
            out.append(d / length)
    return np.array(out).reshape(-1, 2)


def _may_move(state, f, end, target, turns):
    """Whether the end of polyline f may move to target (rule 1 above).

    The end segment after the move must keep min_segment of length and
    still meet every fracture it met before (snapping joins fractures, it
    never parts them); if the move turns it (turns = True), it must make at
    least JUNCTION_MIN_ANGLE with every segment of another fracture leaving
    the target, and lie along none of the others.
    """
    pf = state.polylines[f]
    inner = pf[1] if end == 0 else pf[-2]
    d = inner - target
    length = float(np.linalg.norm(d))
    if length < state.min_segment:
        return False
    old = (inner.tolist(), _end_point(pf, end).tolist())
    new = (inner.tolist(), target.tolist())
    cos_min = np.cos(np.radians(JUNCTION_MIN_ANGLE))
    for g in state.neighbours[f]:
        pg = state.polylines[g]
        pts = pg.tolist()
        segments = list(zip(pts[:-1], pts[1:], strict=True))
        if _meets(old, segments, state.tol) and not _meets(new, segments, state.tol):
            return False
        if not turns:  # along its own line: no new angle, no new overlap
            continue
        if np.any(_leaving(pg, target, state.tol) @ (d / length) >= cos_min):
            return False
        if any(
            _overlap(*new, a, b, state.tol) or _overlap(a, b, *new, state.tol)
            for a, b in segments
        ):
            return False
    return True


def _meets(segment, segments, tol):
    """Whether a segment meets (crosses or touches, within tol) any of the
    others ((2,) float sequences)."""
    return any(
        not _apart(*segment, a, b, tol) and _segment_crossing(*segment, a, b, tol)
        for a, b in segments
    )


def _snap_pair(state, a, b):
    """Snap the free ends of fractures a and b onto each other (rule 1)."""
    polylines, free_ends, taken, rank = (
        state.polylines,
        state.free_ends,
        state.taken,
        state.rank,
    )
    snap = state.snap
    pa, pb = polylines[a], polylines[b]
    cross = None  # crossings of a and b, found once an end is near the other
    for f, g, arc_k in ((a, b, 0), (b, a, 1)):
        pf, pg = polylines[f], polylines[g]
        lo, hi = pg.min(axis=0) - snap, pg.max(axis=0) + snap
        for end in (0, 1):
            if not free_ends[f][end] or taken[f][end]:
                continue
            p = _end_point(pf, end)
            if np.any(p < lo) or np.any(p > hi):
                continue
            dist, _, _, q = _closest_on_polyline(pg, p)
            if dist > snap:
                continue
            state.near.add((f, end))
            # the other's ends near p: a V, the secondary onto the main
            v_end = None
            for e2 in (0, 1):
                if (
                    free_ends[g][e2]
                    and not taken[g][e2]
                    and np.linalg.norm(_end_point(pg, e2) - p) <= snap
                ):
                    v_end = e2
            if v_end is not None:
                sec, main = (f, g) if rank[g] <= rank[f] else (g, f)
                sec_end = end if sec == f else v_end
                main_end = v_end if sec == f else end
                target = _end_point(polylines[main], main_end)
                if _may_move(state, sec, sec_end, target, turns=True):
                    _move_end(polylines[sec], sec_end, target)
                    taken[f][end] = taken[g][v_end] = True
                    cross = None
                    continue
            # an overshoot (a crossing on the end segment) is trimmed back to
            # the crossing if the stub is shorter than snap along the fracture,
            # else it is an X; a gap is closed at the nearest point
            if cross is None:
                cross = _crossings(pa, pb, state.tol, (state.names[a], state.names[b]))
            total = float(np.linalg.norm(np.diff(pf, axis=0), axis=1).sum())
            end_arc = 0.0 if end == 0 else total
            seg_len = np.linalg.norm(pf[1] - pf[0] if end == 0 else pf[-1] - pf[-2])
            over = [
                (abs(c[arc_k] - end_arc), k)
                for k, c in enumerate(cross)
                if abs(c[arc_k] - end_arc) <= seg_len
            ]
            target, turns = q, True
            if over:
                along, k = min(over)
                if along > snap:
                    continue
                target, turns = cross[k][2], False
            if _may_move(state, f, end, target, turns):
                _move_end(pf, end, target.copy())
                taken[f][end] = True
                cross = None


def _junction_cut(main, sec, point, direction, far, straight=0.0):
    """Cut of the secondary's arm lying in ``direction`` from the junction.

    The main's segment at the junction is the one the arm is furthest from
    tangent to (at a kink of the main the point lies on two).  ``straight``:
    the side to take when the arm continues the main's line (a V of two
    collinear fractures meeting end to end); 0 where that cannot be.
    """
    dist = _to_segments(main.points, np.asarray(point, float))[0]
    tol = GEOMETRY_TOL * float(main.length.min())
    near = np.flatnonzero(dist <= max(tol, float(dist.min())))
    j = int(near[np.argmax(np.abs(main.normal[near] @ direction))])
    nrm = main.normal[j]
    side = float(np.sign(direction @ nrm)) or straight
    if side == 0.0:
        raise GeometryError(
            f"fractures[{sec.index}] meets fractures[{main.index}] tangentially"
        )
    return Cut(point=np.asarray(point, float), normal=nrm, sign=side, far=far)


def _split_pieces(fr, s_values, tol):
    """Split the cell pieces of fr at the arc lengths s_values."""
    cells, segs, ts = (
        list(fr.piece_cell),
        list(fr.piece_seg),
        [tuple(t) for t in fr.piece_t],
    )
    for s in s_values:
        seg = int(
            np.clip(
                np.searchsorted(fr.s_start, s, side="right") - 1, 0, fr.length.size - 1
            )
        )
        t = (s - fr.s_start[seg]) / fr.length[seg]
        e = tol / fr.length[seg]
        for k in range(len(cells)):
            ta, tb = ts[k]
            if segs[k] == seg and ta + e < t < tb - e:
                cells.insert(k + 1, cells[k])
                segs.insert(k + 1, seg)
                ts[k] = (ta, t)
                ts.insert(k + 1, (t, tb))
                break
    return (
        np.array(cells, np.int64),
        np.array(segs, np.int64),
        np.array(ts, float).reshape(-1, 2),
    )


def build_fractures(mesh, specs, box: Box) -> tuple[Fracture, ...]:
    """All fractures of a case, with their junctions (X, T/Y, V), in the
    domain ``box``."""
    tol = GEOMETRY_TOL * mesh.h_min
    names = [f"fractures[{s.index}]" for s in specs]
    clipped, offsets, free = [], [], []
    for spec, key in zip(specs, names, strict=True):
        pts, s_off = clip_to_domain(np.asarray(spec.points, float), box, tol, key)
        pts = at_mesh_resolution(mesh, pts, key)
        clipped.append(pts.copy())
        offsets.append(s_off)
        free.append(
            [not on_boundary(pts[0], box, tol), not on_boundary(pts[-1], box, tol)]
        )
    _check_fractures_per_cell(mesh, clipped, names, tol)
    before = [p.copy() for p in clipped]
    found = find_junctions(clipped, free, names, mesh.h_min, tol)
    for f, (p0, p1) in enumerate(zip(before, clipped, strict=True)):
        # an end moved along the first segment shifts the arc-length origin
        t0 = (p0[1] - p0[0]) / np.linalg.norm(p0[1] - p0[0])
        offsets[f] += float((p1[0] - p0[0]) @ t0)
        if np.any(np.linalg.norm(np.diff(p1, axis=0), axis=1) <= tol):
            raise GeometryError(
                f"{names[f]}: a segment vanishes where the fracture is snapped onto "
                "a junction; move its end point"
            )
    junction_ends: list[set[int]] = [set() for _ in specs]
    # junction arc lengths (polyline own, from pts[0])
    arcs: list[list[float]] = [[] for _ in specs]
    for kind, main, sec, point in found:
        if kind in ("T", "V"):
            pts = clipped[sec]
            junction_ends[sec].add(0 if np.allclose(pts[0], point, atol=tol) else 1)
        for f in (main, sec):
            _, j, t, _ = _closest_on_polyline(clipped[f], point)
            arcs[f].append(_arc(clipped[f], j, t))
    reach = []
    for f, pts in enumerate(clipped):
        total = float(np.linalg.norm(np.diff(pts, axis=0), axis=1).sum())
        inner = [s for s in arcs[f] if tol < s < total - tol]
        reach.append(
            {0: min(inner, default=np.inf), 1: total - max(inner, default=-np.inf)}
        )
    fracs = [
        build_fracture(
            mesh, spec, box, clipped[f], offsets[f], tuple(junction_ends[f]), reach[f]
        )
        for f, spec in enumerate(specs)
    ]
    # arms and cuts (Daux et al. 2000): the secondary of an X is cut into two
    # arms, each ending on the main; a T / V secondary's end arm is cut too
    # per fracture: (arc length, main fracture, point, tangent) of its X splits
    splits: list[list[tuple]] = [[] for _ in specs]
    end_cuts: list[dict[int, Cut]] = [{} for _ in specs]
    for kind, main, sec, point in found:
        fm, fs = fracs[main], fracs[sec]
        _, j, t, _ = _closest_on_polyline(fs.points, point)
        s_sec = float(fs.s_start[j] + t * fs.length[j])
        if kind == "X":
            splits[sec].append((s_sec, main, point, fs.tangent[j]))
            continue
        end = 0 if np.allclose(fs.points[0], point, atol=tol) else 1
        inward = fs.tangent[0] if end == 0 else -fs.tangent[-1]
        far = 0.0
        if kind == "V":
            # J is the indicator of the wedge between the two: outer value
            # beyond the main's line (where the main does not continue)
            mend = 0 if np.allclose(fm.points[0], point, atol=tol) else 1
            body = fm.tangent[0] if mend == 0 else -fm.tangent[-1]
            nrm_s = fs.normal[0] if end == 0 else fs.normal[-1]
            far = -float(np.sign(body @ nrm_s)) or -1.0
            # end to end on one line, the wedge is the half-plane on which
            # H of the secondary is -far (J then jumps along both)
            nrm_m = fm.normal[0] if mend == 0 else fm.normal[-1]
            straight = -far * float(np.sign(nrm_m @ nrm_s))
            end_cuts[sec][end] = _junction_cut(fm, fs, point, inward, far, straight)
            continue
        end_cuts[sec][end] = _junction_cut(fm, fs, point, inward, far)
    out = []
    for f, fr in enumerate(fracs):
        sp = sorted(splits[f], key=lambda r: r[0])
        arms: list[list[Cut]] = [[] for _ in range(len(sp) + 1)]
        for k, (_, main, point, tan) in enumerate(sp):
            arms[k].append(_junction_cut(fracs[main], fr, point, -tan, 0.0))
            arms[k + 1].append(_junction_cut(fracs[main], fr, point, tan, 0.0))
        if 0 in end_cuts[f]:
            arms[0].append(end_cuts[f][0])
        if 1 in end_cuts[f]:
            arms[-1].append(end_cuts[f][1])
        s_all = sorted(offsets[f] + s for s in arcs[f])
        cell, seg, tt = _split_pieces(fr, s_all, tol)
        out.append(
            replace(
                fr,
                piece_cell=cell,
                piece_seg=seg,
                piece_t=tt,
                arm_splits=tuple(r[0] for r in sp),
                arms=tuple(tuple(a) for a in arms),
                junction_s=tuple(s_all),
            )
        )
    if found:
        kinds = [k for k, *_ in found]
        logger.info(
            "junctions: %d X, %d T, %d V",
            kinds.count("X"),
            kinds.count("T"),
            kinds.count("V"),
        )
    return tuple(out)
