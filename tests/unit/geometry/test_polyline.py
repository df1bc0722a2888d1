"""xfemslip.geometry.polyline: the segment-pair sweep against an all-pairs reference,
and the simplification below a mesh's resolution against its stated bounds."""

from __future__ import annotations

import math

import numpy as np
import pytest

from xfemslip.geometry.polyline import first_meeting, simplify
from xfemslip.geometry.regions import in_polygon, polygon_problem


def _cross(o, a, b) -> float:
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])


def _on(a, b, c) -> bool:
    return (
        _cross(a, b, c) == 0
        and min(a[0], b[0]) <= c[0] <= max(a[0], b[0])
        and min(a[1], b[1]) <= c[1] <= max(a[1], b[1])
    )


def _meet(p, q, r, s) -> bool:
    """Closed segments p-q and r-s share a point (scalar reference)."""
    d1, d2, d3, d4 = _cross(r, s, p), _cross(r, s, q), _cross(p, q, r), _cross(p, q, s)
    if d1 * d2 < 0 and d3 * d4 < 0:
        return True
    return _on(r, s, p) or _on(r, s, q) or _on(p, q, r) or _on(p, q, s)


def _all_pairs(pts, closed):
    """First (i, j) of the all-pairs double loop, the definition of a meeting."""
    n = len(pts) if closed else len(pts) - 1
    seg = [(pts[i], pts[(i + 1) % len(pts)]) for i in range(n)]
    for i in range(n):
        for j in range(i + 1, n):
            if j == i + 1 or (closed and i == 0 and j == n - 1):
                if closed:
                    continue
                a, b, c = seg[i][0], seg[i][1], seg[j][1]
                back = np.dot(b - a, c - b) < 0
                if _cross(a, b, c) == 0 and back:
                    return i, j
                continue
            if _meet(*seg[i], *seg[j]):
                return i, j
    return None


@pytest.mark.parametrize("closed", [False, True])
def test_first_meeting_matches_all_pairs(closed):
    """Random polylines on an integer grid (collinear and touching cases) and
    in the plane: the sweep finds exactly the pair the double loop finds."""
    rng = np.random.default_rng(7)
    found = 0
    for trial in range(600):
        k = int(rng.integers(3, 14))
        pts = rng.integers(0, 5, (k, 2)).astype(float)
        if trial % 2:
            pts = rng.random((k, 2))
        ring = np.vstack([pts, pts[:1]]) if closed else pts
        if np.any(np.all(np.diff(ring, axis=0) == 0.0, axis=1)):
            continue
        want = _all_pairs(pts, closed)
        found += want is not None
        assert first_meeting(pts, closed=closed) == want, pts.tolist()
    assert found > 50  # the sample holds meetings, not only clean polylines


def test_first_meeting_on_thousands_of_segments():
    """A 20,000-point spiral (1,000 points a turn) does not meet itself; with
    vertex 15,000 pulled just inside segment 5,000, its two segments cross
    every turn out to there, and the smallest pair is (5000, 14999)."""
    t = np.linspace(0.0, 40.0 * np.pi, 20_000)
    pts = np.column_stack([(1.0 + t) * np.cos(t), (1.0 + t) * np.sin(t)])
    assert first_meeting(pts) is None
    bad = pts.copy()
    bad[15_000] = 0.99 * 0.5 * (pts[5_000] + pts[5_001])
    assert first_meeting(bad) == (5_000, 14_999)


def test_polygon_problem_names_the_crossing_edges_of_a_large_polygon():
    n = 5_000
    a = 2.0 * np.pi * np.arange(n) / n
    ring = np.column_stack([np.cos(a), np.sin(a)])
    assert polygon_problem(ring) is None
    bad = ring.copy()
    bad[2_500] = [1.5, 0.0]  # a spike from the far side across edge 0
    why = polygon_problem(bad)
    assert why.startswith("is not simple: edges 0 and 2499")


def test_in_polygon_matches_point_by_edge_even_odd():
    """The edge-by-band classification against the all-pairs even-odd rule,
    degenerate points (on vertices and edges of a grid polygon) included."""
    rng = np.random.default_rng(3)
    for trial in range(200):
        k = int(rng.integers(3, 25))
        P = (
            rng.integers(0, 6, (k, 2)).astype(float)
            if trial % 2
            else rng.random((k, 2))
        )
        xy = rng.integers(0, 6, (300, 2)).astype(float)
        if trial % 3 == 0:
            xy = rng.random((300, 2))
        Q = np.roll(P, -1, axis=0)
        x, y = xy[:, :1], xy[:, 1:]
        straddle = (P[:, 1] > y) != (Q[:, 1] > y)
        with np.errstate(divide="ignore", invalid="ignore"):
            xc = P[:, 0] + (y - P[:, 1]) * (Q[:, 0] - P[:, 0]) / (Q[:, 1] - P[:, 1])
        want = np.count_nonzero(straddle & (x < xc), axis=1) % 2 == 1
        np.testing.assert_array_equal(in_polygon(xy, P), want)


