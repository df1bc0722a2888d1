"""Tests of xfemslip.fem.quadrature: polygon splitting, sub-cell rules, Duffy rule,
interface points.

References: exact monomial integrals over triangles (barycentric formula),
polar-coordinate integrals of r^p evaluated with scipy.integrate.quad, areas
of hand-cut cells.
"""

from __future__ import annotations

import math
from itertools import product

import numpy as np
import pytest
from scipy import integrate

from tests.support.casegen import fracture_spec
from xfemslip.fem.mesh import build_mesh
from xfemslip.fem.quadrature import (
    cell_subtriangles,
    duffy_rule,
    interface_points,
    polygon_area,
    split_polygon,
    triangle_rule,
)
from xfemslip.geometry.fracture import build_fracture

SQUARE = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
TOL = 1e-10
TRI = np.array([[0.1, 0.2], [0.9, 0.3], [0.4, 0.8]])


def _tri_area(tris):
    e1 = tris[:, 1] - tris[:, 0]
    e2 = tris[:, 2] - tris[:, 0]
    return 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])


# -------------------------------------------------------------------- references


def _multinomial_terms(power, coords):
    """(exponents (3,), coefficient) of (sum_k lambda_k c_k)^power."""
    out = []
    for a in range(power + 1):
        for b in range(power + 1 - a):
            c = power - a - b
            coef = math.factorial(power) / (
                math.factorial(a) * math.factorial(b) * math.factorial(c)
            )
            out.append(
                ((a, b, c), coef * coords[0] ** a * coords[1] ** b * coords[2] ** c)
            )
    return out


def exact_monomial(tri, i, j):
    """int_T x^i y^j dA, expanded in barycentric coordinates:
    int_T l1^p l2^q l3^r dA = 2 A p! q! r! / (p + q + r + 2)!."""
    area = abs(_tri_area(tri[None])[0])
    total = 0.0
    for (ex, cx), (ey, cy) in product(
        _multinomial_terms(i, tri[:, 0]), _multinomial_terms(j, tri[:, 1])
    ):
        p, q, r = (ex[k] + ey[k] for k in range(3))
        total += (
            cx
            * cy
            * 2.0
            * area
            * (math.factorial(p) * math.factorial(q) * math.factorial(r))
            / math.factorial(p + q + r + 2)
        )
    return total


def polar_reference(tri, power):
    """int_T |x - v0|^power dA = int_theta R(theta)^(power+2) / (power+2) dtheta,
    R(theta) the distance from v0 to the opposite edge along direction theta."""
    v0, v1, v2 = tri
    e = v2 - v1

    def radius(theta):
        d = np.array([math.cos(theta), math.sin(theta)])
        s, _ = np.linalg.solve(np.column_stack([d, -e]), v1 - v0)
        return s

    a, b = v1 - v0, v2 - v0
    a1 = math.atan2(a[1], a[0])
    sweep = math.atan2(a[0] * b[1] - a[1] * b[0], a @ b)  # signed angle a -> b
    val, _ = integrate.quad(
        lambda t: radius(t) ** (power + 2) / (power + 2),
        a1,
        a1 + sweep,
        epsabs=0.0,
        epsrel=1e-13,
        limit=200,
    )
    return abs(val)


def test_references_on_the_unit_triangle():
    unit = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    assert exact_monomial(unit, 0, 0) == pytest.approx(0.5, rel=1e-15)
    assert exact_monomial(unit, 1, 0) == pytest.approx(1.0 / 6.0, rel=1e-15)
    assert exact_monomial(unit, 1, 1) == pytest.approx(1.0 / 24.0, rel=1e-15)
    assert exact_monomial(unit, 2, 0) == pytest.approx(1.0 / 12.0, rel=1e-15)
    # int of r dA over the half square 0 <= y <= x <= 1 = (sqrt(2) + asinh(1)) / 6
    half = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])
    for tri in (half, half[[0, 2, 1]]):
        assert polar_reference(tri, 1.0) == pytest.approx(
            (math.sqrt(2.0) + math.asinh(1.0)) / 6.0, rel=1e-12
        )
    # int of 1 dA is the area, whatever the orientation or the angle range
    for tri in (unit, TRI, np.array([[0.5, 0.5], [0.2, 0.9], [0.1, 0.3]])):
        assert polar_reference(tri, 0.0) == pytest.approx(
            exact_monomial(tri, 0, 0), rel=1e-12
        )


