"""Inclined frictional crack in an infinite plane, with exact boundary data.

Setup (the same as the acceptance check ``check_inclined_crack.py``): a 2 m x 2 m
box centred near the origin, a straight crack of half-length a = 0.5 m at angle
psi through (0.0123, -0.0077), remote stress (xx, yy, xy) = (-20, -40, 0) MPa,
E = 5 GPa, nu = 0.3.  Every edge gets, through a boundary CSV file, the exact
displacement of the cracked infinite plane (uniform strain + Westergaard
mode-II perturbation of the slipping crack, ``closed_form.displacement``), so
the only error left is the discretisation (and the penalty kn = kt = 100 E/h).
The slip along the crack is compared with Phan et al. (2003)'s closed form
``closed_form.slip_profile`` in the relative L2 norm along the arc length.

Measured relative L2 slip errors (branch tips, the default; contact patches of
1.5 cells, the default; h = 2 m / n, so n = 64 is h = a/16; the table was
measured with pointwise contact, which gives the same slip to +-0.01 %):

===============================================  ======  ======  =======
psi, f, c, plane                                 n = 32  n = 64  n = 128
===============================================  ======  ======  =======
30 deg, f = 0.1, c = 0, plane strain             1.01 %  0.59 %  0.31 %
60 deg, f = 0.1, c = 0, plane strain                     0.60 %
45 deg, f = 0.2, c = 1 MPa, plane strain                 0.50 %
30 deg, f = 0 (frictionless), plane strain               0.60 %
15 deg, f = 0.1, c = 0, plane strain                     0.54 %
30 deg, f = 0.1, c = 0, plane stress                     0.56 %
120 deg, f = 0.2, c = 0, plane stress                    0.53 %
135 deg, f = 0.1, c = 2 MPa, plane strain                0.56 %
150 deg, f = 0 (frictionless), plane stress              0.52 %
===============================================  ======  ======  =======

With the geometric branch radius (0.1 x length, within 4-6 tip cells) the
psi = 30 row is 0.99 / 0.59 / 0.19 % and the least-squares order over the
three meshes 1.20 (it was 0.84 with a fixed 4-cell radius), see
``test_slip_error_converges``.  The 3 % limit of the brief is the acceptance
limit; the measured errors are far below it, so only a regression that makes
the error about five times worse is caught by the fast tests -- the
convergence test is the sharper one.  Stuck cracks (80 deg with f = 0.3,
45 deg with f = 0.6) carry max |slip| 2e-7 to 7e-7 m, the elastic penalty
jump tau / kt.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests.support.harness import SLIP, STICK, read_result
from xfemslip.case import load_case
from xfemslip.reference import closed_form as cf
from xfemslip.simulation import run_case
from xfemslip.verify import problems as V

pytestmark = pytest.mark.verification

# the box, crack and stress of xfemslip.verify.problems, whose case writer runs them
HALF = V.HALF_BOX  # half-width of the box [m]
A = V.HALF_LENGTH  # crack half-length [m]
CENTER = V.CENTER  # off the mesh lines on purpose [m]
STRESS = V.STRESS  # remote stress, tension positive [Pa]
E, NU = V.E, V.NU
PENALTY = 100.0  # kn = kt = PENALTY * E / h
LIMIT = 0.03  # allowed relative L2 slip error at h = a/16 (n = 64)


def run_inclined(
    folder: Path,
    *,
    psi,
    friction,
    cohesion=0.0,
    plane="plane_strain",
    n=64,
    steps=1,
    penalty=PENALTY,
    patch=None,
):
    """Write the case and the four boundary CSV files into folder, run, read the result.

    The case is ``xfemslip.verify.problems``'s (the same box, crack and exact edges).
    Returns (s, slip, state, exact slip at s).
    """
    prob = V.Problem("inclined", psi, friction, cohesion, plane)
    solver = None if patch is None else {"contact_patch": patch}
    case = V.write_case(folder, n, prob, None, penalty, steps=steps, solver=solver)
    run_case(load_case(case), folder / "out")
    fr = read_result(folder / "out" / "result.h5").fr
    exact = cf.slip_profile(fr["s"], A, E, NU, plane, STRESS, psi, friction, cohesion)
    run_inclined.fracture = fr  # the whole fracture record, for traction checks
    return fr["s"], fr["slip"], fr["state"], exact


def _check_slipping(s, slip, state, exact, limit=LIMIT):
    assert np.any(exact), "test premise: the closed form must slip"
    err = cf.relative_l2(s, slip, exact)
    assert err <= limit, f"relative L2 slip error {100 * err:.2f}% > {100 * limit:.1f}%"
    # the sign of the slip follows the driving shear (output-format.md sign convention)
    inner = np.abs(s - A) < 0.8 * A
    assert np.all(np.sign(slip[inner]) == np.sign(exact[inner]))
    # away from the tips every point is sliding on the Coulomb bound
    assert np.mean(state[inner] == SLIP) >= 0.95
    return err


@pytest.mark.parametrize(
    ("psi", "friction", "cohesion"),
    [(30.0, 0.1, 0.0), (60.0, 0.1, 0.0), (45.0, 0.2, 1.0e6)],
    ids=["psi30-f0.1", "psi60-f0.1", "psi45-f0.2-c1MPa"],
)
def test_slip_matches_closed_form(tmp_path, psi, friction, cohesion):
    """Relative L2 slip error <= 3 % at h = a/16 (measured 0.50 - 0.60 %)."""
    s, slip, state, exact = run_inclined(
        tmp_path, psi=psi, friction=friction, cohesion=cohesion
    )
    _check_slipping(s, slip, state, exact)


def test_frictionless_crack_is_pure_mode_two(tmp_path):
    """f = 0: the whole remote shear t.sigma.n drives the slip (measured 0.60 %)."""
    psi = 30.0
    _, tau = cf.crack_tractions(STRESS, psi)
    assert cf.driving_shear(STRESS, psi, 0.0) == pytest.approx(tau)
    s, slip, state, exact = run_inclined(tmp_path, psi=psi, friction=0.0)
    _check_slipping(s, slip, state, exact)
    # peak slip of the mode-II crack: 4 (1 - nu^2) / E * tau * a at the centre
    peak = 4 * (1 - NU**2) / E * tau * A
    assert np.max(np.abs(slip)) == pytest.approx(abs(peak), rel=0.03)


@pytest.mark.parametrize(
    ("psi", "friction"),
    [(80.0, 0.3), pytest.param(45.0, 0.6, marks=pytest.mark.slow)],
)
def test_crack_outside_slip_window_sticks(tmp_path, psi, friction):
    """80 deg is 10 deg from sigma1 (vertical); with f = 0.3, |tau| < f |sigma_n|, so
    the closed form has no slip: every point must STICK with ~0 slip.  (45 deg with
    f = 0.6: the most critically oriented plane, held by a high friction.)"""
    t_n, t_t = cf.crack_tractions(STRESS, psi)
    assert abs(t_t) < 0.95 * friction * abs(t_n)  # premise: inside the cone
    s, slip, state, exact = run_inclined(tmp_path, psi=psi, friction=friction)
    assert not np.any(exact)
    assert np.all(state == STICK)
    # the stuck faces carry only the elastic penalty jump tau / kt ~ 1e-7 m
    kt = PENALTY * E / (2 * HALF / 64)
    assert np.max(np.abs(slip)) <= 2 * abs(t_t) / kt
    # ... which is < 1e-3 of the slip the same crack would have without friction
    frictionless_peak = 4 * (1 - NU**2) / E * abs(t_t) * A
    assert np.max(np.abs(slip)) < 1e-3 * frictionless_peak


@pytest.mark.slow
@pytest.mark.parametrize(
    ("psi", "friction", "cohesion", "plane"),
    [
        (15.0, 0.1, 0.0, "plane_strain"),
        (30.0, 0.1, 0.0, "plane_stress"),
        (120.0, 0.2, 0.0, "plane_stress"),
        (135.0, 0.1, 2.0e6, "plane_strain"),
        (150.0, 0.0, 0.0, "plane_stress"),
    ],
)
def test_slip_matches_closed_form_more(tmp_path, psi, friction, cohesion, plane):
    """More angles, friction, cohesion, plane stress; n = 64 (measured 0.52-0.56 %)."""
    s, slip, state, exact = run_inclined(
        tmp_path, psi=psi, friction=friction, cohesion=cohesion, plane=plane
    )
    _check_slipping(s, slip, state, exact)


@pytest.mark.slow
def test_slip_error_converges(tmp_path):
    """Observed order of the L2 slip error over n = 32, 64, 128 is >= 1.

    The order is the least-squares slope of log(error) against log(h) over the
    three meshes: measured 1.20, errors 0.99 %, 0.59 %, 0.19 %.  It was 0.84
    (1.01 / 0.59 / 0.31 %) when the branch radius was a fixed 4 tip cells: a
    radius that shrinks with h leaves the near-tip error at a fixed share
    (Laborde et al. 2005), hence the geometric radius of geometry.py.
    """
    ns = np.array([32, 64, 128])
    errors = []
    for n in ns:
        s, slip, _, exact = run_inclined(
            tmp_path / f"n{n}", psi=30.0, friction=0.1, n=int(n)
        )
        errors.append(cf.relative_l2(s, slip, exact))
    order = np.polyfit(np.log(2.0 / ns), np.log(errors), 1)[0]  # error ~ h^order
    assert errors[1] <= LIMIT
    assert errors[0] > errors[1] > errors[2], f"errors {errors} do not decrease"
    assert order >= 1.0, f"errors {errors}, observed order {order:.2f}"


def test_stiff_penalty_converges_with_the_line_search(tmp_path):
    """kn h / E = 1e6: the slip is as accurate as with a moderate penalty
    (measured 0.60 %; 0.59 % at kn h / E = 100) and every point slides.

    With the pointwise penalty this case ping-ponged between open and slip (28
    iterations with the line search) and about 30 % of the points reported
    OPEN under 30 MPa of compression; on contact patches it takes 2.
    """
    s, slip, state, exact = run_inclined(
        tmp_path, psi=30.0, friction=0.1, n=64, penalty=1.0e6
    )
    err = cf.relative_l2(s, slip, exact)
    assert err < 0.01, f"relative L2 slip error {100 * err:.2f}%"
    inner = np.abs(s - A) < 0.8 * A
    assert np.all(np.sign(slip[inner]) == np.sign(exact[inner]))
    assert np.all(state == SLIP)


def _oscillation(s, traction):
    """max |t_N - mean| / |mean| over the inner 90 % of the crack."""
    inner = np.abs(s - A) < 0.9 * A
    t = traction[inner]
    return float(np.max(np.abs(t - t.mean())) / abs(t.mean()))


@pytest.mark.parametrize(
    "psi, friction", [(30.0, 0.1), (80.0, 0.3)], ids=["slipping", "stuck"]
)
def test_normal_traction_is_uniform_on_contact_patches(tmp_path, psi, friction):
    """The closed form's normal traction is uniform, n.sigma.n, along the crack.

    Pointwise penalty XFEM oscillates from Gauss point to Gauss point (the LBB
    problem of contact on an enriched interface): measured max deviation over
    mean 16.7 % (slipping) and 3.0 % (stuck) at n = 64.  On 1.5-cell contact
    patches (the default): 0.15 % and 0.23 %, and the mean is n.sigma.n.
    """
    t_n, _ = cf.crack_tractions(STRESS, psi)
    s, *_ = run_inclined(tmp_path / "patch", psi=psi, friction=friction)
    patch = run_inclined.fracture["normal_traction"]
    s0, *_ = run_inclined(tmp_path / "point", psi=psi, friction=friction, patch=0.0)
    point = run_inclined.fracture["normal_traction"]
    assert _oscillation(s, patch) <= 0.01
    assert _oscillation(s0, point) >= 5 * _oscillation(s, patch)  # before/after
    inner = np.abs(s - A) < 0.9 * A
    assert np.mean(patch[inner]) == pytest.approx(t_n, rel=0.005)
