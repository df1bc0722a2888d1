"""Which fracture orientations slip: the Mohr-Coulomb slip window.

``cases/reservoir_depletion.toml`` (far field xx = -20 MPa, yy = -40 MPa,
central 0.6 m fracture, no cohesion) is turned to several angles theta.  A
plane at angle beta to sigma_1 slips when |tau| > f |sigma_n|, i.e. for beta
inside the window of ``closed_form.slip_window`` (Jaeger et al. 2007):

- f = 0.1: beta in (5.83, 78.46) deg;
- f = 0.3: beta in (21.4, 51.9) deg.

sigma_1 is vertical here, so beta = |theta - 90| folded into [0, 90].
Inside the window every contact point must be SLIP; outside, none may be.
(With the boundaries loaded by the same uniform stress, the uncracked field
satisfies the contact conditions of a stuck fracture, so outside the window the
exact solution has no slip at all, no tip concentration; inside, the whole
fracture slips.)
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

from tests.support.harness import SLIP, read_result
from xfemslip.case import build, load_case
from xfemslip.reference import closed_form as cf
from xfemslip.simulation import run_case

pytestmark = pytest.mark.verification

CASE = Path(__file__).resolve().parents[2] / "cases" / "reservoir_depletion.toml"
MARGIN = 4.0  # deg kept clear of the window edges (fast tests)
SWEEP_MARGIN = 0.5  # deg, the 1-degree sweep (see test_slip_window_sweep)


def base_case() -> dict:
    return tomllib.loads(CASE.read_text())


def window_of(doc: dict, friction: float):
    s = doc["loading"]["stress"]
    sigma1, sigma3, dir1 = cf.principal((s["xx"], s["yy"], s.get("xy", 0.0)))
    cohesion = doc["fractures"][0].get("cohesion", 0.0)
    return cf.slip_window(sigma1, sigma3, friction, cohesion), dir1


def slip_share(folder: Path, theta: float, friction: float, elements=None) -> tuple:
    """Run the reservoir case with the fracture at theta [deg]: (SLIP share, points)."""
    doc = base_case()
    frac = doc["fractures"][0]
    frac.pop("points", None)
    frac.update(angle=float(theta), friction=float(friction))
    if elements is not None:
        doc["mesh"]["elements"] = list(elements)
    doc["output"] = {"formats": ["h5"]}
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"case_{theta:g}.toml"
    path.write_text(build.case_text(doc))
    out = folder / f"out_{theta:g}"
    run_case(load_case(path), out)
    state = read_result(out / "result.h5").fr["state"]
    return float(np.mean(state == SLIP)), state.size


def test_window_closed_form():
    """The closed form itself: window edges are where |tau| = f |sigma_n|."""
    doc = base_case()
    stress = tuple(doc["loading"]["stress"][k] for k in ("xx", "yy", "xy"))
    for friction in (0.1, 0.2, 0.3):
        (lo, hi), dir1 = window_of(doc, friction)
        assert dir1 == pytest.approx(90.0)
        for beta in (lo, hi):
            t_n, t_t = cf.crack_tractions(stress, dir1 + beta)
            assert abs(t_t) == pytest.approx(friction * abs(t_n), rel=1e-12)
        mid = 0.5 * (lo + hi)
        assert cf.driving_shear(stress, dir1 + mid, friction) != 0.0
        assert cf.driving_shear(stress, dir1 + 0.5 * lo, friction) == 0.0
    assert window_of(doc, 0.1)[0] == pytest.approx((5.83, 78.46), abs=0.01)
    # f = 0.6: S = 3 sin(atan 0.6) > 1, no orientation slips (cf. the inclined-crack
    # stick test at 45 deg with f = 0.6)
    assert window_of(doc, 0.6)[0] is None


@pytest.mark.parametrize(
    ("friction", "theta"),
    [
        (0.1, 0.0),
        (0.1, 45.0),
        (0.1, 90.0),
        (0.1, 160.0),
        (0.3, 20.0),
        (0.3, 60.0),
        (0.3, 120.0),
        (0.3, 170.0),
    ],
)
def test_slips_inside_window_only(tmp_path, friction, theta):
    (lo, hi), dir1 = window_of(base_case(), friction)
    beta = cf.angle_to_sigma1(theta, dir1)
    assert min(abs(beta - lo), abs(beta - hi)) > MARGIN, (
        "test premise: clear of the edges"
    )
    share, n = slip_share(tmp_path, theta, friction)
    if lo < beta < hi:
        assert share == 1.0, (
            f"beta {beta:.1f} inside ({lo:.1f}, {hi:.1f}): {share:.0%} slip"
        )
    else:
        assert share == 0.0, (
            f"beta {beta:.1f} outside ({lo:.1f}, {hi:.1f}): {share:.0%} slip"
        )


@pytest.mark.slow
@pytest.mark.parametrize("friction", [0.1, 0.3])
def test_slip_window_sweep(tmp_path, friction):
    """1-degree sweep 0..180 on a 30 x 30 mesh: every angle more than
    SWEEP_MARGIN from a window edge is classified right at every contact point
    (all SLIP inside, none outside).  The issue's target is 2 deg.

    With the pointwise penalty this needed a 3 deg margin and 80 % inside:
    theta = 93 (beta 3.0, 2.8 deg outside the f = 0.1 window) had 1 of 36
    points slipping near a tip, where the oscillating penalty tractions
    deviated (p_N 55 % of sigma_n).  The patch projection (contact.py) removed
    the oscillation; measured on 50 x 50 meshes, orientations 0.25 deg from
    either edge of the f = 0.1 and f = 0.3 windows are classified right.
    """
    (lo, hi), dir1 = window_of(base_case(), friction)
    wrong = []
    checked = 0
    for theta in range(0, 181):
        beta = cf.angle_to_sigma1(theta, dir1)
        if min(abs(beta - lo), abs(beta - hi)) <= SWEEP_MARGIN:
            continue
        share, _ = slip_share(tmp_path, theta, friction, elements=(30, 30))
        checked += 1
        inside = lo < beta < hi
        if (inside and share < 1.0) or (not inside and share > 0.0):
            wrong.append(
                f"theta {theta} (beta {beta:.1f}): {share:.0%} slip, "
                f"expected {'all' if inside else 'none'}"
            )
    assert checked > 140
    assert not wrong, "; ".join(wrong)
