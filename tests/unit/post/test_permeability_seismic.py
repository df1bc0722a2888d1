"""Aperture, cubic law, Oda's tensor and event size against hand computations
and closed forms."""

from __future__ import annotations

import math

import numpy as np
import pytest

from xfemslip.post.metrics import point_stretches
from xfemslip.post.permeability import ApertureLaw, oda_tensor, transmissivity
from xfemslip.post.seismic import (
    moment_magnitude,
    moment_per_length,
    shear_modulus,
    stress_drop,
)
from xfemslip.reference import closed_form as cf


def test_uniform_slip_dilates_by_slip_times_tan_psi_until_it_stops():
    """a0 = 0.1 mm, psi = 5 deg, dilation stops at 2 mm of slip: a uniform
    slip of 1 mm gives 0.1 + tan(5 deg) mm, 3 mm gives 0.1 + 2 tan(5 deg) mm,
    and the transmissivity is a^3 / 12."""
    law = ApertureLaw(initial_aperture=1e-4, dilation_angle=5.0, dilation_slip=2e-3)
    t5 = math.tan(math.radians(5.0))
    a = law.aperture([1e-3, -1e-3, 3e-3], -10e6, -10e6)
    np.testing.assert_allclose(
        a, [1e-4 + 1e-3 * t5, 1e-4 + 1e-3 * t5, 1e-4 + 2e-3 * t5]
    )
    np.testing.assert_allclose(transmissivity(a), a**3 / 12.0)
    # (0.1 + 0.0875) mm cubed over 12, by hand: 5.4932e-13 m^3
    assert transmissivity(a)[0] == pytest.approx(
        (1e-4 + 1e-3 * t5) ** 3 / 12, rel=1e-15
    )
    assert transmissivity(a)[0] == pytest.approx(5.4932e-13, rel=1e-4)


def test_normal_closure_is_the_hyperbola_relative_to_the_in_situ_state():
    """Bandis: closure V_m sigma / (K V_m + sigma); compressing from 10 to 20 MPa
    with V_m = 50 um, K = 1e11 Pa/m closes 50e-6 (20/(5+20) - 10/(5+10)) m;
    unloading to tension opens the faces by the mechanical opening."""
    law = ApertureLaw(initial_aperture=1e-4, max_closure=5e-5, normal_stiffness=1e11)
    a = law.aperture(0.0, -20e6, -10e6)
    expected = 1e-4 - 5e-5 * (20.0 / 25.0 - 10.0 / 15.0)
    assert a == pytest.approx(expected, rel=1e-14)
    assert law.aperture(0.0, -10e6, -10e6) == pytest.approx(1e-4, rel=1e-15)
    # open: no compression, plus a 20 um mechanical opening
    a_open = law.aperture(0.0, 0.0, -10e6, opening=2e-5)
    assert a_open == pytest.approx(1e-4 + 5e-5 * 10.0 / 15.0 + 2e-5, rel=1e-14)
    # the aperture stays above a0 - V_m however hard the compression
    assert law.aperture(0.0, -1e15, 0.0) > 1e-4 - 5e-5


@pytest.mark.parametrize("theta", [0.0, 30.0, 90.0, 135.0])
def test_oda_tensor_of_one_fracture_is_its_closed_form(theta):
    """a^3 L / (12 A) t t^T for a straight fracture of uniform aperture."""
    a, L, area = 2e-4, 0.6, 1.0
    t = np.array([math.cos(math.radians(theta)), math.sin(math.radians(theta))])
    s = np.linspace(0.0, L, 31)
    stretch = point_stretches(s, 0.0, L)
    k = oda_tensor([(stretch, np.tile(t, (s.size, 1)), np.full(s.size, a))], area)
    np.testing.assert_allclose(k, a**3 * L / (12 * area) * np.outer(t, t), rtol=1e-13)
    k_m = oda_tensor([], area, matrix_permeability=1e-18)
    np.testing.assert_array_equal(k_m, 1e-18 * np.eye(2))


def test_moment_and_stress_drop_of_the_slipping_crack():
    """The elliptical slip of a straight crack (closed_form.slip_profile):
    int s = (kappa + 1) pi a^2 dtau / (4 mu), so the crack-model stress drop
    recovers dtau, and Mw follows the IASPEI standard form."""
    E, nu, a = 5e9, 0.3, 0.3
    stress, psi, f = (-20e6, -40e6, 0.0), 45.0, 0.1
    dtau = abs(cf.driving_shear(stress, psi, f))  # 10 - 3 = 7 MPa
    assert dtau == pytest.approx(7e6)
    # Gauss points along the crack, as a fracture's contact points
    xg, wg = np.polynomial.legendre.leggauss(400)
    s = a * (xg + 1.0)
    slip = cf.slip_profile(s, a, E, nu, "plane_strain", stress, psi, f)
    mu = shear_modulus(E, nu)
    m0 = moment_per_length(mu, a * wg, slip)
    exact = (cf.kolosov(nu, "plane_strain") + 1) * math.pi * a * a * dtau / 4.0
    assert m0 == pytest.approx(exact, rel=1e-5)
    assert stress_drop(mu, nu, "plane_strain", a * wg, slip, 2 * a) == pytest.approx(
        dtau, rel=1e-5
    )
    # W = 100 m: M0 = 100 m0; Mw = 2/3 (log10 M0 - 9.1)
    assert moment_magnitude(100.0 * m0) == pytest.approx(
        2.0 / 3.0 * (math.log10(100.0 * m0) - 9.1)
    )
    assert moment_magnitude(1.0e9 * 10**9.1 / 1e9) == pytest.approx(0.0)
    assert moment_magnitude(0.0) == -math.inf
    assert math.isnan(stress_drop(mu, nu, "plane_strain", a * wg, slip, 0.0))
    assert math.isnan(stress_drop(mu, nu, "plane_strain", a * wg, 0.0 * slip, 2 * a))
