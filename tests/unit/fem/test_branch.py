"""Tests of xfemslip.fem.branch: the four near-tip functions, their gradients and jumps.

References: closed forms sqrt(r) {sin, cos}(theta/2) [sin theta] in the tip
frame, central finite differences for the gradients.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from xfemslip.case import FractureSpec
from xfemslip.fem.branch import branch_functions, tip_frame
from xfemslip.fem.mesh import build_mesh
from xfemslip.geometry.fracture import build_fracture


def _fracture(points=((0.2, 0.3), (0.8, 0.6))):
    grid = np.linspace(0.0, 1.0, 9)
    mesh = build_mesh(grid, grid)
    spec = FractureSpec(
        index=0,
        points=np.asarray(points, float),
        friction=0.5,
        cohesion=0.0,
        kn=1e12,
        kt=1e12,
        tip="branch",
        tip_radius=None,
    )
    return build_fracture(mesh, spec, np.array([0.0, 1.0, 0.0, 1.0]))


FR = _fracture()
TIPS = {f"end{tp.end}": tp for tp in FR.tips}


def _closed_form(tip, pts):
    """B1..B4 / sqrt(h) from the polar coordinates of the tip frame."""
    d = tip.direction
    nd = np.array([-d[1], d[0]])
    rel = np.atleast_2d(pts) - tip.point
    r = np.linalg.norm(rel, axis=1)
    th = np.arctan2(rel @ nd, rel @ d)
    sr = np.sqrt(r) / math.sqrt(tip.cell_size)
    return np.column_stack(
        [
            sr * np.sin(th / 2),
            sr * np.cos(th / 2),
            sr * np.sin(th / 2) * np.sin(th),
            sr * np.cos(th / 2) * np.sin(th),
        ]
    )


def _away_points(tip, n, rng):
    """Random points within 0.3 of the tip, away from the tip and from the fracture
    line behind it (theta = +-pi, where B1 jumps)."""
    r = rng.uniform(0.02, 0.3, n)
    th = rng.uniform(-np.pi + 0.1, np.pi - 0.1, n)
    d = tip.direction
    nd = np.array([-d[1], d[0]])
    return tip.point + (r * np.cos(th))[:, None] * d + (r * np.sin(th))[:, None] * nd


@pytest.mark.parametrize("which", sorted(TIPS))
def test_values_equal_the_closed_form(which):
    tip = TIPS[which]
    pts = _away_points(tip, 50, np.random.default_rng(0))
    F, _ = branch_functions(tip, pts)
    np.testing.assert_allclose(F, _closed_form(tip, pts), rtol=1e-13, atol=1e-15)
    # one point by hand: r = 0.04 straight along n_d (theta = pi/2)
    nd = np.array([-tip.direction[1], tip.direction[0]])
    F, _ = branch_functions(tip, tip.point + 0.04 * nd)
    s = 0.2 / math.sqrt(tip.cell_size)
    np.testing.assert_allclose(
        F[0],
        [
            s * math.sqrt(0.5),
            s * math.sqrt(0.5),
            s * math.sqrt(0.5),
            s * math.sqrt(0.5),
        ],
        rtol=1e-13,
    )


@pytest.mark.parametrize("which", sorted(TIPS))
def test_gradients_match_central_differences(which):
    tip = TIPS[which]
    pts = _away_points(tip, 60, np.random.default_rng(1))
    _, grad = branch_functions(tip, pts)
    h = 1e-7
    fd = np.empty_like(grad)
    for k in range(2):
        e = np.zeros(2)
        e[k] = h
        fd[..., k] = (
            branch_functions(tip, pts + e)[0] - branch_functions(tip, pts - e)[0]
        ) / (2 * h)
    # |grad| ~ 1/(2 sqrt(r h_tip)) <= ~10; FD error O(h^2 r^-5/2) ~ 1e-11
    np.testing.assert_allclose(grad, fd, rtol=0, atol=1e-6)


@pytest.mark.parametrize("which", sorted(TIPS))
def test_b1_jumps_across_the_fracture_and_b2_to_b4_do_not(which):
    tip = TIPS[which]
    n = FR.normal[0]  # the fracture's normal: + side is where n points
    # points on the fracture behind the tip (a fraction of its length)
    a = np.array([0.01, 0.05, 0.2, 0.5]) * FR.length[0]
    on = tip.point - a[:, None] * tip.direction
    np.testing.assert_allclose(FR.signed_distance(on), 0.0, atol=1e-15)
    # [[B1]] of the scaled B1: 2 sqrt(r) (n_d . n) / sqrt(h_tip), r = a
    expected = 2.0 * np.sqrt(a) * tip.sign / math.sqrt(tip.cell_size)
    # just above (+ side) and just below (- side)
    eps = 1e-10
    Fp, _ = branch_functions(tip, on + eps * n)
    Fm, _ = branch_functions(tip, on - eps * n)
    np.testing.assert_allclose(Fp[:, 0] - Fm[:, 0], expected, rtol=1e-4)
    np.testing.assert_allclose(Fp[:, 1:] - Fm[:, 1:], 0.0, atol=1e-4)
    # on the line itself, the side argument decides
    Fp, _ = branch_functions(tip, on, side=np.ones(a.size), tol=1e-12)
    Fm, _ = branch_functions(tip, on, side=-np.ones(a.size), tol=1e-12)
    np.testing.assert_allclose(Fp[:, 0] - Fm[:, 0], expected, rtol=1e-13)
    np.testing.assert_allclose(Fp[:, 1:] - Fm[:, 1:], 0.0, atol=1e-13)
    # ... and gives the one-sided limits: B1 = +-sqrt(r)/sqrt(h), B2..B4 = 0
    np.testing.assert_allclose(Fp[:, 0], 0.5 * expected, rtol=1e-13)
    np.testing.assert_allclose(Fp[:, 1:], 0.0, atol=1e-13)


def test_b1_jump_sign_follows_the_fracture_orientation():
    """[[B1]] (+ minus - side) is +2 sqrt(r) at the last point, -2 sqrt(r) at the
    first."""
    assert TIPS["end1"].sign == 1.0 and TIPS["end0"].sign == -1.0
    for tip in FR.tips:
        on = tip.point - 0.1 * tip.direction
        n = FR.normal[0]
        jump = (
            branch_functions(tip, on + 1e-10 * n)[0][0, 0]
            - branch_functions(tip, on - 1e-10 * n)[0][0, 0]
        )
        assert np.sign(jump) == tip.sign


def test_side_is_ignored_ahead_of_the_tip_and_off_the_line():
    tip = TIPS["end1"]
    nd = np.array([-tip.direction[1], tip.direction[0]])
    pts = np.array(
        [
            tip.point + 0.1 * tip.direction,
            tip.point + 0.05 * nd,
            tip.point - 0.1 * tip.direction + 0.01 * nd,
        ]
    )
    F0, _ = branch_functions(tip, pts)
    for side in (1.0, -1.0):
        F1, _ = branch_functions(tip, pts, side=np.full(3, side), tol=1e-12)
        np.testing.assert_array_equal(F1, F0)


@pytest.mark.parametrize("which", sorted(TIPS))
def test_functions_vanish_at_the_tip(which):
    tip = TIPS[which]
    F, grad = branch_functions(tip, tip.point)
    np.testing.assert_array_equal(F, 0.0)
    assert np.all(np.isfinite(grad))
    # and go to 0 like sqrt(r)
    pts = _away_points(tip, 20, np.random.default_rng(2))
    rel = pts - tip.point
    for scale in (1e-2, 1e-4):
        Fs, _ = branch_functions(tip, tip.point + scale * rel)
        Fo, _ = branch_functions(tip, pts)
        np.testing.assert_allclose(Fs, math.sqrt(scale) * Fo, rtol=1e-10, atol=1e-15)


def test_tip_frame_coordinates():
    tip = TIPS["end1"]
    d = tip.direction
    nd = np.array([-d[1], d[0]])
    p = tip.point + 0.3 * d - 0.4 * nd
    xl, yl, r, th = tip_frame(tip, p)
    np.testing.assert_allclose(
        [xl[0], yl[0], r[0], th[0]], [0.3, -0.4, 0.5, math.atan2(-0.4, 0.3)], rtol=1e-13
    )