# ----------------------------------------------------------------- split_polygon


def _assert_clean(poly, tol=TOL):
    """Convex, counter-clockwise, positive area, no repeated vertex (no sliver)."""
    assert polygon_area(poly) > 1e3 * tol
    k = poly.shape[0]
    assert k >= 3
    gaps = np.linalg.norm(poly - np.roll(poly, -1, axis=0), axis=1)
    assert gaps.min() > tol
    e = np.roll(poly, -1, axis=0) - poly
    cross = (
        e[:, 0] * np.roll(e, -1, axis=0)[:, 1] - e[:, 1] * np.roll(e, -1, axis=0)[:, 0]
    )
    assert np.all(cross > -1e-14)


def test_split_polygon_random_lines_conserve_area():
    rng = np.random.default_rng(3)
    hexagon = np.column_stack(
        [
            np.cos(np.arange(6) * np.pi / 3) + 2.0,
            0.5 * np.sin(np.arange(6) * np.pi / 3) - 1.0,
        ]
    )
    for poly in (SQUARE, hexagon):
        area = polygon_area(poly)
        lo, hi = poly.min(axis=0), poly.max(axis=0)
        n_split = 0
        for _ in range(200):
            point = lo + rng.random(2) * (hi - lo)
            ang = rng.uniform(0.0, 2.0 * np.pi)
            normal = np.array([np.cos(ang), np.sin(ang)])
            pieces = split_polygon(poly, point, normal, TOL)
            assert sum(polygon_area(p) for p in pieces) == pytest.approx(
                area, rel=1e-13
            )
            for p in pieces:
                _assert_clean(p)
            if len(pieces) == 2:
                n_split += 1
                # one piece on each side of the line
                d = [(p - point) @ normal for p in pieces]
                assert (d[0].min() >= -1e-12 and d[1].max() <= 1e-12) or (
                    d[1].min() >= -1e-12 and d[0].max() <= 1e-12
                )
        assert n_split > 100


def test_split_through_two_vertices_gives_two_triangles():
    normal = np.array([1.0, -1.0]) / math.sqrt(2.0)  # the diagonal y = x
    pieces = split_polygon(SQUARE, np.zeros(2), normal, TOL)
    assert len(pieces) == 2
    for p in pieces:
        assert p.shape == (3, 2)
        assert polygon_area(p) == pytest.approx(0.5, rel=1e-15)
        _assert_clean(p)


def test_split_through_one_vertex_creates_no_extra_vertex_there():
    # line through (0, 0) and (1, 0.5)
    normal = np.array([0.5, -1.0]) / math.hypot(0.5, 1.0)
    pieces = split_polygon(SQUARE, np.zeros(2), normal, TOL)
    assert sorted(p.shape[0] for p in pieces) == [3, 4]
    assert sorted(polygon_area(p) for p in pieces) == pytest.approx(
        [0.25, 0.75], rel=1e-14
    )
    for p in pieces:
        _assert_clean(p)


@pytest.mark.parametrize(
    "point, normal",
    [
        pytest.param([0.3, 0.0], [0.0, 1.0], id="along-bottom-edge"),
        pytest.param([1.0, 0.7], [-1.0, 0.0], id="along-right-edge"),
        pytest.param([1.0, 1.0], [1.0, 1.0], id="touching-one-vertex"),
        pytest.param([2.0, 0.5], [1.0, 0.2], id="missing"),
        pytest.param([0.3, 1e-13], [0.0, 1.0], id="within-tol-of-an-edge"),
    ],
)
def test_lines_that_do_not_cut_leave_the_polygon_whole(point, normal):
    normal = np.asarray(normal, float) / np.linalg.norm(normal)
    pieces = split_polygon(SQUARE, np.asarray(point, float), normal, TOL)
    assert len(pieces) == 1
    np.testing.assert_array_equal(pieces[0], SQUARE)


def test_line_within_tol_of_a_vertex_makes_no_sliver():
    # the diagonal shifted by 1e-13: without snapping this would cut a sliver of
    # area ~1e-13 off the corners (0, 0) and (1, 1)
    normal = np.array([1.0, -1.0]) / math.sqrt(2.0)
    pieces = split_polygon(SQUARE, np.array([1e-13, 0.0]), normal, TOL)
    assert len(pieces) == 2
    for p in pieces:
        assert p.shape == (3, 2)
        _assert_clean(p)


