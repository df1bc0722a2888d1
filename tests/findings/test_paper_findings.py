"""The seed paper's findings (Cao et al. 2020, Section 4) on its three studies,
run from the shipped sweep files ``cases/sweeps/*.toml`` (base case
``cases/reservoir_depletion.toml``: sigma_1 = 40 MPa vertical, sigma_3 = 20 MPa,
a 0.6 m fracture, E = 5 GPa, f = 0.1).

The closed-form references (``xfemslip.reference.closed_form``) are the Mohr-Coulomb
slip window and the excess shear Delta tau = |tau| - f |sigma_n| that drives
the slip of a crack in an infinite plane (slip proportional to Delta tau / E').
The model is a 1 m box, not an infinite plane, so magnitudes are compared as
ratios with a stated tolerance.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from xfemslip.reference.closed_form import (
    angle_to_sigma1,
    crack_tractions,
    driving_shear,
    principal,
    slip_window,
)
from xfemslip.studies.run import run_sweep
from xfemslip.studies.sweep import load_sweep

ROOT = Path(__file__).resolve().parents[2]
STRESS = (-20.0e6, -40.0e6, 0.0)  # the base case's loading.stress [Pa]
NO_SLIP = 1e-3  # "no slip": max |slip| below this fraction of the 45-degree slip


@pytest.fixture(scope="module")
def studies(tmp_path_factory):
    """Each study's rows by its varied value: {study: {value: metrics}}."""
    out = tmp_path_factory.mktemp("studies")
    found = {}
    for stem in ("young_modulus", "fracture_angle", "friction"):
        sweep = load_sweep(ROOT / "cases" / "sweeps" / f"{stem}.toml")
        rows = run_sweep(sweep, out / stem, jobs=1)
        assert all(r.status == "ok" and r.metrics["converged"] for r in rows), rows
        found[stem] = {r.params[0][1]: r.metrics for r in rows}
    return found


def test_base_case_is_the_papers(studies):
    base = load_sweep(ROOT / "cases" / "sweeps" / "young_modulus.toml")
    assert base.base_path.resolve() == (ROOT / "cases" / "reservoir_depletion.toml")
    spec = base.cases[0].spec
    assert spec.loading.stress == STRESS
    assert spec.fractures[0].friction == 0.1


def test_slip_decreases_as_young_modulus_increases(studies):
    rows = studies["young_modulus"]
    slips = [rows[E]["max_abs_slip_m"] for E in (5e9, 20e9, 80e9)]
    assert slips[0] > slips[1] > slips[2] > 0.0
    # Stress-driven slip scales like 1/E (Phan et al. 2003): 4x stiffer, about
    # 4x less slip.  The jump is the crack's in the bulk under the traction
    # drop, ~ 1/E; what slid is the jump less the elastic give of the penalty
    # springs (k_T = 5e12 Pa/m), the same at every E, so its ratio is 4 or a
    # little above.
    assert slips[0] / slips[1] == pytest.approx(4.0, rel=0.1)
    assert slips[1] / slips[2] == pytest.approx(4.0, rel=0.1)
    # the stress state alone decides where it slips: all points, every E
    assert all(rows[E]["slip_share"] == 1.0 for E in rows)


def test_no_slip_at_0_and_90_degrees(studies):
    rows = studies["fracture_angle"]
    reference = rows[45.0]["max_abs_slip_m"]
    for angle in (0.0, 90.0):
        assert rows[angle]["slip_share"] == 0.0
        assert rows[angle]["slip_length_m"] == 0.0
        assert rows[angle]["max_abs_slip_m"] < NO_SLIP * reference
        # closed form: a principal plane carries no shear
        assert driving_shear(STRESS, angle, 0.1) == 0.0


