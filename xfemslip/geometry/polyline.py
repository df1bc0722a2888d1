"""Polyline and polygon tools whose cost follows the geometry, not the number
of vertices (pure NumPy).

- ``simplify``: the vertices of a polyline that a mesh of cell size h can
  resolve (the rule is in docs/method.md, *Fracture geometry*: geometry below the
  mesh resolution);
- ``first_meeting``: the first pair of segments of a polyline or polygon that
  touch, cross or fold back, from a sweep over the segments' bounding boxes
  (candidate pairs are only those whose boxes overlap, tested in vectorised
  chunks), instead of all pairs in a Python loop.
"""

from __future__ import annotations

import numpy as np

# Candidate segment pairs tested at once by first_meeting: bounds the memory
# of a chunk (about 200 bytes per pair) whatever the number of segments.
PAIR_CHUNK = 1 << 18


def _orientation(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Sign of the cross product (b - a) x (c - a); arrays (..., 2)."""
    ab, ac = b - a, c - a
    return np.sign(ab[..., 0] * ac[..., 1] - ab[..., 1] * ac[..., 0])


def _in_box(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Whether c lies in the bounding box of segment a-b; arrays (..., 2)."""
    return np.all((np.minimum(a, b) <= c) & (c <= np.maximum(a, b)), axis=-1)


def _pairs_meet(p, q, r, s) -> np.ndarray:
    """(m,) bool: closed segments p-q and r-s (arrays (m, 2)) share a point."""
    o1, o2 = _orientation(p, q, r), _orientation(p, q, s)
    o3, o4 = _orientation(r, s, p), _orientation(r, s, q)
    return (
        ((o1 * o2) < 0) & ((o3 * o4) < 0)
        | (o1 == 0) & _in_box(p, q, r)
        | (o2 == 0) & _in_box(p, q, s)
        | (o3 == 0) & _in_box(r, s, p)
        | (o4 == 0) & _in_box(r, s, q)
    )


def _folds_back(a, b, c) -> np.ndarray:
    """(m,) bool: the path a -> b -> c turns back on itself along one line."""
    turn = np.einsum("mk,mk->m", b - a, c - b)
    return (_orientation(a, b, c) == 0) & (turn < 0.0)


def _overlap_pairs(lo: np.ndarray, hi: np.ndarray):
    """Chunks (i, j) of segment pairs whose closed bounding boxes overlap.

    lo, hi : (n, 2) box corners.  A sweep along the axis that gives fewer
    candidates: with the segments sorted by their low end on that axis, the
    partners of segment p are those that start before p ends; the pairs are
    then filtered on the other axis.  Every overlapping pair is produced once.
    """
    n = lo.shape[0]
    best: tuple[int, np.ndarray, np.ndarray] | None = None
    for axis in (0, 1):
        order = np.argsort(lo[:, axis], kind="stable")
        start = lo[order, axis]
        end = np.searchsorted(start, hi[order, axis], side="right")
        count = np.maximum(end - np.arange(n) - 1, 0)
        if best is None or count.sum() < best[2].sum():
            best = (axis, order, count)
    assert best is not None
    axis, order, count = best
    other = 1 - axis
    first = 0
    while first < n:
        stop = first + max(
            1, int(np.searchsorted(np.cumsum(count[first:]), PAIR_CHUNK, "right"))
        )
        block = count[first:stop]
        rows = np.repeat(np.arange(first, stop), block)
        offsets = np.arange(rows.size) - np.repeat(np.cumsum(block) - block, block)
        i, j = order[rows], order[rows + 1 + offsets]
        keep = (lo[j, other] <= hi[i, other]) & (lo[i, other] <= hi[j, other])
        i, j = i[keep], j[keep]
        yield np.minimum(i, j), np.maximum(i, j)
        first = stop


@np.errstate(over="ignore", invalid="ignore")
def first_meeting(points: np.ndarray, closed: bool = False) -> tuple[int, int] | None:
    """The smallest pair (i, j), i < j, of segments that touch, cross or fold
    back, or None.

    points : (k, 2) vertices [m]; segment i joins vertex i to i + 1 (and, when
    ``closed``, the last vertex to the first).  Neighbouring segments share a
    vertex: on an open polyline they count only when the path turns back along
    one line; on a closed polygon they do not count.  The work follows the
    number of segment pairs whose bounding boxes overlap (_overlap_pairs).
    """
    pts = np.asarray(points, float)
    a = pts
    b = np.roll(pts, -1, axis=0) if closed else pts[1:]
    a = a[: b.shape[0]]
    n = a.shape[0]
    if n < 2:
        return None
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    best = None
    for i, j in _overlap_pairs(lo, hi):
        neighbours = j == i + 1
        if closed:
            neighbours |= (i == 0) & (j == n - 1)
            hit = ~neighbours & _pairs_meet(a[i], b[i], a[j], b[j])
        else:
            hit = np.where(
                neighbours,
                _folds_back(a[i], b[i], b[j]),
                _pairs_meet(a[i], b[i], a[j], b[j]),
            )
        if hit.any():
            k = np.lexsort((j[hit], i[hit]))[0]
            pair = int(i[hit][k]), int(j[hit][k])
            best = pair if best is None else min(best, pair)
    return best


def _chord_distance(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(m,) distance [m] of points (m, 2) from the segment a-b."""
    d = b - a
    dd = float(d @ d)
    rel = points - a
    t = np.clip(rel @ d / dd, 0.0, 1.0) if dd > 0.0 else np.zeros(len(points))
    return np.linalg.norm(rel - t[:, None] * d, axis=1)


def _douglas_peucker(
    points: np.ndarray, deviation: np.ndarray, min_segment: np.ndarray
) -> np.ndarray:
    """Douglas-Peucker with a shortest segment: (k,) bool, the vertices kept.

    A run of vertices between two kept ones is split at the vertex farthest
    beyond its ``deviation`` from their chord, among the vertices at least
    their ``min_segment`` from both ends; when there is none, the run is
    dropped.  So every new segment is at least min_segment long, and every
    dropped vertex lies within its deviation of the result, or within its
    min_segment of a kept vertex.  Each run costs its length: the work is
    at most (vertices) x (vertices kept).
    """
    keep = np.zeros(len(points), bool)
    keep[[0, -1]] = True
    stack = [(0, len(points) - 1)]
    while stack:
        i, j = stack.pop()
        if j - i < 2:
            continue
        inner = points[i + 1 : j]
        excess = _chord_distance(inner, points[i], points[j]) - deviation[i + 1 : j]
        room = min_segment[i + 1 : j]
        apart = (np.linalg.norm(inner - points[i], axis=1) >= room) & (
            np.linalg.norm(inner - points[j], axis=1) >= room
        )
        excess[~apart] = -np.inf
        k = int(np.argmax(excess))
        if excess[k] > 0.0:
            keep[i + 1 + k] = True
            stack += [(i, i + 1 + k), (i + 1 + k, j)]
    return keep


def simplify(
    points: np.ndarray, cell_size: np.ndarray, min_segment: float, deviation: float
) -> np.ndarray:
    """Indices of the vertices of a polyline kept at a mesh's resolution.

    points : (k, 2) [m]; cell_size : (k,) local cell size h at each vertex [m];
    min_segment, deviation : fractions of h.  Nothing is dropped unless a
    segment is shorter than min_segment * h (of either end); then
    Douglas-Peucker with that shortest segment (_douglas_peucker) keeps the
    vertices more than deviation * h off the simplified line that are at
    least min_segment * h from their neighbours in it.  The end points are
    always kept.
    """
    # Not a library's simplification: the tolerance here varies along the
    # line with the local cell size, and the shortest segment is a
    # constraint; matplotlib's Path simplification works to one tolerance in
    # display pixels for drawing, and shapely (which has Douglas-Peucker
    # with one tolerance) is not a dependency.
    pts = np.asarray(points, float)
    h = np.asarray(cell_size, float)
    lengths = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    if len(pts) <= 2 or np.all(lengths >= min_segment * np.maximum(h[:-1], h[1:])):
        return np.arange(len(pts))
    return np.flatnonzero(_douglas_peucker(pts, deviation * h, min_segment * h))
