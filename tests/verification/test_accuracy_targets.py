"""The accuracy targets on the frictional inclined crack.

The problem (xfemslip.verify.problems): a straight crack of half-length a = 0.5 m at
30 deg in a 2 m box whose edges carry the exact displacements of the cracked
infinite plane (closed_form.displacement), far field xx = -20 MPa,
yy = -40 MPa, f = 0.1, default tip treatment, kn = kt = 100 E / h.  With the
exact boundary data the closed form is the exact solution of the box, so the
errors below are discretisation errors only.

Targets: relative L2 slip error <= 1 % at h = a/20; K_II (interaction
integral) within 2 % at h = a/20; observed order of the slip error >= 1
between a/10 and a/40.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from xfemslip.post.jintegral import stress_intensity_factors
from xfemslip.reference import closed_form as cf
from xfemslip.verify import problems as V

pytestmark = pytest.mark.verification

INCLINED = V.PROBLEMS[0]  # inclined-30


@pytest.fixture(scope="module")
def a20(tmp_path_factory):
    """The inclined crack solved at h = a/20 (80 x 80 cells, about 2 s)."""
    folder = tmp_path_factory.mktemp("a20")
    path = V.write_case(folder, 80, INCLINED, None, V.PENALTY)
    return V.solve_case(path)


def test_slip_error_at_a_over_20(a20):
    row = V.measure(a20, INCLINED, 20)
    # target 1 %; measured 0.42 % (docs/verification.md)
    assert row.slip_error <= V.SLIP_TARGET


def test_k_ii_at_a_over_20_at_both_tips(a20):
    k_exact = cf.k_ii(V.STRESS, INCLINED.psi, V.HALF_LENGTH, INCLINED.friction)
    sifs = stress_intensity_factors(a20.model, a20.u, a20.contact)
    assert len(sifs) == 2
    for t in sifs:
        # target 2 %; measured 0.29 % with the default domain (3 tip cells)
        assert abs(t.k_ii - k_exact) <= V.KII_TARGET * abs(k_exact)
        # the crack is closed: K_I = 0 exactly; measured |K_I| = 1.8 % of K_II,
        # from the penalty traction oscillation near the tips (face term)
        assert abs(t.k_i) <= 0.05 * abs(k_exact)


def test_k_ii_does_not_depend_on_the_domain(a20):
    small = stress_intensity_factors(a20.model, a20.u, a20.contact, radius_cells=3)
    large = stress_intensity_factors(a20.model, a20.u, a20.contact, radius_cells=6)
    for s, g in zip(small, large, strict=True):
        assert s.end == g.end
        # path independence of the interaction integral up to discretisation
        # error: measured 0.3 %
        assert g.k_ii == pytest.approx(s.k_ii, rel=0.01)
        assert g.radius == pytest.approx(2 * s.radius)


def test_sign_of_k_ii_follows_the_slip(tmp_path):
    # at 150 deg the shear traction t.s.n is +8.66 MPa: the + face moves
    # along +t, slip > 0 and K_II > 0 (30 deg: both negative, see above)
    prob = V.Problem("inclined-150", 150.0)
    assert prob.driving_shear() > 0 > INCLINED.driving_shear()
    solved = V.solve_case(V.write_case(tmp_path, 40, prob, None, V.PENALTY))
    slip = V.fracture_arrays(solved)["slip"]
    sifs = stress_intensity_factors(solved.model, solved.u, solved.contact)
    assert np.all(slip > 0)
    k_exact = cf.k_ii(V.STRESS, 150.0, V.HALF_LENGTH, prob.friction)
    for t in sifs:
        assert t.k_ii > 0
        assert t.k_ii == pytest.approx(k_exact, rel=0.02)


def test_stuck_crack_has_no_k(tmp_path):
    # 80 deg with f = 0.3 lies outside the slip window: every point sticks,
    # the exact solution is the uniform field, K_I = K_II = 0.  Relative to the
    # frictionless K_II at this angle, measured 0.8 % (penalty elastic slip).
    prob = next(p for p in V.PROBLEMS if p.kind == "stick")
    assert prob.driving_shear() == 0.0
    row = V.run_problem(prob, 10, None, V.PENALTY, tmp_path)
    assert row.extra["slipping_points"] == 0
    assert row.kii_error < 0.02
    assert row.ki_ratio < 0.1


@pytest.mark.slow
@pytest.mark.parametrize("plane", ["plane_strain", "plane_stress"])
def test_cohesion_and_plane_stress_at_a_over_20(tmp_path, plane):
    prob = V.Problem("cohesion", 30.0, friction=0.1, cohesion=2.0e6, plane=plane)
    row = V.run_problem(prob, 20, None, V.PENALTY, tmp_path)
    assert row.slip_error <= V.SLIP_TARGET
    assert row.kii_error <= V.KII_TARGET


# Measured (default tip "branch" with its geometric radius, contact patches,
# kn = 100 E / h): slip L2 error 0.796 % (a/10), 0.414 % (a/20), 0.156 % (a/40):
# order 1.18 over a/10..a/40 (branch radius capped at 6 tip cells).  With the
# former fixed 4-cell branch radius and
# pointwise contact it was 0.802 / 0.421 / 0.294 %, order 0.72 (the error
# levelled off near 0.3 %).


@pytest.mark.slow
def test_observed_order_of_the_slip_error(tmp_path):
    errors = {
        aoh: V.run_problem(INCLINED, aoh, None, V.PENALTY, tmp_path).slip_error
        for aoh in (10, 40)
    }
    order = math.log(errors[10] / errors[40]) / math.log(4.0)
    assert order >= V.ORDER_TARGET
