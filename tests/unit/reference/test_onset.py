"""The pressure change to slip (xfemslip.reference.onset) and its three users
against one independent reference: a scan along dp of the solver's own
contact law.

The reference, :func:`scan_onset`, knows nothing of the linear form
sigma_n' = A0 + A1 dp of the law: each test writes its stress path as the
stress tensor and the pore pressure at a pore-pressure change dp, projects
it on the plane with matrices, and asks the contact return map
(xfemslip.kernels.vectorized.coulomb_return_map, the NumPy twin of the
solver's kernel) at a point with no jump whether the plane still sticks.
The first dp where it does not (it opens or slips) is found on a grid in the
direction of the change, then by bisection of the bracket.  Under depletion
the grid ends at dp = -p0 (the pore pressure cannot fall below 0); under
injection it ends at SPAN, beyond every finite onset of these tests.

The three users: ``reference.screen.pressure_to_slip`` (the total stress
kept), ``reference.closed_form_depletion.critical_change_uniaxial`` (the
uniaxial-strain path) and ``studies.slip_screen.critical_changes`` (the
uncertainty screen, along the path it reads from a case).
"""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest

from xfemslip.case import loads_case
from xfemslip.conventions import STICK
from xfemslip.kernels.vectorized import coulomb_return_map
from xfemslip.reference.closed_form_depletion import critical_change_uniaxial
from xfemslip.reference.onset import DEPLETION, INJECTION, critical_change, onset
from xfemslip.reference.screen import pressure_to_slip
from xfemslip.studies.slip_screen import critical_changes, stress_path

MPA = 1e6
SPAN = 2.0e9  # [Pa] end of the injection scan
GRID = 40001  # scan points: 50 kPa apart under injection, < 1 kPa under depletion


def tractions(S, theta_deg):
    """(n.S.n, t.S.n) of the plane at theta with matrices; S (..., 2, 2)."""
    th = math.radians(theta_deg)
    t = np.array([math.cos(th), math.sin(th)])
    n = np.array([-math.sin(th), math.cos(th)])
    return n @ S @ n, t @ S @ n


def scan_onset(state_at, friction, cohesion, direction, p0):
    """First dp in ``direction`` at which the contact law does not stick.

    state_at(dp (k,)) -> (sigma_n' (k,), tau (k,)) [Pa].  0 if it does not
    stick at dp = 0, NaN if it sticks over the whole range."""

    def fails(dp):
        sn, tau = state_at(np.atleast_1d(np.asarray(dp, float)))
        one = np.ones(sn.shape)
        state = coulomb_return_map(
            0.0 * one,
            tau,
            0.0 * one,
            0.0 * one,
            sn,
            one,
            one,
            friction * one,
            cohesion * one,
            friction * one,
            cohesion * one,
            np.inf * one,
        )[2]
        return state != STICK

    span = p0 if direction == DEPLETION else SPAN
    grid = direction * np.linspace(0.0, span, GRID)
    bad = fails(grid)
    if not bad.any():
        return math.nan
    i = int(np.argmax(bad))
    if i == 0:
        return 0.0
    lo, hi = grid[i - 1], grid[i]  # sticks at lo, not at hi
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if fails(mid)[0] else (mid, hi)
    return float(hi)


def assert_same(got, ref, scale=MPA):
    """Equal to the reference's bisection (0.1 Pa) or both NaN."""
    if math.isnan(ref):
        assert math.isnan(got), (got, ref)
    else:
        assert got == pytest.approx(ref, abs=1e-7 * scale), (got, ref)


# --------------------------------------------------------------------------- #
# The law by hand
# --------------------------------------------------------------------------- #


