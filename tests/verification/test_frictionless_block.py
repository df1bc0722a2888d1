"""A block fully cut by a horizontal fault, sheared under normal compression.

Unit square, fault y = 0.53 from the left edge to the right edge (mid-element,
so no enrichment is dropped), bottom edge fixed, top edge displaced
tangentially by ux = d with the normal traction sigma_yy = -10 MPa in its free
component (``top = { ux = d, traction = true }``), left and right edges free.

Once the fault slides, the Coulomb law holds with equality at every contact
point: |tau| = f |sigma_n| (rel 1e-6), tau and the slip point the way the
top block is dragged (+x; t = +x, n = +y, so the + side is the top block).
The free side edges let the top block tilt, so sigma_n varies along the
fault (and the left end may open), but the vertical equilibrium of the top
block is exact: the integral of sigma_n over the fault equals the load on the
top edge, -10 MN/m (the rigid vertical translation of the top block is an
admissible virtual displacement of the discrete problem).  f = 0 (the
"frictionless block") transmits no shear at all.

Measured (10 x 10, d = 1 cm): f = 0.3: 39 SLIP + 1 OPEN point, max
| |tau| - f |sigma_n| | = 0 to round-off, integral of sigma_n -10.000 MN/m
(1e-9 rel), slip 5.2 - 6.5 mm, 6 Newton iterations.  f = 0.6 (d = 2 cm): the
overturning couple lifts the left 0.4 m of the fault (OPEN; a rigid
no-tension base would open 0.34 m), the rest slides on the bound, 11
iterations.

There is no closed form for the slip itself with free side edges (the
springs-in-series formula of the house style assumes simple shear), so the
slip is only checked for sign and bound (0 < slip < d).
"""

from __future__ import annotations

import numpy as np
import pytest

from tests.support.harness import OPEN, SLIP, STICK, case_text, run_text

pytestmark = pytest.mark.verification

Y0 = 0.53  # fault height [m]
PRESSURE = 10.0e6  # normal compression on the top edge [Pa]
D = 1.0e-2  # tangential displacement of the top edge [m]


def gauss_weights(s, n_elements):
    """Weights of the interface points: Gauss-Legendre on each element-wide piece.

    Checks that the output points are those Gauss points (the premise of an
    exact resultant); returns the weights (K,) [m].
    """
    per_piece = s.size // n_elements
    assert per_piece * n_elements == s.size
    xi, w = np.polynomial.legendre.leggauss(per_piece)
    h = 1.0 / n_elements
    left = np.repeat(np.arange(n_elements) * h, per_piece)
    np.testing.assert_allclose(
        s, left + np.tile(0.5 * h * (1.0 + xi), n_elements), rtol=0, atol=1e-12
    )
    return np.tile(0.5 * h * w, n_elements)


def run_block(tmp_path, friction, d=D, n=10, steps=1):
    fault = dict(
        points=[[0.0, Y0], [1.0, Y0]],
        friction=friction,
        cohesion=0.0,
        kn=5.0e12,
        kt=5.0e12,
    )
    boundary = {
        "bottom": {"ux": 0.0, "uy": 0.0},
        "top": {"ux": d, "traction": True},
        "left": "free",
        "right": "free",
    }
    text = case_text(
        elements=(n, n),
        fractures=[fault],
        boundary=boundary,
        stress=(0.0, -PRESSURE, 0.0),
        steps=steps,
    )
    return run_text(text, tmp_path)


@pytest.mark.parametrize(
    ("friction", "d", "steps"),
    [(0.3, D, 1), (0.3, D, 4), (0.6, 2 * D, 1), (0.0, D, 1)],
    ids=["f0.3", "f0.3-4steps", "f0.6", "frictionless"],
)
def test_sliding_fault_is_on_the_coulomb_bound(tmp_path, friction, d, steps):
    r = run_block(tmp_path, friction, d=d, steps=steps)
    fr = r.fr
    pn, pt, state, slip = (
        fr[k] for k in ("normal_traction", "shear_traction", "state", "slip")
    )
    assert not np.any(state == STICK)
    assert np.mean(state == SLIP) >= (0.9 if friction < 0.5 else 0.5)
    # Coulomb with equality, point by point
    bound = friction * np.abs(pn)
    assert np.max(np.abs(np.abs(pt) - bound)) <= 1e-6 * max(np.max(bound), PRESSURE)
    np.testing.assert_array_equal(pn[state == OPEN], 0.0)
    sliding = state == SLIP
    assert np.all(slip[sliding] > 0.0)
    if friction > 0:
        assert np.all(pt[sliding] > 0.0) and np.all(slip < d)
    # vertical equilibrium of the top block: resultant of sigma_n = top load
    w = gauss_weights(fr["s"], 10)
    assert np.sum(w * pn) == pytest.approx(-PRESSURE * 1.0, rel=1e-6)
    # ... and so the shear the fault transmits is f times the top load
    assert np.sum(w * pt) == pytest.approx(
        friction * PRESSURE * 1.0, rel=1e-6, abs=1e-3
    )


def test_frictionless_slip_by_symmetry(tmp_path):
    """f = 0: no shear crosses the fault, so apart from the rigid translation d of the
    top block the problem is mirror-symmetric about x = 0.5 (Poisson expansion of
    both blocks): slip(x) + slip(1 - x) = 2 d and the mean slip is d (measured
    1e-14 rel)."""
    r = run_block(tmp_path, 0.0)
    slip = r.fr["slip"]
    np.testing.assert_allclose(slip + slip[::-1], 2 * D, rtol=1e-9)
    w = gauss_weights(r.fr["s"], 10)
    assert np.sum(w * slip) == pytest.approx(D, rel=1e-9)
    assert np.ptp(slip) > 1e-4 * D  # premise: the slip is not uniform


def test_sliding_is_path_independent(tmp_path):
    """Monotonic shearing: 1 step and 4 steps give the same slip."""
    one = run_block(tmp_path / "one", 0.3)
    four = run_block(tmp_path / "four", 0.3, steps=4)
    np.testing.assert_allclose(four.fr["slip"], one.fr["slip"], rtol=1e-6)
