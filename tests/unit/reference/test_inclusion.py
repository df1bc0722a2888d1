"""The stress of a pressure change in a polygon (xfemslip.reference.inclusion),
checked independently: numerical quadrature of the point-source kernel in
polar coordinates around the point, the corner sum of a rectangle, the
laterally infinite layer (uniaxial strain), the vertical fault (J1),
symmetry and the jump across an edge."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from scipy import integrate

from xfemslip.reference.closed_form_depletion import (
    offset_fault_shear,
    rectangles_shear,
    uniaxial_strain_change,
)
from xfemslip.reference.inclusion import (
    coulomb_change,
    displaced_fault,
    fault_tractions,
    log_potential_hessian,
    polygon_stress,
    stress_factor,
)

NU, ALPHA, DP = 0.15, 0.9, -25.0e6
K = ALPHA * DP * (1.0 - 2.0 * NU) / (1.0 - NU)


def _ray_interval(p, polygon, e):
    """[rho0, rho1] of the ray p + rho e (rho >= 0) inside a convex
    counter-clockwise polygon (Cyrus-Beck), or None."""
    lo, hi = 0.0, math.inf
    m = len(polygon)
    for k in range(m):
        a, b = polygon[k], polygon[(k + 1) % m]
        n = np.array([b[1] - a[1], a[0] - b[0]])  # outward for CCW
        num, den = -np.dot(n, p - a), np.dot(n, e)
        if den > 0.0:
            hi = min(hi, num / den)
        elif den < 0.0:
            lo = max(lo, num / den)
        elif num < 0.0:
            return None
    return (lo, hi) if hi > lo else None


def _quadrature_stress(p, polygon, inside):
    """sigma = K (H - chi I), H_ij = (1/2 pi) PV int d_i d_j ln r dA + chi/2
    delta_ij (d_i d_j ln r = (delta_ij r^2 - 2 r_i r_j) / r^4 + pi delta_ij
    delta(r)).  In polar coordinates around p the kernel is
    k(theta) / rho^2 with k = (-cos 2 theta, cos 2 theta, -sin 2 theta) of
    zero mean, so int dA = int k(theta) ln(rho1 / rho0) dtheta (rho0 -> 0
    drops out inside); split at the vertex directions, adaptive quadrature
    on each piece."""
    p = np.asarray(p, float)
    poly = np.asarray(polygon, float)
    cuts = np.sort(np.arctan2(poly[:, 1] - p[1], poly[:, 0] - p[0]) % (2 * np.pi))
    edges = np.concatenate([[0.0], cuts, [2 * np.pi]])

    def f(theta, which):
        e = np.array([math.cos(theta), math.sin(theta)])
        span = _ray_interval(p, poly, e)
        if span is None:
            return 0.0
        rho0, rho1 = span
        length = math.log(rho1) - (0.0 if inside else math.log(rho0))
        k = (-math.cos(2 * theta), math.cos(2 * theta), -math.sin(2 * theta))[which]
        return k * length

    H = np.zeros(3)
    for which in range(3):
        for t0, t1 in zip(edges[:-1], edges[1:], strict=True):
            if t1 > t0:
                with warnings.catch_warnings():  # at round-off: said, not an error
                    warnings.simplefilter("ignore", integrate.IntegrationWarning)
                    val, _ = integrate.quad(
                        f, t0, t1, args=(which,), epsabs=1e-14, epsrel=1e-13, limit=200
                    )
                H[which] += val / (2 * np.pi)
    chi = 1.0 if inside else 0.0
    H[:2] += 0.5 * chi
    return K * np.array([H[0] - chi, H[1] - chi, H[2]])


TRAPEZOID = np.array([[0.0, 0.0], [120.0, 0.0], [95.0, 60.0], [10.0, 60.0]])
TRIANGLE = np.array([[-30.0, 5.0], [40.0, -20.0], [10.0, 70.0]])


@pytest.mark.parametrize(
    ("polygon", "point", "inside"),
    [
        (TRAPEZOID, (50.0, 30.0), True),
        (TRAPEZOID, (3.0, 2.0), True),
        (TRAPEZOID, (130.0, 70.0), False),
        (TRAPEZOID, (60.0, -4.0), False),
        (TRIANGLE, (5.0, 10.0), True),
        (TRIANGLE, (-40.0, 60.0), False),
    ],
)
def test_polygon_matches_quadrature_of_the_point_source(polygon, point, inside):
    got = polygon_stress(np.array([point]), polygon, DP, NU, ALPHA)[0]
    want = _quadrature_stress(point, polygon, inside)
    np.testing.assert_allclose(got, want, rtol=0.0, atol=1e-10 * abs(K))


def test_nonconvex_polygon_is_the_sum_of_its_convex_parts():
    """An L-shape against its two rectangles (each checked by quadrature
    above as a polygon) and the orientation: clockwise = counter-clockwise."""
    ell = np.array([[0, 0], [60, 0], [60, 20], [20, 20], [20, 50], [0, 50]], float)
    parts = [
        np.array([[0, 0], [60, 0], [60, 20], [0, 20]], float),
        np.array([[0, 20], [20, 20], [20, 50], [0, 50]], float),
    ]
    pts = np.array([[30.0, 35.0], [10.0, 10.0], [-5.0, 60.0], [40.0, 21.0]])
    got = polygon_stress(pts, ell, DP, NU, ALPHA)
    want = sum(polygon_stress(pts, q, DP, NU, ALPHA) for q in parts)
    np.testing.assert_allclose(got, want, rtol=0.0, atol=1e-12 * abs(K))
    np.testing.assert_allclose(
        polygon_stress(pts, ell[::-1], DP, NU, ALPHA), got, rtol=1e-14, atol=0.0
    )
    for q, p in zip(parts, ([30.0, 35.0], [10.0, 40.0]), strict=True):
        inside = bool(p[1] > 20.0) == bool(q[0, 1] == 20.0)
        np.testing.assert_allclose(
            polygon_stress(np.array([p]), q, DP, NU, ALPHA)[0],
            _quadrature_stress(p, q, inside),
            atol=1e-10 * abs(K),
        )


def test_rectangle_shear_is_the_corner_sum():
    """sigma_xy of a rectangle: K / (2 pi) times the signed sum of ln r over
    its corners, written out here."""
    x0, y0, x1, y1 = -20.0, 10.0, 35.0, 45.0
    pts = np.array([[0.0, 0.0], [5.0, 20.0], [50.0, 44.0], [-20.0, 30.0]])

    def g(cx, cy):
        return np.log(np.hypot(pts[:, 0] - cx, pts[:, 1] - cy))

    corner = g(x0, y0) - g(x0, y1) - g(x1, y0) + g(x1, y1)
    box = [[x0, y0], [x1, y0], [x1, y1], [x0, y1]]
    got = polygon_stress(pts, box, DP, NU, ALPHA)[:, 2]
    np.testing.assert_allclose(got, K / (2 * np.pi) * corner, rtol=1e-13)


def test_laterally_infinite_layer_is_uniaxial_strain():
    """A layer 1e9 times wider than thick: inside sigma_xx = -alpha dp (1 - 2
    nu) / (1 - nu), sigma_yy = sigma_xy = 0 (closed_form_depletion, 1);
    outside no stress."""
    L = 1.0e11
    layer = [[-L, -50.0], [L, -50.0], [L, 50.0], [-L, 50.0]]
    pts = np.array([[0.0, 0.0], [300.0, 49.0], [-7.0, -49.9], [0.0, 80.0]])
    s = polygon_stress(pts, layer, DP, NU, ALPHA)
    ref = uniaxial_strain_change(DP, NU, ALPHA)
    np.testing.assert_allclose(s[:3, 0], ref["xx"], rtol=1e-9)
    np.testing.assert_allclose(s[:3, 1:], 0.0, atol=1e-9 * abs(K))
    np.testing.assert_allclose(s[3], 0.0, atol=1e-9 * abs(K))
    assert log_potential_hessian(pts, layer)[:, 3].tolist() == [1.0, 1.0, 1.0, 0.0]


def test_edge_gives_the_mean_of_the_two_sides_and_vertices_nan():
    """On an edge: the mean of the limits from both sides (their tractions
    agree, sigma_tt jumps by K); NaN at a vertex."""
    poly = TRAPEZOID
    a, b = poly[1], poly[2]
    t = (b - a) / np.linalg.norm(b - a)
    n = np.array([t[1], -t[0]])  # outward
    p = a + 0.3 * (b - a)
    eps = 1e-7
    on, out, inn = (
        polygon_stress(np.array([q]), poly, DP, NU, ALPHA)[0]
        for q in (p, p + eps * n, p - eps * n)
    )
    np.testing.assert_allclose(on, 0.5 * (out + inn), atol=1e-6 * abs(K))

    def frame(s):
        S = np.array([[s[0], s[2]], [s[2], s[1]]])
        return n @ S @ n, t @ S @ n, t @ S @ t

    (nn_o, tn_o, tt_o), (nn_i, tn_i, tt_i) = frame(out), frame(inn)
    assert nn_o == pytest.approx(nn_i, abs=1e-6 * abs(K))
    assert tn_o == pytest.approx(tn_i, abs=1e-6 * abs(K))
    assert tt_i - tt_o == pytest.approx(-K, rel=1e-5)  # the inclusion's jump
    assert log_potential_hessian(np.array([p]), poly)[0, 3] == 0.5
    assert np.isnan(polygon_stress(poly[2:3], poly, DP, NU, ALPHA)).all()


def test_vertical_fault_is_j1():
    """Dip 90: the compartments are the rectangles of (J1); with t = (0, 1)
    and n = (-1, 0), tau = -sigma_xy and sigma_n = sigma_xx."""
    h, throw = 100.0, 30.0
    fault = displaced_fault(h, throw, 90.0)
    y = np.linspace(-120.0, 120.0, 49) + 0.31
    res = fault_tractions(fault, y, DP, DP, NU, ALPHA)
    a, b = -0.5 * (h + throw), 0.5 * (h - throw)  # hanging wall, x < 0
    c, d = -0.5 * (h - throw), 0.5 * (h + throw)
    np.testing.assert_allclose(
        res.tau, -offset_fault_shear(y, a, b, c, d, DP, NU, ALPHA), rtol=1e-9
    )
    np.testing.assert_allclose(res.sigma_n, res.stress[:, 0], rtol=1e-12, atol=1e-6)
    L = 1.0e9
    rects = [[-L, a, 0.0, b], [0.0, c, L, d]]
    np.testing.assert_allclose(
        res.stress[:, 2], rectangles_shear(0.0 * y, y, rects, DP, NU, ALPHA), rtol=1e-7
    )
    np.testing.assert_allclose(fault.normal, [-1.0, 0.0], atol=1e-15)
    assert fault.corners.tolist() == [a, c, b, d]


def test_displaced_fault_symmetry():
    """The published geometry (h = 225 m, t = 75 m, dip 70): a half turn
    about the centre swaps the compartments and keeps the fault and its
    frame, so with one dp the tractions are even in y; dp only in the
    hanging wall at y equals dp only in the footwall at -y."""
    fault = displaced_fault(225.0, 75.0, 70.0)
    half = np.linspace(0.35, 300.0, 40)
    y = np.concatenate([-half[::-1], half])
    both = fault_tractions(fault, y, DP, DP, NU, ALPHA)
    np.testing.assert_allclose(both.tau, both.tau[::-1], atol=1e-9 * abs(K))
    np.testing.assert_allclose(both.sigma_n, both.sigma_n[::-1], atol=1e-9 * abs(K))
    hw = fault_tractions(fault, y, DP, 0.0, NU, ALPHA)
    fw = fault_tractions(fault, y, 0.0, DP, NU, ALPHA)
    np.testing.assert_allclose(hw.tau, fw.tau[::-1], atol=1e-9 * abs(K))
    np.testing.assert_allclose(hw.tau + fw.tau, both.tau, atol=1e-12 * abs(K))
    assert fault.corners.tolist() == [-150.0, -75.0, 75.0, 150.0]
    at = fault_tractions(fault, fault.corners, DP, DP, NU, ALPHA)
    assert np.isnan(at.tau).all()
    # zero throw, one dp: the fault sees the layer's uniaxial state
    flat = fault_tractions(displaced_fault(225.0, 0.0, 70.0), [0.0, 100.0], DP, DP, NU)
    th = math.radians(70.0)
    sxx = stress_factor(-DP, NU)  # uniaxial: sigma_xx = -K(alpha = 1)
    n = np.array([-math.sin(th), math.cos(th)])
    t = np.array([math.cos(th), math.sin(th)])
    np.testing.assert_allclose(flat.sigma_n, sxx * n[0] ** 2, rtol=1e-9)
    np.testing.assert_allclose(flat.tau, sxx * t[0] * n[0], rtol=1e-9)


def test_face_pressures_and_coulomb_change():
    fault = displaced_fault(225.0, 75.0, 70.0)
    y = np.array([-160.0, -100.0, 0.0, 100.0, 160.0])
    res = fault_tractions(fault, y, -20.0e6, -25.0e6, NU, ALPHA)
    # n points into the hanging wall (-x side, -150..75); footwall -75..150
    assert res.pressure_plus.tolist() == [0.0, -20.0e6, -20.0e6, 0.0, 0.0]
    assert res.pressure_minus.tolist() == [0.0, 0.0, -25.0e6, -25.0e6, 0.0]
    p = 0.5 * (res.pressure_plus + res.pressure_minus)
    cfs = coulomb_change(res.tau, res.sigma_n, p, 0.6, sense=-1.0)
    np.testing.assert_allclose(cfs, -res.tau + 0.6 * (res.sigma_n + p), rtol=1e-15)
    with pytest.raises(ValueError, match="sense"):
        coulomb_change(res.tau, res.sigma_n, p, 0.6, sense=0.5)