@pytest.mark.parametrize(
    ("normal", "shear", "f", "c", "direction", "p0", "dp", "opens"),
    [
        # injection, c = 2.5 MPa, f = 0.5, tau = 0: opens at sigma_n' = 0
        # (dp = 10 MPa) before the Coulomb line, which reaches into tension
        # up to c / f = 5 MPa (dp = 15 MPa)
        ((-10 * MPA, 1.0), (0.0, 0.0), 0.5, 2.5 * MPA, INJECTION, None, 10 * MPA, True),
        # the same without cohesion: Coulomb and opening meet at sigma_n' = 0
        ((-10 * MPA, 1.0), (0.0, 0.0), 0.5, 0.0, INJECTION, None, 10 * MPA, True),
        # tau = 3 MPa fixed, f = 0.5: 3 = 0.5 (10 - dp) at dp = 4 MPa
        ((-10 * MPA, 1.0), (3 * MPA, 0.0), 0.5, 0.0, INJECTION, None, 4 * MPA, False),
        # f = 0: the bound is c alone; tau = 1 MPa - 0.5 dp reaches -c = -2 MPa
        # at dp = 6 MPa (the branch tau < 0), before opening at 10 MPa
        (
            (-10 * MPA, 1.0),
            (1 * MPA, -0.5),
            0.0,
            2 * MPA,
            INJECTION,
            None,
            6 * MPA,
            False,
        ),
        # f = 0 and tau fixed below c: stuck until it opens
        (
            (-10 * MPA, 1.0),
            (1 * MPA, 0.0),
            0.0,
            2 * MPA,
            INJECTION,
            None,
            10 * MPA,
            True,
        ),
        # f = 0, c = 0: the bound is 0, reached in situ even at tau = 0
        ((-10 * MPA, 1.0), (0.0, 0.0), 0.0, 0.0, INJECTION, None, 0.0, False),
        # in tension in situ: open already
        ((1 * MPA, 1.0), (0.0, 0.0), 0.5, 0.0, DEPLETION, 30 * MPA, 0.0, True),
        # exactly at sigma_n' = 0: at the limit
        ((0.0, 1.0), (0.0, 0.0), 0.5, 1 * MPA, DEPLETION, 30 * MPA, 0.0, True),
        # exactly on the Coulomb line: at the limit
        ((-10 * MPA, 1.0), (-5 * MPA, 0.0), 0.5, 0.0, DEPLETION, 30 * MPA, 0.0, False),
        # depletion, tau = 1 MPa + 0.5 dp changes sign at dp = -2 MPa and
        # reaches the bound on its negative branch: -(1 + 0.5 dp) =
        # 0.2 (10 - 0.1 dp) [MPa] at dp = -3 / 0.48 MPa
        (
            (-10 * MPA, 0.1),
            (1 * MPA, 0.5),
            0.2,
            0.0,
            DEPLETION,
            30 * MPA,
            -3 / 0.48 * MPA,
            False,
        ),
        # depletion where sigma_n' rises (A1 < 0): opens at dp = -10 / 0.5 MPa
        (
            (-10 * MPA, -0.5),
            (0.0, 0.0),
            0.5,
            1 * MPA,
            DEPLETION,
            30 * MPA,
            -20 * MPA,
            True,
        ),
        # ... but not if p0 = 15 MPa: p would have to fall below 0
        (
            (-10 * MPA, -0.5),
            (0.0, 0.0),
            0.5,
            1 * MPA,
            DEPLETION,
            15 * MPA,
            math.nan,
            False,
        ),
        # ... and exactly at p = 0 it counts
        (
            (-10 * MPA, -0.5),
            (0.0, 0.0),
            0.5,
            1 * MPA,
            DEPLETION,
            20 * MPA,
            -20 * MPA,
            True,
        ),
        # the state moves away from every limit: never
        (
            (-10 * MPA, 1.0),
            (1 * MPA, 0.0),
            0.5,
            0.0,
            DEPLETION,
            30 * MPA,
            math.nan,
            False,
        ),
        # a plane whose stress does not change along the path: never
        ((-10 * MPA, 0.0), (0.0, 0.0), 0.0, 1 * MPA, INJECTION, None, math.nan, False),
    ],
)
def test_hand_solved_cases(normal, shear, f, c, direction, p0, dp, opens):
    found = onset(normal, shear, f, c, direction, p0)
    if math.isnan(dp):
        assert np.isnan(found.change)
    else:
        assert found.change == pytest.approx(dp, abs=1e-6)
    assert bool(found.opens) is opens
    assert_same(float(critical_change(normal, shear, f, c, direction, p0)), dp)


def test_vectorised_nan_and_direction():
    """Arrays broadcast; a NaN coefficient gives NaN; direction is +-1."""
    found = onset(
        (np.array([-10 * MPA, np.nan, -10 * MPA]), 1.0),
        (np.array([3 * MPA, 0.0, -3 * MPA]), 0.0),
        0.5,
        np.array([0.0, 0.0, 1 * MPA]),
        INJECTION,
        None,
    )
    np.testing.assert_allclose(found.change, [4 * MPA, np.nan, 6 * MPA])
    np.testing.assert_array_equal(found.opens, [False, False, False])
    with pytest.raises(ValueError, match="direction"):
        onset((-1.0, 1.0), (0.0, 0.0), 0.5, 0.0, 0.0, 1.0)


# --------------------------------------------------------------------------- #
# The three users against the scan
# --------------------------------------------------------------------------- #


def _random_cases(seed, k):
    """k (stress (3,), p0, theta, f, c) with cohesion in half of them."""
    rng = np.random.default_rng(seed)
    out = []
    for j in range(k):
        sxx, syy = -rng.uniform(5, 60, 2) * MPA
        sxy = rng.uniform(-10, 10) * MPA
        p0 = rng.uniform(0.0, 40) * MPA
        theta = float(rng.choice([0.0, 90.0, rng.uniform(0.0, 180.0)]))
        f = float(rng.choice([0.0, rng.uniform(0.1, 0.9)]))
        c = rng.uniform(0.0, 8.0) * MPA if j % 2 else 0.0
        out.append(((sxx, syy, sxy), p0, theta, f, c))
    return out