def test_slip_at_27_45_63_largest_near_45_minus_phi_over_2(studies):
    rows = studies["fracture_angle"]
    slipping = (27.0, 45.0, 63.0)
    s1, s3, dir1 = principal(STRESS)
    lo, hi = slip_window(s1, s3, 0.1)
    for angle in slipping:
        assert lo < angle_to_sigma1(angle, dir1) < hi  # inside the window
        assert rows[angle]["slip_share"] == 1.0
        assert rows[angle]["slip_length_m"] == pytest.approx(0.6, rel=1e-9)
    slips = {a: rows[a]["max_abs_slip_m"] for a in slipping}
    # the most critical plane is at 45 - phi/2 from sigma_1 (Jaeger et al.):
    # of the three, the one closest to it slips most, as the closed form says
    critical = 45.0 - math.degrees(math.atan(0.1)) / 2.0
    closest = min(slipping, key=lambda a: abs(angle_to_sigma1(a, dir1) - critical))
    assert closest == 45.0
    assert max(slips, key=slips.get) == closest
    assert max(slipping, key=lambda a: abs(driving_shear(STRESS, a, 0.1))) == closest
    # and the slip follows the excess shear: ratios to 45 degrees within 6 %
    for angle in (27.0, 63.0):
        expected = driving_shear(STRESS, angle, 0.1) / driving_shear(STRESS, 45.0, 0.1)
        assert slips[angle] / slips[45.0] == pytest.approx(expected, rel=0.06)


def test_slip_shrinks_as_friction_grows_and_vanishes_at_06(studies):
    rows = studies["friction"]
    slips = [rows[f]["max_abs_slip_m"] for f in (0.1, 0.3, 0.6)]
    assert slips[0] > slips[1] > slips[2]
    # f = 0.6: the 45-degree plane is outside the slip window (none exists:
    # S = 3 sin(atan 0.6) > 1), so nothing slips
    assert slip_window(40e6, 20e6, 0.6) is None
    assert rows[0.6]["slip_share"] == 0.0
    assert rows[0.6]["slip_length_m"] == 0.0
    # what is left is the elastic give of the stuck penalty spring, |tau| / k_T
    # (10 MPa / 5e12 Pa/m = 2 um; the contact tractions vary along the
    # fracture, hence the factor 1.5), 1/1000 of the slip at f = 0.1
    _, tau = crack_tractions(STRESS, 45.0)
    assert slips[2] < 1.5 * abs(tau) / 5.0e12
    assert slips[2] < 2 * NO_SLIP * slips[0]
    # f = 0.3 still slips, driven by Delta tau = 10 - 0.3 * 30 = 1 MPa against
    # 7 MPa at f = 0.1: about 1/7 of the slip
    assert rows[0.3]["slip_share"] > 0.5
    expected = driving_shear(STRESS, 45.0, 0.3) / driving_shear(STRESS, 45.0, 0.1)
    assert expected == pytest.approx(1.0 / 7.0)
    assert slips[1] / slips[0] == pytest.approx(expected, rel=0.15)


@pytest.mark.slow
def test_finer_angle_sweep_peaks_at_45_minus_phi_over_2(tmp_path):
    """Angles 0..90 by 3 degrees: every point slips inside the closed-form
    window and none outside (away from its edges by more than 0.5 degrees,
    the margin of the slip-window sweep test), and the largest slip within
    3 degrees of the critical orientation 90 - (45 - phi/2) = 47.9 degrees
    from +x."""
    base = (ROOT / "cases" / "reservoir_depletion.toml").as_posix()
    sweep = tmp_path / "angles.toml"
    sweep.write_text(
        f'base = "{base}"\n[vary]\n'
        '"fractures[0].angle" = { start = 0.0, stop = 90.0, step = 3.0 }\n'
    )
    rows = run_sweep(load_sweep(sweep), tmp_path / "out", jobs=1)
    slips = {r.params[0][1]: r.metrics for r in rows}
    s1, s3, dir1 = principal(STRESS)
    lo, hi = slip_window(s1, s3, 0.1)
    for angle, metrics in slips.items():
        beta = angle_to_sigma1(angle, dir1)
        if min(abs(beta - lo), abs(beta - hi)) > 0.5:
            expected = 1.0 if lo < beta < hi else 0.0
            assert metrics["slip_share"] == expected, angle
    peak = max(slips, key=lambda a: slips[a]["max_abs_slip_m"])
    critical = 90.0 - (45.0 - math.degrees(math.atan(0.1)) / 2.0)
    assert abs(peak - critical) <= 3.0