def test_in_polygon_area_of_a_many_sided_circle():
    """The fraction of a 400 x 400 grid of cell centres inside a 5,000-gon
    of radius 0.35 is its area pi 0.35^2 to the grid's resolution."""
    n = 5_000
    a = 2.0 * np.pi * np.arange(n) / n
    ring = np.column_stack([0.5 + 0.35 * np.cos(a), 0.5 + 0.35 * np.sin(a)])
    c = (np.arange(400) + 0.5) / 400
    X, Y = np.meshgrid(c, c)
    inside = in_polygon(np.column_stack([X.ravel(), Y.ravel()]), ring)
    # the boundary cells: perimeter / h cells of area h^2 at most misjudged
    assert abs(inside.mean() - math.pi * 0.35**2) < 2 * math.pi * 0.35 / 400


# --------------------------------------------------------------------------- #
# simplify
# --------------------------------------------------------------------------- #


def _distance_to_polyline(p, line):
    a, b = line[:-1], line[1:]
    d = b - a
    t = np.clip(np.einsum("nmk,mk->nm", p[:, None] - a, d) / (d * d).sum(1), 0, 1)
    q = a + t[..., None] * d
    return np.linalg.norm(p[:, None] - q, axis=2).min(axis=1)


def test_resolvable_polyline_is_kept_whole():
    pts = np.array([[0.0, 0.0], [0.3, 0.1], [0.6, 0.0], [0.61, 0.26]])
    kept = simplify(pts, np.full(4, 0.1), 0.25, 0.05)
    np.testing.assert_array_equal(kept, np.arange(4))


def test_zigzag_inside_one_cell():
    """1,000 points zigzagging 0.2 h across a line inside one cell of size
    h = 0.05: every segment at least h/4, so each advances at least
    sqrt((h/4)^2 - (0.2 h)^2) along x over the 0.046 m; the end points kept;
    every dropped vertex within h/4 of the result."""
    h, n = 0.05, 1000
    x = 0.452 + 0.046 * np.arange(n) / (n - 1)
    pts = np.column_stack([x, np.where(np.arange(n) % 2 == 0, 0.47, 0.48)])
    kept = simplify(pts, np.full(n, h), 0.25, 0.05)
    out = pts[kept]
    assert kept[0] == 0 and kept[-1] == n - 1
    assert np.all(np.linalg.norm(np.diff(out, axis=0), axis=1) >= 0.25 * h)
    assert 2 <= len(out) <= 0.046 / math.sqrt((0.25 * h) ** 2 - (0.2 * h) ** 2) + 1
    assert _distance_to_polyline(pts, out).max() <= 0.25 * h


def test_digitised_arc_follows_the_chord_rule():
    """A 2,000-point arc of radius R = 0.5 on cells h = 0.02: the kept
    vertices are vertices of the arc, and their number lies between the
    chord count whose sagitta is h/20 (Douglas-Peucker cannot do with
    fewer) and the arc length over h/4 (the thinning bound)."""
    R, h, n = 0.5, 0.02, 2000
    ang = np.radians(135.0 - 90.0 * np.arange(n) / (n - 1))
    pts = np.column_stack([0.5 + R * np.cos(ang), 0.1 + R * np.sin(ang)])
    out = pts[simplify(pts, np.full(n, h), 0.25, 0.05)]
    segments = len(out) - 1
    chord_angle = 2.0 * math.acos(1.0 - 0.05 * h / R)  # sagitta = h/20
    assert math.ceil(math.radians(90.0) / chord_angle) <= segments
    assert segments <= R * math.radians(90.0) / (0.25 * h) + 1
    assert _distance_to_polyline(pts, out).max() <= 0.05 * h + 1e-12


def test_kink_with_long_arms_is_kept():
    """Two arms of 1,000 collinear points meeting at 60 degrees: exactly the
    two ends and the kink are left."""
    s = np.linspace(0.0, 1.0, 1000)
    arm1 = np.column_stack([s, 0.0 * s])
    arm2 = np.column_stack([1.0 + 0.5 * s[1:], math.sqrt(3) / 2 * s[1:]])
    pts = np.vstack([arm1, arm2])
    out = pts[simplify(pts, np.full(len(pts), 0.1), 0.25, 0.05)]
    np.testing.assert_array_equal(out, [[0.0, 0.0], [1.0, 0.0], pts[-1]])


def test_local_cell_size_sets_the_resolution():
    """The same wavy line over a graded mesh keeps its waves where the cells
    are small (h = 0.002) and loses them where they are large (h = 0.1)."""
    x = np.linspace(0.0, 1.0, 2001)
    pts = np.column_stack([x, 0.5 + 0.004 * np.sin(2 * np.pi * x / 0.05)])
    h = np.where(x < 0.5, 0.002, 0.1)
    out = pts[simplify(pts, h, 0.25, 0.05)]
    fine, coarse = out[out[:, 0] < 0.5], out[out[:, 0] > 0.5]
    assert len(fine) >= 4 * 10  # 10 waves, at least 4 vertices each
    assert len(coarse) <= 0.5 / (0.25 * 0.1) + 1
    assert np.abs(coarse[:, 1] - 0.5).max() <= 0.004