# ------------------------------------------------------------- cell_subtriangles


def _check_subtriangles(bounds, lines, apexes=()):
    tris = cell_subtriangles(np.asarray(bounds, float), lines, TOL, apexes=apexes)
    x0, x1, y0, y1 = bounds
    area = _tri_area(tris)
    assert np.all(area > 0.0)  # counter-clockwise, non-degenerate
    assert area.sum() == pytest.approx((x1 - x0) * (y1 - y0), rel=1e-13)
    for point, normal in lines:
        d = (tris - point) @ normal  # (t, 3)
        assert np.all((d.max(axis=1) <= 1e-12) | (d.min(axis=1) >= -1e-12))
    assert np.all(
        (tris[..., 0] >= x0 - 1e-14)
        & (tris[..., 0] <= x1 + 1e-14)
        & (tris[..., 1] >= y0 - 1e-14)
        & (tris[..., 1] <= y1 + 1e-14)
    )
    return tris


def _line(p, q):
    p, q = np.asarray(p, float), np.asarray(q, float)
    t = (q - p) / np.linalg.norm(q - p)
    return p, np.array([-t[1], t[0]])


@pytest.mark.parametrize(
    "bounds, lines",
    [
        pytest.param(
            [0.0, 1.0, 0.0, 1.0], [_line([0, 0.25], [1, 0.75])], id="one-line"
        ),
        pytest.param([0.0, 1.0, 0.0, 1.0], [_line([0, 0], [1, 1])], id="diagonal"),
        pytest.param(
            [0.0, 1.0, 0.0, 1.0],
            [
                _line([0, 0.5], [1, 0.5]),
                _line([0.3, 0], [0.3, 1]),
                _line([0.7, 0], [0.7, 1]),
            ],
            id="three-lines",
        ),
        pytest.param(
            [2.0, 2.5, 1.0, 1.25],
            [_line([2.1, 1.0], [2.4, 1.3]), _line([2.0, 1.2], [2.5, 1.05])],
            id="two-crossing-lines-small-cell",
        ),
        pytest.param([0.0, 1.0, 0.0, 1.0], [_line([0, 0], [1, 0])], id="along-an-edge"),
    ],
)
def test_cell_subtriangles_tile_the_cell_and_respect_every_line(bounds, lines):
    _check_subtriangles(bounds, lines)


def test_cell_subtriangles_fan_from_the_tip():
    tip = np.array([0.6, 0.55])
    d = np.array([0.8, 0.6])  # tip direction; fracture behind it
    nd = np.array([-d[1], d[0]])
    lines = [(tip, nd), (tip, d), (tip - 0.3 * d, d)]
    tris = _check_subtriangles([0.0, 1.0, 0.0, 1.0], lines, apexes=[tip])
    at_tip = np.linalg.norm(tris - tip, axis=2) <= 1e-12
    touching = at_tip.any(axis=1)
    assert touching.sum() >= 4  # the tip is a vertex of the sub-cells around it
    assert np.all(at_tip[touching, 0])  # ... always as vertex 0 (Duffy rule)


def test_sub_cell_rule_integrates_linear_fields_per_side():
    # cell [0,1]^2 cut by y = 0.25 + 0.5 x: below it, area = 1/2 and
    # int x dA = int_0^1 x (0.25 + 0.5 x) dx = 1/8 + 1/6
    point, normal = _line([0.0, 0.25], [1.0, 0.75])
    tris = _check_subtriangles([0.0, 1.0, 0.0, 1.0], [(point, normal)])
    xy, w = triangle_rule(tris)
    below = np.repeat((tris.mean(axis=1) - point) @ normal < 0.0, 7)
    assert w[below].sum() == pytest.approx(0.5, rel=1e-13)
    assert w[~below].sum() == pytest.approx(0.5, rel=1e-13)
    assert (w * xy[:, 0])[below].sum() == pytest.approx(1 / 8 + 1 / 6, rel=1e-13)
    assert (w * xy[:, 1])[below].sum() == pytest.approx(
        integrate.quad(lambda x: 0.5 * (0.25 + 0.5 * x) ** 2, 0, 1)[0], rel=1e-13
    )


# ------------------------------------------------------------------ triangle_rule