@pytest.mark.parametrize("direction", [DEPLETION, INJECTION])
def test_pressure_to_slip_against_the_scan(direction):
    """Constant total stress: sigma' = sigma + p I, p = p0 + dp."""
    kinds = set()
    for stress, p0, theta, f, c in _random_cases(1, 150):
        S = np.array([[stress[0], stress[2]], [stress[2], stress[1]]])
        sn0, tau0 = tractions(S, theta)
        found = pressure_to_slip(sn0 + p0, tau0, f, c, direction, p0)

        def state_at(dp, S=S, p0=p0, theta=theta):
            sn, tau = tractions(S, theta)
            return sn + p0 + dp, np.full(dp.shape, tau)

        ref = scan_onset(state_at, f, c, direction, p0)
        assert_same(float(found.change), ref)
        kinds.add((math.isnan(ref) or ref == 0.0, bool(found.opens)))
    # both sides of the opening limit, and in-situ / never, were checked
    if direction == INJECTION:
        assert {(False, True), (False, False)} <= kinds
    assert (True, False) in kinds


def _uniaxial_state(stress, p0, nu, theta, biot=1.0):
    """The uniaxial-strain path written out: the bulk contracts laterally
    confined, sigma_xx changes by -alpha (1 - 2 nu) / (1 - nu) dp, the rest
    stays, the fracture sees its fluid pressure p0 + dp (Terzaghi)."""

    def state_at(dp):
        sn, tau = [], []
        for d in dp:
            sxx = stress[0] - biot * (1.0 - 2.0 * nu) / (1.0 - nu) * d
            S = np.array([[sxx, stress[2]], [stress[2], stress[1]]])
            a, b = tractions(S, theta)
            sn.append(a + p0 + d)
            tau.append(b)
        return np.array(sn), np.array(tau)

    return state_at


def _vectorised_uniaxial(stress, p0, nu, theta, biot=1.0):
    """_uniaxial_state for a whole grid at once (the same formulas)."""
    th = math.radians(theta)
    t = np.array([math.cos(th), math.sin(th)])
    n = np.array([-math.sin(th), math.cos(th)])

    def state_at(dp):
        sxx = stress[0] - biot * (1.0 - 2.0 * nu) / (1.0 - nu) * dp
        S = np.zeros(dp.shape + (2, 2))
        S[..., 0, 0], S[..., 1, 1] = sxx, stress[1]
        S[..., 0, 1] = S[..., 1, 0] = stress[2]
        sn = np.einsum("i,...ij,j->...", n, S, n)
        tau = np.einsum("i,...ij,j->...", t, S, n)
        return sn + p0 + dp, tau

    return state_at


def test_the_vectorised_path_is_the_written_out_one():
    state = (-30 * MPA, -50 * MPA, 4 * MPA)
    dp = np.linspace(-20, 20, 7) * MPA
    for theta in (0.0, 33.0, 90.0, 151.0):
        a = _uniaxial_state(state, 20 * MPA, 0.27, theta)(dp)
        b = _vectorised_uniaxial(state, 20 * MPA, 0.27, theta)(dp)
        np.testing.assert_allclose(a, b, rtol=1e-13, atol=1e-6)


@pytest.mark.parametrize("direction", [DEPLETION, INJECTION])
def test_critical_change_uniaxial_against_the_scan(direction):
    rng = np.random.default_rng(7)
    kinds = set()
    for stress, p0, theta, f, c in _random_cases(2, 150):
        nu = float(rng.uniform(0.1, 0.4))
        got = critical_change_uniaxial(stress, p0, nu, theta, f, c, 1.0, direction)
        ref = scan_onset(
            _vectorised_uniaxial(stress, p0, nu, theta), f, c, direction, p0
        )
        assert_same(got, ref)
        kinds.add("never" if math.isnan(ref) else "in situ" if ref == 0 else "found")
    # injection opens every plane of this path in the end (sigma_n' grows)
    assert kinds == {"never", "in situ", "found"} - {"never" if direction > 0 else ""}


# --------------------------------------------------------------------------- #
# The uncertainty screen (slip_screen.critical_changes) on a case
# --------------------------------------------------------------------------- #


