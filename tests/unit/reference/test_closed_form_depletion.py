"""Closed forms of depletion (xfemslip.reference.closed_form_depletion), checked
independently: numerical integration of the potential behind (J1), the
Griffith crack for the dislocation kernel, cancellation of (J1) by the slip
(J2), symmetry, limits and the sign of the released energy."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import integrate

from xfemslip.reference.closed_form_depletion import (
    critical_change_uniaxial,
    dislocation_shear,
    offset_fault_shear,
    offset_fault_slip,
    rectangles_shear,
    uniaxial_strain_change,
)

NU, MU, DP = 0.25, 4.0e9, -10.0e6
A, B, C, D = -50.0, 50.0, -20.0, 80.0  # left a..b, right c..d: throw 30 m


def _numerical_shear(x, y, rect, dp, nu):
    """2 mu d2psi/dxdy by direct 2D quadrature of d2(ln r)/dxdy over the
    rectangle (the point is outside it): -2 (x - x')(y - y') / r^4."""
    x0, y0, x1, y1 = rect

    def f(yp, xp):
        dx, dy = x - xp, y - yp
        return -2.0 * dx * dy / (dx * dx + dy * dy) ** 2

    val, _ = integrate.dblquad(f, x0, x1, y0, y1, epsabs=1e-13, epsrel=1e-11)
    return dp * (1.0 - 2.0 * nu) / (2.0 * np.pi * (1.0 - nu)) * val


@pytest.mark.parametrize("point", [(3.0, 60.0), (-2.0, -70.0), (10.0, 20.0)])
def test_rectangle_corner_sum_matches_quadrature(point):
    rect = (0.0, C, 40.0, D) if point[0] < 0 else (-40.0, A, -1.0, B)
    got = rectangles_shear(point[0], point[1], [rect], DP, NU)
    want = _numerical_shear(point[0], point[1], rect, DP, NU)
    assert got == pytest.approx(want, rel=1e-7)


def test_fault_form_is_the_limit_of_wide_rectangles():
    y = np.array([-80.0, -35.0, 0.0, 65.0, 120.0])
    L = 1.0e8
    wide = rectangles_shear(0.0 * y, y, [[-L, A, 0.0, B], [0.0, C, L, D]], DP, NU)
    np.testing.assert_allclose(
        wide, offset_fault_shear(y, A, B, C, D, DP, NU), rtol=1e-9
    )


def test_symmetry_and_zero_throw():
    y = np.linspace(-200.0, 230.0, 37) + 0.123
    s = offset_fault_shear(y, A, B, C, D, DP, NU)
    # mirror x -> -x swaps the sides and flips sigma_xy
    np.testing.assert_allclose(offset_fault_shear(y, C, D, A, B, DP, NU), -s)
    # mirror y -> (A + D) - y swaps the sides too (and flips sigma_xy): both
    # mirrors together map the geometry onto itself, so s is even about (A + D)/2
    np.testing.assert_allclose(
        offset_fault_shear(A + D - y, A, B, C, D, DP, NU), s, rtol=1e-12, atol=1e-6
    )
    np.testing.assert_allclose(
        offset_fault_shear(y, A, B, A, B, DP, NU), 0.0, atol=1e-15 * abs(DP)
    )
    np.testing.assert_allclose(
        offset_fault_slip(y, A, B, A, B, DP, NU, MU), 0.0, atol=1e-15
    )
    # linear in dp: injection reverses it
    np.testing.assert_allclose(offset_fault_shear(y, A, B, C, D, -DP, NU), -s)


def test_dislocation_kernel_griffith_crack():
    """Slip -2 (1 - nu) S / mu sqrt(a^2 - y^2) carries -S on the crack."""
    S, a = 1.0e6, 1.0
    th = np.linspace(np.pi, 0.0, 4001)
    s = a * np.cos(th)
    slip = -2.0 * (1.0 - NU) * S / MU * np.sqrt(np.maximum(a * a - s * s, 0.0))
    y = np.array([-0.7, -0.2, 0.1, 0.5]) + 1.0e-7
    np.testing.assert_allclose(dislocation_shear(y, s, slip, NU, MU), -S, rtol=5e-4)


def test_frictionless_slip_cancels_the_stuck_shear():
    s = np.array([-1000.0, A, C, B, D, 1000.0])
    slip = offset_fault_slip(s, A, B, C, D, DP, NU, MU)
    y = np.array([-300.0, -70.0, -40.0, -30.0, 0.0, 60.0, 70.0, 95.0, 400.0])
    total = dislocation_shear(y, s, slip, NU, MU) + offset_fault_shear(
        y, A, B, C, D, DP, NU
    )
    np.testing.assert_allclose(total, 0.0, atol=1e-9 * abs(DP))
    # compact, plateau alpha |dp| (1 - 2 nu) throw / mu in the overlap, with
    # the lower (left) side moving down
    np.testing.assert_allclose(slip[[0, 1, 4, 5]], 0.0, atol=1e-15)
    assert slip[2] == pytest.approx(-abs(DP) * (1 - 2 * NU) * (C - A) / MU)
    assert slip[3] == pytest.approx(slip[2])
    with pytest.raises(ValueError):
        offset_fault_slip(s, A, B, C, D + 1.0, DP, NU, MU)


def test_slip_releases_energy():
    y = np.linspace(A - 10.0, D + 10.0, 200001)
    for dp in (DP, -DP):
        tau = offset_fault_shear(y, A, B, C, D, dp, NU)
        slip = offset_fault_slip(y, A, B, C, D, dp, NU, MU)
        ok = np.isfinite(tau)
        released = -0.5 * integrate.trapezoid(tau[ok] * slip[ok], y[ok])
        assert released > 0.0


def test_uniaxial_path_ratio_and_signs():
    ch = uniaxial_strain_change(-10.0e6, 0.25, 0.9)
    assert ch["xx"] > 0.0 and ch["yy"] == 0.0  # total horizontal less compressive
    assert ch["yy_eff"] == pytest.approx(-9.0e6)  # effective vertical: alpha dp
    assert ch["xx_eff"] / ch["yy_eff"] == pytest.approx(0.25 / 0.75)  # "about 1/3"
    assert ch["xx"] == pytest.approx(0.9 * 10.0e6 * 0.5 / 0.75)
    assert ch["xx_eff"] == pytest.approx(
        ch["xx"] + ch["yy_eff"]
    )  # sigma' = sigma + a p


def test_critical_change_is_on_the_coulomb_line():
    s0, p0, nu, ang, f, c = (-44.0e6, -62.0e6, 1.0e6), 30.0e6, 0.2, 60.0, 0.5, 0.5e6
    dp = critical_change_uniaxial(s0, p0, nu, ang, f, c)
    assert dp < 0.0

    def margin(d):
        th = np.radians(ang)
        t, n = np.array([np.cos(th), np.sin(th)]), np.array([-np.sin(th), np.cos(th)])
        sxx = s0[0] - (1 - 2 * nu) / (1 - nu) * d
        sig = np.array([[sxx, s0[2]], [s0[2], s0[1]]])
        return abs(t @ sig @ n) - (c - f * (n @ sig @ n + p0 + d))

    assert margin(dp) == pytest.approx(0.0, abs=1e-6)
    assert margin(0.0) < 0.0 and margin(0.999 * dp) < 0.0 < margin(1.001 * dp)


def test_forms_agree_with_the_published_geos_benchmark():
    """(J1) and (J2) against the dislocated-reservoir solution that GEOS's
    "stableVerticalFault" / "slippedVerticalFault" validations use
    (GEOS-DEV/GEOS, src/docs/sphinx/advancedExamples/validationStudies/
    faultMechanics/slippedVerticalFault/generate_analytical.py; Frigo,
    Castelletto, Cusini et al., J. Comput. Phys. 2026, Sec. 5.1.2, eqs. 48-51),
    written here in its own notation: left reservoir z in [-b, a], right
    reservoir z in [-a, b],

        t_T(z) = C/2 ln((z-a)^2 (z+a)^2 / ((z-b)^2 (z+b)^2)),
        C = (1 - 2 nu) alpha dp / (2 pi (1 - nu)),   A = G / (2 pi (1 - nu)),
        |g_T| = |C/A| * {b - a on |z| < a, b - |z| on a <= |z| < b, 0 beyond}.

    With the benchmark's own parameters (E = 14.95 GPa, nu = 0.15,
    K_grain = 71.19 GPa, dp = -25 MPa, a = 75 m, b = 150 m).  The two
    derivations are independent; they must agree to round-off, up to the
    sign convention of the traction (GEOS plots minus its fault traction)."""
    E, nu, k_grain = 14.95e9, 0.15, 7.119047619047619e10
    dp, a, b = -25.0e6, 75.0, 150.0
    G = E / (2.0 * (1.0 + nu))
    alpha = 1.0 - E / (3.0 * (1.0 - 2.0 * nu)) / k_grain
    z = np.linspace(-260.0, 260.0, 523) + 0.0371  # off the four corners
    c_geos = (1.0 - 2.0 * nu) * alpha * dp / (2.0 * np.pi * (1.0 - nu))
    a_geos = G / (2.0 * np.pi * (1.0 - nu))
    ratio = (z - a) ** 2 * (z + a) ** 2 / ((z - b) ** 2 * (z + b) ** 2)
    t_geos = c_geos / 2.0 * np.log(ratio)
    g_geos = np.abs(c_geos / a_geos) * np.clip(b - np.maximum(np.abs(z), a), 0.0, None)

    ours_t = offset_fault_shear(z, -b, a, -a, b, dp, nu, biot=alpha)
    ours_g = offset_fault_slip(z, -b, a, -a, b, dp, nu, G, biot=alpha)
    scale = np.max(np.abs(t_geos))
    sign = np.sign(ours_t[0] * t_geos[0])  # one convention for the whole fault
    np.testing.assert_allclose(ours_t, sign * t_geos, rtol=1e-10, atol=1e-12 * scale)
    np.testing.assert_allclose(np.abs(ours_g), g_geos, rtol=1e-12, atol=1e-18)
    # the benchmark's headline number: maximum slip (b - a) |C/A|
    assert np.max(np.abs(ours_g)) == pytest.approx(
        (1.0 - 2.0 * nu) * alpha * abs(dp) * (b - a) / G, rel=1e-12
    )