@pytest.mark.parametrize("degree", range(6))
def test_triangle_rule_is_exact_up_to_degree_5(degree):
    xy, w = triangle_rule(TRI[None])
    for i in range(degree + 1):
        j = degree - i
        exact = exact_monomial(TRI, i, j)
        assert np.sum(w * xy[:, 0] ** i * xy[:, 1] ** j) == pytest.approx(
            exact, rel=1e-13
        )


def test_triangle_rule_is_not_exact_at_degree_6():
    """The rule really is degree 5 (the exactness test above can fail)."""
    tri = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    xy, w = triangle_rule(tri[None])
    err = abs(np.sum(w * xy[:, 0] ** 6) - exact_monomial(tri, 6, 0))
    assert err > 1e-6


def test_triangle_rule_on_many_triangles_and_orientation():
    tris = np.stack([TRI, TRI[::-1], TRI + 1.0])  # one of them clockwise
    xy, w = triangle_rule(tris)
    assert xy.shape == (21, 2) and w.shape == (21,)
    np.testing.assert_allclose(
        w.reshape(3, 7).sum(axis=1), abs(_tri_area(tris)), rtol=1e-14
    )


# --------------------------------------------------------------------- duffy_rule


def test_duffy_points_lie_in_the_triangle_and_weights_sum_to_area():
    xy, w = duffy_rule(TRI[None])
    assert np.all(w > 0.0)
    assert w.sum() == pytest.approx(abs(_tri_area(TRI[None])[0]), rel=1e-14)
    # barycentric coordinates of the points are in [0, 1]
    T = np.column_stack([TRI[1] - TRI[0], TRI[2] - TRI[0]])
    lam = np.linalg.solve(T, (xy - TRI[0]).T).T
    assert np.all(lam >= 0.0) and np.all(lam.sum(axis=1) <= 1.0)


@pytest.mark.parametrize("degree", range(7))
def test_duffy_rule_integrates_polynomials_exactly(degree):
    xy, w = duffy_rule(TRI[None])
    for i in range(degree + 1):
        j = degree - i
        exact = exact_monomial(TRI, i, j)
        assert np.sum(w * xy[:, 0] ** i * xy[:, 1] ** j) == pytest.approx(
            exact, rel=1e-12
        )


def test_duffy_rule_integrates_the_1_over_r_stiffness_singularity():
    """|grad B|^2 ~ 1/r at the tip (vertex 0): the collapse makes it smooth."""
    for tri in (
        TRI,
        np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]),
        np.array([[0.5, 0.5], [0.2, 0.9], [0.1, 0.3]]),
    ):
        xy, w = duffy_rule(tri[None])
        r = np.linalg.norm(xy - tri[0], axis=1)
        # 7 x 7 collapsed Gauss points: ~1e-8 on TRI, ~2e-6 on the third (blunter) one
        assert np.sum(w / r) == pytest.approx(polar_reference(tri, -1.0), rel=1e-5)


def test_duffy_rule_integrates_inverse_sqrt_r_accurately():
    xy, w = duffy_rule(TRI[None])
    r = np.linalg.norm(xy - TRI[0], axis=1)
    ref = polar_reference(TRI, -0.5)
    assert abs(np.sum(w / np.sqrt(r)) / ref - 1.0) < 1e-6


def test_duffy_rule_inverse_sqrt_r_error_is_bounded():
    """What the rule does reach on 1/sqrt(r) today (guards against getting worse)."""
    xy, w = duffy_rule(TRI[None])
    r = np.linalg.norm(xy - TRI[0], axis=1)
    ref = polar_reference(TRI, -0.5)
    assert abs(np.sum(w / np.sqrt(r)) / ref - 1.0) < 1e-3


# -------------------------------------------------------------- interface_points


def _fractures(points_list, n=8, tip="ramp"):
    grid = np.linspace(0.0, 1.0, n + 1)
    mesh = build_mesh(grid, grid)
    box = np.array([0.0, 1.0, 0.0, 1.0])
    frs = tuple(
        build_fracture(
            mesh,
            fracture_spec(p, i, tip),
            box,
        )
        for i, p in enumerate(points_list)
    )
    return mesh, frs