def _case(change, *, layer: bool, sides: str):
    """A 100 m box, one center-form fracture; the pressure changes by
    ``change`` everywhere (constant total stress: traction sides) or in a
    full-width layer between rollers (uniaxial strain)."""
    reservoir = (
        "[reservoir]\nbox = [0.0, 40.0, 100.0, 60.0]\nE = 8e9\nnu = 0.2\n"
        if layer
        else ""
    )
    region = "reservoir" if layer else "all"
    return f"""
name = "onset"
[domain]
size = [100.0, 100.0]
[mesh]
elements = [10, 10]
[material]
E = 20e9
nu = 0.25
{reservoir}
[pore_pressure]
initial = 30e6
change = {change}
region = "{region}"
[[fractures]]
center = [50.0, 50.0]
length = 10.0
angle = 60.0
friction = 0.5
cohesion = 0.0
[loading]
initial_stress = {{ xx = -44e6, yy = -62e6, xy = 0.0 }}
stress = {{ xx = -44e6, yy = -62e6, xy = 0.0 }}
[boundary]
left = {sides}
right = {sides}
bottom = {{ uy = 0.0 }}
top = "traction"
"""


KEYS = (
    "fractures[0].friction",
    "fractures[0].cohesion",
    "fractures[0].angle",
    "pore_pressure.initial",
    "loading.initial_stress.xx",
)


def _samples(seed, n):
    rng = np.random.default_rng(seed)
    return np.column_stack(
        [
            rng.choice([0.0, 0.3, 0.5, 0.7], n) * rng.uniform(0.8, 1.2, n),
            np.where(rng.random(n) < 0.5, 0.0, rng.uniform(0.0, 6e6, n)),
            np.where(rng.random(n) < 0.2, 90.0, rng.uniform(0.0, 180.0, n)),
            rng.uniform(5e6, 40e6, n),
            rng.uniform(-70e6, -40e6, n),
        ]
    )


@pytest.mark.parametrize("change", [-20e6, 20e6])
@pytest.mark.parametrize(
    ("layer", "sides"), [(True, "{ ux = 0.0 }"), (False, '"traction"')]
)
def test_uncertainty_screen_against_the_scan(change, layer, sides):
    text = _case(change, layer=layer, sides=sides)
    spec = loads_case(text, "onset.toml")
    path, why = stress_path(spec)
    assert not why
    values = _samples(3, 120)
    got = critical_changes(spec, tomllib.loads(text), path, KEYS, values)[:, 0]
    direction = math.copysign(1.0, change)
    kinds = set()
    for (f, c, theta, p0, sxx), dp in zip(values, got, strict=True):
        stress = (sxx, -62e6, 0.0)
        if layer:  # the layer's nu = 0.2; the fracture lies inside it
            state_at = _vectorised_uniaxial(stress, p0, 0.2, theta)
        else:  # the traction edges go from the sampled in-situ stress to
            # the case's loading.stress as the pressure reaches its change
            state_at = _total_state(stress, (-44e6, -62e6, 0.0), change, p0, theta)
        ref = scan_onset(state_at, f, c, direction, p0)
        assert_same(dp, ref)
        kinds.add("never" if math.isnan(ref) else "in situ" if ref == 0 else "found")
    assert {"in situ", "found"} <= kinds
    assert ("never" in kinds) is (direction < 0)


def _total_state(initial, final, change, p0, theta):
    """Constant total stress between loads: S(dp) = S0 + (S1 - S0) dp / change,
    the fracture's fluid pressure p0 + dp."""
    th = math.radians(theta)
    t = np.array([math.cos(th), math.sin(th)])
    n = np.array([-math.sin(th), math.cos(th)])

    def state_at(dp):
        lam = (dp / change)[:, None]
        xx, yy, xy = (np.asarray(initial) + (np.subtract(final, initial)) * lam).T
        S = np.stack([np.stack([xx, xy], -1), np.stack([xy, yy], -1)], -2)
        sn = np.einsum("i,...ij,j->...", n, S, n)
        tau = np.einsum("i,...ij,j->...", t, S, n)
        return sn + p0 + dp, tau

    return state_at


def test_injection_with_cohesion_opens_before_the_coulomb_line():
    """A horizontal fracture (tau = 0) at sigma_n' = -62 + 52 = -10 MPa, c =
    2.5 MPa, f = 0.5, under injection: it opens at dp = 10 MPa.  The Coulomb
    line alone would reach sigma_n' = c / f = +5 MPa at dp = 15 MPa, a
    plane in tension that carries no shear."""
    text = _case(20e6, layer=False, sides='"traction"')
    spec = loads_case(text, "onset.toml")
    path, _ = stress_path(spec)
    keys = ("fractures[0].angle", "fractures[0].cohesion", "pore_pressure.initial")
    values = np.array([[0.0, 2.5e6, 52e6], [180.0, 2.5e6, 52e6]])
    got = critical_changes(spec, tomllib.loads(text), path, keys, values)[:, 0]
    np.testing.assert_allclose(got, [10e6, 10e6], rtol=1e-12)
    found = pressure_to_slip(-10e6, 0.0, 0.5, 2.5e6)
    assert found.change == pytest.approx(10e6) and found.opens
