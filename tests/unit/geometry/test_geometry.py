"""Tests of xfemslip.geometry.fracture: level-set signs, tips, clipping, cell
pieces, ramp.

Every expected number is computed by hand in the test (distances, clipping
parameters, arc lengths) or checked by central finite differences.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.support.casegen import fracture_spec
from xfemslip.errors import GeometryError
from xfemslip.fem.mesh import build_mesh
from xfemslip.geometry.fracture import build_fracture, clip_segment
from xfemslip.geometry.junctions import build_fractures

# 8 x 8 cells on the unit square: h = 0.125 and every node coordinate is exact
# in binary, so fractures "on a node" or "on an edge" are exactly there.
N_CELLS = 8
BOX = np.array([0.0, 1.0, 0.0, 1.0])


def _mesh(n: int = N_CELLS):
    grid = np.linspace(0.0, 1.0, n + 1)
    return build_mesh(grid, grid)


_spec = fracture_spec


def _fracture(points, tip: str = "ramp"):
    mesh = _mesh()
    return mesh, build_fracture(mesh, _spec(points, tip=tip), BOX)


def _pieces_length(fr) -> float:
    return float(
        np.sum((fr.piece_t[:, 1] - fr.piece_t[:, 0]) * fr.length[fr.piece_seg])
    )


# ----------------------------------------------------------------- level-set signs

# the generic fracture of the brief: t = (2, 1)/sqrt(5), n = (-1, 2)/sqrt(5)
A, B = np.array([0.2, 0.3]), np.array([0.8, 0.6])
SQ5 = math.sqrt(5.0)


def test_tangent_and_normal_of_a_segment():
    _, fr = _fracture([A, B])
    np.testing.assert_allclose(
        fr.tangent[0], [2.0 / SQ5, 1.0 / SQ5], rtol=0, atol=1e-15
    )
    # n is t rotated by +90 degrees (counter-clockwise)
    np.testing.assert_allclose(
        fr.normal[0], [-1.0 / SQ5, 2.0 / SQ5], rtol=0, atol=1e-15
    )
    assert fr.length[0] == pytest.approx(0.3 * SQ5, rel=1e-15)


def test_signed_distance_on_both_sides_by_hand():
    _, fr = _fracture([A, B])
    # (0.4, 0.6): (x - A) . n = (-0.2 + 0.6) / sqrt(5); its foot lies inside
    # the segment (parameter 0.7 / 1.5), so phi is that perpendicular distance.
    # (0.6, 0.3): (x - A) . n = (-0.4 + 0.0) / sqrt(5) < 0 (parameter 1.2/1.5).
    pts = np.array([[0.4, 0.6], [0.6, 0.3]])
    phi = fr.signed_distance(pts)
    np.testing.assert_allclose(phi, [0.4 / SQ5, -0.4 / SQ5], rtol=1e-14)
    # points offset along +-n from the segment's midpoint
    mid = 0.5 * (A + B)
    n = np.array([-1.0, 2.0]) / SQ5
    phi = fr.signed_distance(np.array([mid + 0.1 * n, mid - 0.05 * n, mid + 0.3 * n]))
    np.testing.assert_allclose(phi, [0.1, -0.05, 0.3], rtol=1e-12)


def test_signed_distance_beyond_the_ends_is_the_distance_to_the_end_point():
    _, fr = _fracture([A, B])
    # beyond B: (0.9, 0.5) projects at parameter 0.48 / 0.45 > 1; (x - B) = (0.1, -0.1)
    # has (x - B) . n = -0.3/sqrt(5) < 0, so phi = -|x - B| = -sqrt(0.02)
    # before A: (0.1, 0.35) projects at parameter -0.15/0.45 < 0;
    # (x - A) = (-0.1, 0.05),
    # (x - A) . n = 0.2/sqrt(5) > 0, so phi = +|x - A| = sqrt(0.0125)
    phi = fr.signed_distance(np.array([[0.9, 0.5], [0.1, 0.35]]))
    np.testing.assert_allclose(phi, [-math.sqrt(0.02), math.sqrt(0.0125)], rtol=1e-13)


def test_reversing_the_polyline_flips_the_sign():
    _, fwd = _fracture([A, B])
    _, rev = _fracture([B, A])
    pts = np.random.default_rng(1).random((50, 2))
    np.testing.assert_allclose(
        rev.signed_distance(pts), -fwd.signed_distance(pts), rtol=0, atol=1e-15
    )


def _sector_sign(theta_deg, lo, hi):
    """+1 if the angle lies strictly in the counter-clockwise sector (lo, hi)."""
    t = (theta_deg - lo) % 360.0
    return 1.0 if 0.0 < t < (hi - lo) % 360.0 else -1.0


@pytest.mark.parametrize(
    "points, back_deg, fwd_deg",
    [
        # kink turning left: + side is the 135-degree sector from 45 to 180
        ([[0.1, 0.5], [0.5, 0.5], [0.9, 0.9]], 180.0, 45.0),
        # kink turning right: + side is the 225-degree (reflex) sector from -45 to 180
        ([[0.1, 0.5], [0.5, 0.5], [0.9, 0.1]], 180.0, -45.0),
    ],
)
def test_kink_pseudo_normal_gives_consistent_signs(points, back_deg, fwd_deg):
    """Around a kink the + side (where n points) is the sector swept
    counter-clockwise from the outgoing to the incoming segment."""
    _, fr = _fracture(points)
    kink = np.array(points[1])
    for r in (1e-3, 0.02, 0.1):
        theta = np.arange(0.0, 360.0, 2.5)
        # keep away from the two fracture rays themselves
        ok = [
            min(abs((t - a + 180.0) % 360.0 - 180.0) for a in (back_deg, fwd_deg)) > 1.0
            for t in theta
        ]
        theta = theta[np.array(ok)]
        pts = kink + r * np.column_stack(
            [np.cos(np.radians(theta)), np.sin(np.radians(theta))]
        )
        phi = fr.signed_distance(pts)
        expected = np.array([_sector_sign(t, fwd_deg, back_deg) for t in theta])
        np.testing.assert_array_equal(np.sign(phi), expected)
        # |phi| is the distance to the polyline (brute force on a fine sampling)
        s = np.linspace(0.0, 1.0, 4001)[:, None]
        p = np.asarray(points, float)
        samples = np.concatenate([p[0] + s * (p[1] - p[0]), p[1] + s * (p[2] - p[1])])
        brute = np.min(np.linalg.norm(pts[:, None, :] - samples[None], axis=2), axis=1)
        np.testing.assert_allclose(np.abs(phi), brute, rtol=0, atol=1e-4)


def test_side_is_plus_one_on_the_fracture_itself():
    # fractures whose arithmetic is exact in binary (axis-aligned, or a 3-4-5
    # direction with a dyadic length), so phi = 0 exactly on them
    _, fr = _fracture([[0.25, 0.25], [0.75, 0.625]])  # d = (0.5, 0.375), |d| = 0.625
    on = np.array([[0.25, 0.25], [0.75, 0.625], [0.5, 0.4375], [0.375, 0.34375]])
    np.testing.assert_array_equal(fr.signed_distance(on), 0.0)
    np.testing.assert_array_equal(fr.side(on), 1.0)
    _, flat = _fracture([[0.2, 0.5], [0.8, 0.5]])
    on = np.column_stack([np.linspace(0.2, 0.8, 7), np.full(7, 0.5)])
    np.testing.assert_array_equal(flat.side(on), 1.0)
    np.testing.assert_array_equal(
        flat.side([[0.5, 0.5 + 1e-12], [0.5, 0.5 - 1e-12]]), [1.0, -1.0]
    )


def test_side_is_plus_one_at_the_vertices_of_a_generic_fracture():
    _, fr = _fracture([[0.2, 0.3], [0.4, 0.4]])
    np.testing.assert_array_equal(fr.side(np.array([[0.2, 0.3], [0.4, 0.4]])), 1.0)


# -------------------------------------------------------------------------- tips


def test_interior_fracture_has_two_tips_pointing_outwards():
    _, fr = _fracture([A, B])
    assert len(fr.tips) == 2
    t = np.array([2.0, 1.0]) / SQ5
    first, last = sorted(fr.tips, key=lambda tp: tp.end)
    np.testing.assert_array_equal(first.point, A)
    np.testing.assert_array_equal(last.point, B)
    np.testing.assert_allclose(first.direction, -t, atol=1e-15)
    np.testing.assert_allclose(last.direction, t, atol=1e-15)
    assert (first.sign, last.sign) == (-1.0, 1.0)
    # the tip cell of B is [0.75, 0.875] x [0.5, 0.625]; the fracture enters it at
    # x = 0.75 (parameter 0.55/0.6), so the ramp length is (1 - 0.55/0.6) * |AB|
    assert last.ramp_length == pytest.approx((0.05 / 0.6) * 0.3 * SQ5, rel=1e-12)
    assert last.cell_size == 0.125


def test_fracture_reaching_one_edge_has_one_tip():
    _, fr = _fracture([[0.0, 0.3], [0.6, 0.6]])
    assert len(fr.tips) == 1
    assert fr.tips[0].end == 1
    np.testing.assert_array_equal(fr.tips[0].point, [0.6, 0.6])
    _, fr = _fracture([[0.4, 0.3], [0.7, 1.0]])
    assert [tp.end for tp in fr.tips] == [0]


def test_crossing_fracture_has_no_tip():
    _, fr = _fracture([[0.0, 0.3], [1.0, 0.6]])
    assert fr.tips == ()
    _, fr = _fracture([[-0.5, 0.2], [1.5, 0.7]])  # both ends outside: clipped to edges
    assert fr.tips == ()


def test_partly_outside_fracture_is_clipped_and_keeps_its_arc_length():
    # segment (-0.2, 0.2) -> (0.6, 0.6) leaves the domain at x = 0: y = 0.3,
    # which is at arc length |(0.2, 0.1)| = sqrt(0.05) from the first point
    _, fr = _fracture([[-0.2, 0.2], [0.6, 0.6]])
    np.testing.assert_allclose(fr.points, [[0.0, 0.3], [0.6, 0.6]], atol=1e-15)
    np.testing.assert_allclose(fr.s_start, [math.sqrt(0.05)], rtol=1e-14)
    assert len(fr.tips) == 1
    # polyline whose first segment lies entirely outside: s_start counts it
    _, fr = _fracture([[-0.4, 0.1], [-0.2, 0.2], [0.6, 0.6]])
    np.testing.assert_allclose(fr.points, [[0.0, 0.3], [0.6, 0.6]], atol=1e-15)
    np.testing.assert_allclose(fr.s_start, [2.0 * math.sqrt(0.05)], rtol=1e-14)
    # polyline clipped inside its first segment, second segment kept whole
    _, fr = _fracture([[-0.2, 0.2], [0.2, 0.4], [0.6, 0.4]])
    np.testing.assert_allclose(
        fr.points, [[0.0, 0.3], [0.2, 0.4], [0.6, 0.4]], atol=1e-15
    )
    np.testing.assert_allclose(
        fr.s_start, [math.sqrt(0.05), 2.0 * math.sqrt(0.05)], rtol=1e-14
    )
    np.testing.assert_allclose(fr.length, [math.sqrt(0.05), 0.4], rtol=1e-14)
    # arc_length continues along the clipped polyline
    np.testing.assert_allclose(
        fr.arc_length(np.array([1]), np.array([0.5])),
        [2.0 * math.sqrt(0.05) + 0.2],
        rtol=1e-14,
    )


def test_fracture_outside_the_domain_raises():
    with pytest.raises(GeometryError, match=r"fractures\[0\]"):
        _fracture([[1.2, 0.2], [1.6, 0.7]])


@pytest.mark.parametrize(
    "points",
    [
        pytest.param([[0.0, 0.0], [0.0, 2.3e-27]], id="corner-sliver"),  # fuzz find
        pytest.param([[0.4, 0.4], [0.4 + 1e-12, 0.4]], id="interior"),
        pytest.param([[-0.5, 1.0], [1e-13, 1.0]], id="clipped-to-a-point"),
    ],
)
def test_fracture_below_the_tolerance_raises(points):
    """Nonzero but below the geometric tolerance (the case reader refuses
    only exact zero): a GeometryError naming the fracture, not an IndexError."""
    with pytest.raises(GeometryError, match=r"fractures\[0\].*shorter than"):
        _fracture(points)


# ------------------------------------------------------------------------ pieces


@pytest.mark.parametrize(
    "points",
    [
        pytest.param([[0.2, 0.3], [0.8, 0.6]], id="generic"),
        pytest.param([[0.2, 0.5], [0.8, 0.5]], id="along-horizontal-grid-line"),
        pytest.param([[0.5, 0.2], [0.5, 0.8]], id="along-vertical-grid-line"),
        pytest.param([[0.0, 0.5], [1.0, 0.5]], id="crossing-along-grid-line"),
        pytest.param([[0.125, 0.125], [0.875, 0.875]], id="diagonal-tips-on-nodes"),
        pytest.param([[0.0, 0.0], [1.0, 1.0]], id="diagonal-corner-to-corner"),
        pytest.param([[0.25, 0.3], [0.8, 0.625]], id="tips-on-edges"),
        pytest.param([[0.1, 0.5], [0.5, 0.5], [0.9, 0.9]], id="kinked"),
        pytest.param([[0.125, 0.25], [0.5, 0.5], [0.875, 0.25]], id="kink-on-node"),
        pytest.param([[-0.2, 0.2], [0.2, 0.4], [0.6, 0.4]], id="clipped"),
    ],
)
def test_piece_lengths_sum_to_the_fracture_length(points):
    mesh, fr = _fracture(points)
    assert _pieces_length(fr) == pytest.approx(float(fr.length.sum()), rel=1e-12)
    # every piece lies in its cell (its midpoint, with a round-off margin)
    p0 = fr.points[fr.piece_seg]
    d = fr.points[fr.piece_seg + 1] - p0
    mid = p0 + fr.piece_t.mean(axis=1)[:, None] * d
    b = mesh.bounds[fr.piece_cell]
    eps = 1e-12
    assert np.all(
        (mid[:, 0] >= b[:, 0] - eps)
        & (mid[:, 0] <= b[:, 1] + eps)
        & (mid[:, 1] >= b[:, 2] - eps)
        & (mid[:, 1] <= b[:, 3] + eps)
    )
    # pieces do not overlap: along each segment they tile [t_first, t_last]
    for k in range(fr.length.size):
        t = fr.piece_t[fr.piece_seg == k]
        t = t[np.argsort(t[:, 0])]
        np.testing.assert_allclose(t[1:, 0], t[:-1, 1], atol=1e-12)


def test_fracture_along_a_grid_line_has_one_piece_per_cell_column():
    _, fr = _fracture([[0.0, 0.5], [1.0, 0.5]])
    assert fr.piece_cell.size == N_CELLS  # not 2 * 8: the shared edge counted once


def test_diagonal_through_nodes_has_one_piece_per_diagonal_cell():
    mesh, fr = _fracture([[0.0, 0.0], [1.0, 1.0]])
    i = np.arange(N_CELLS)
    np.testing.assert_array_equal(np.sort(fr.piece_cell), mesh.cell_of(i, i))
    np.testing.assert_allclose(
        fr.piece_t[:, 1] - fr.piece_t[:, 0], 1.0 / N_CELLS, rtol=1e-12
    )


def test_clip_segment_against_hand_computed_parameters():
    p0, p1 = np.array([0.0, 0.0]), np.array([2.0, 1.0])
    boxes = np.array(
        [
            [0.5, 1.5, 0.0, 1.0],  # x limits t to [0.25, 0.75], y to [0, 1]
            [0.0, 1.0, 0.25, 0.75],  # x: [0, 0.5]; y: [0.25, 0.75] -> [0.25, 0.5]
            [1.5, 2.0, 0.0, 0.2],  # x: [0.75, 1]; y: [0, 0.2] -> empty
            [-1.0, 3.0, -1.0, 2.0],  # contains the whole segment
        ]
    )
    ta, tb = clip_segment(p0, p1, boxes)
    np.testing.assert_allclose(ta[[0, 1, 3]], [0.25, 0.25, 0.0], atol=1e-15)
    np.testing.assert_allclose(tb[[0, 1, 3]], [0.75, 0.5, 1.0], atol=1e-15)
    assert ta[2] >= tb[2]
    # reversed segment: parameters mirrored (t -> 1 - t)
    ta_r, tb_r = clip_segment(p1, p0, boxes[:2])
    np.testing.assert_allclose(ta_r, 1.0 - tb[:2], atol=1e-15)
    np.testing.assert_allclose(tb_r, 1.0 - ta[:2], atol=1e-15)
    # vertical segment (d_x = 0): inside or outside in x, clipped in y
    ta, tb = clip_segment(
        np.array([0.3, -1.0]),
        np.array([0.3, 1.0]),
        np.array([[0.0, 0.5, 0.0, 0.5], [0.5, 1.0, 0.0, 0.5]]),
    )
    np.testing.assert_allclose([ta[0], tb[0]], [0.5, 0.75], atol=1e-15)
    assert ta[1] >= tb[1]


# ------------------------------------------------------------- intersecting fractures
# Networks are built (junctions: tests/unit/geometry/test_junction.py);
# only truly degenerate input is refused: fractures overlapping on one line.


@pytest.mark.parametrize(
    "second",
    [
        pytest.param([[0.3, 0.3], [0.9, 0.9]], id="overlapping"),
        pytest.param([[0.8, 0.8], [0.5, 0.5]], id="overlapping-reversed"),
    ],
)
def test_overlapping_fractures_raise(second):
    mesh = _mesh()
    specs = [_spec([[0.2, 0.2], [0.8, 0.8]], 0), _spec(second, 1)]
    with pytest.raises(
        GeometryError, match=r"fractures\[0\] and fractures\[1\] overlap"
    ):
        build_fractures(mesh, specs, BOX)


def test_disjoint_fractures_are_accepted():
    mesh = _mesh()
    specs = [_spec([[0.2, 0.2], [0.8, 0.8]], 0), _spec([[0.2, 0.3], [0.7, 0.8]], 1)]
    fracs = build_fractures(mesh, specs, BOX)
    assert [f.index for f in fracs] == [0, 1]


# -------------------------------------------------------------------------- ramp


def test_ramp_values_behind_at_and_ahead_of_a_tip():
    _, fr = _fracture([A, B])
    tip = next(tp for tp in fr.tips if tp.end == 1)
    d, lr = tip.direction, tip.ramp_length
    nd = np.array([-d[1], d[0]])
    # psi = signed distance along d from the tip; a sideways offset changes nothing
    psi = np.array([-0.3, -2.0 * lr, -lr, -0.75 * lr, -0.3 * lr, 0.0, 0.2 * lr, 0.1])
    for off in (0.0, 0.02, -0.05):
        pts = tip.point + psi[:, None] * d + off * nd
        R, _ = fr.ramp(pts)
        np.testing.assert_allclose(
            R, [1.0, 1.0, 1.0, 0.75, 0.3, 0.0, 0.0, 0.0], rtol=0, atol=1e-12
        )
    # the other tip acts the same way from its side
    first = next(tp for tp in fr.tips if tp.end == 0)
    R, _ = fr.ramp(first.point - 0.5 * first.ramp_length * first.direction)
    assert R[0] == pytest.approx(0.5, abs=1e-12)


def test_ramp_is_one_everywhere_without_tips():
    _, fr = _fracture([[0.0, 0.3], [1.0, 0.6]])
    R, g = fr.ramp(np.random.default_rng(0).random((20, 2)))
    np.testing.assert_array_equal(R, 1.0)
    np.testing.assert_array_equal(g, 0.0)


def test_ramp_gradient_matches_central_differences():
    _, fr = _fracture([A, B])
    rng = np.random.default_rng(7)
    pts = []
    for tip in fr.tips:  # points in the linear part of each ramp and around it
        psi = -tip.ramp_length * rng.uniform(-0.5, 1.5, 40)
        off = rng.uniform(-0.1, 0.1, 40)
        nd = np.array([-tip.direction[1], tip.direction[0]])
        pts.append(tip.point + psi[:, None] * tip.direction + off[:, None] * nd)
    pts = np.concatenate(pts + [rng.random((40, 2))])
    # stay away from the ramp's kinks (psi = 0 and psi = -l of each tip)
    h = 1e-7
    for tip in fr.tips:
        psi = (pts - tip.point) @ tip.direction
        pts = pts[(np.abs(psi) > 10 * h) & (np.abs(psi + tip.ramp_length) > 10 * h)]
    assert pts.shape[0] > 60
    _, grad = fr.ramp(pts)
    fd = np.empty_like(grad)
    for k in range(2):
        e = np.zeros(2)
        e[k] = h
        fd[:, k] = (fr.ramp(pts + e)[0] - fr.ramp(pts - e)[0]) / (2 * h)
    scale = 1.0 / min(tp.ramp_length for tp in fr.tips)
    np.testing.assert_allclose(grad, fd, rtol=0, atol=1e-6 * scale)
    # and the linear part really has slope -1/l along d
    tip = fr.tips[1]
    _, g = fr.ramp(tip.point - 0.5 * tip.ramp_length * tip.direction)
    np.testing.assert_allclose(g[0], -tip.direction / tip.ramp_length, rtol=1e-12)