@pytest.mark.parametrize(
    "points",
    [
        pytest.param([[[0.2, 0.3], [0.8, 0.6]]], id="generic"),
        pytest.param([[[0.1, 0.5], [0.5, 0.5], [0.9, 0.9]]], id="kinked"),
        pytest.param([[[0.2, 0.5], [0.8, 0.5]]], id="along-grid-line"),
        pytest.param([[[0.125, 0.125], [0.875, 0.875]]], id="diagonal-through-nodes"),
        pytest.param([[[-0.2, 0.2], [0.2, 0.4], [0.6, 0.4]]], id="clipped"),
        pytest.param([[[0.0, 0.3], [1.0, 0.6]]], id="crossing"),
        pytest.param([[[0.1, 0.1], [0.4, 0.9]], [[0.6, 0.2], [0.9, 0.7]]], id="two"),
    ],
)
def test_interface_points_weights_and_arc_length(points):
    mesh, frs = _fractures(points)
    ip = interface_points(frs)
    assert ip.n > 0
    for fi, fr in enumerate(frs):
        m = ip.fracture == fi
        assert ip.weight[m].sum() == pytest.approx(float(fr.length.sum()), rel=1e-13)
        assert np.all(ip.weight[m] > 0.0)
        s = ip.s[m]
        assert np.all(np.diff(s) > 0.0)
        assert s[0] > fr.s_start[0] and s[-1] < fr.s_start[0] + fr.length.sum()
        # s: arc length of xy along the clipped polyline, from the case's first point
        seg = np.searchsorted(
            np.concatenate([fr.s_start[1:], [np.inf]]), s, side="right"
        )
        t = (s - fr.s_start[seg]) / fr.length[seg]
        np.testing.assert_allclose(
            ip.xy[m],
            fr.points[seg] + t[:, None] * (fr.points[seg + 1] - fr.points[seg]),
            atol=1e-14,
        )
        np.testing.assert_allclose(ip.normal[m], fr.normal[seg], atol=0)
        np.testing.assert_allclose(ip.tangent[m], fr.tangent[seg], atol=0)
        np.testing.assert_allclose(ip.ramp[m], fr.ramp(ip.xy[m])[0], atol=0)
        # every point lies in its cell
        b = mesh.bounds[ip.cell[m]]
        x, y = ip.xy[m, 0], ip.xy[m, 1]
        assert np.all((x >= b[:, 0]) & (x <= b[:, 1]) & (y >= b[:, 2]) & (y <= b[:, 3]))


@pytest.mark.parametrize(
    "points",
    [
        pytest.param([[0.2, 0.3], [0.8, 0.6]], id="generic"),
        pytest.param([[0.125, 0.125], [0.875, 0.875]], id="diagonal-through-nodes"),
    ],
)
def test_interface_points_s_is_strictly_increasing(points):
    _, frs = _fractures([points])
    ip = interface_points(frs)
    assert np.all(np.diff(ip.s) > 0.0)
    # 4 Gauss points per piece, nothing else, when the tips end in their cells
    assert ip.n == 4 * frs[0].piece_cell.size


@pytest.mark.parametrize(
    "points",
    [
        pytest.param([[0.2, 0.3], [0.8, 0.6]], id="generic"),
        pytest.param([[0.125, 0.125], [0.875, 0.875]], id="diagonal-through-nodes"),
    ],
)
def test_no_zero_length_sub_piece_where_the_ramp_kink_meets_a_cell_edge(points):
    """The kink psi = -l of each ramp is the tip cell's boundary: the piece must not
    be cut there again (at HEAD 6d64142 round-off did, adding 4 points of weight
    ~1e-18 at the same s)."""
    _, frs = _fractures([points])
    ip = interface_points(frs)
    assert np.all(np.diff(ip.s) > 0.0)
    assert ip.n == 4 * frs[0].piece_cell.size  # 4 Gauss points per piece, no more


def test_interface_rule_integrates_the_ramped_penalty_exactly():
    """int R^2 ds = L - sum_tips (2/3) l: R falls linearly to 0 over l at each tip."""
    mesh, frs = _fractures([[[0.2, 0.3], [0.8, 0.6]]])
    (fr,) = frs
    ip = interface_points(frs)
    ls = [tp.ramp_length for tp in fr.tips]
    exact = fr.length.sum() - sum(2.0 / 3.0 * lr for lr in ls)
    assert np.sum(ip.weight * ip.ramp**2) == pytest.approx(exact, rel=1e-13)
    # the line rule is a 4-point Gauss rule per piece: degree 7 in s
    exact6 = fr.length.sum() - sum(6.0 / 7.0 * lr for lr in ls)
    assert np.sum(ip.weight * ip.ramp**6) == pytest.approx(exact6, rel=1e-13)
