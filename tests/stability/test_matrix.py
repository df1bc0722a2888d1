"""The numerical stress matrix, fast subset (the whole matrix is
``benchmarks/stability.py``; its table is in ``docs/performance/stability.md``).

Every case converges and matches its independent reference, or fails with a
ConvergenceError that says why and what to change.  Never NaN or inf.
Measured numbers are in the docstrings of the tests and in docs/performance.md.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from tests.support.matrix import (
    OPEN,
    RESERVOIR,
    SHEAR_STRESS,
    SLIP,
    STICK,
    Crack,
    block_text,
    block_threshold,
    crack_error,
    point_fields,
    reservoir_text,
    run_crack,
    solve,
    window_reference,
)
from xfemslip.case import loads_case
from xfemslip.errors import GeometryError
from xfemslip.reference import closed_form as cf
from xfemslip.simulation import build_model

pytestmark = pytest.mark.verification

TANGENTS = ("consistent", "secant")
SLOW = pytest.mark.slow
# the consistent tangent in the default tier, the secant one in the slow tier
TANGENT_TIERS = ("consistent", pytest.param("secant", marks=SLOW))
H32 = 2.0 / 32  # element size of the crack cases [m]


# ------------------------------------------------------------- penalty sweep


@pytest.mark.parametrize("kt_kn", [1e-3, 1.0])
@SLOW
def test_penalty_sweep_consistent(kt_kn):
    """kn h / E from 1e-1 to 1e8, kt / kn = 1e-3 and 1: every case converges;
    the slip written (the whole jump, penalty compliance included) approaches
    the closed form as the penalty stiffens, and is within 2 % once
    kt h / E >= 10.  Measured, kt = kn: 19.1 % at 0.1, 2.2 % at 1, 1.01 ..
    1.08 % at 1e2 .. 1e8; kt = 1e-3 kn: 55 % at 0.1."""
    errors = []
    for penalty in (0.1, 1.0, 1e2, 1e4, 1e6, 1e8):
        out, err, _ = run_crack(Crack(penalty=penalty, kt_kn=kt_kn))
        assert out.converged, (penalty, out.error)
        errors.append(err)
        if penalty * kt_kn >= 10:
            assert err < 0.02, (penalty, err)
    assert errors[0] > errors[-1]


@pytest.mark.parametrize(("penalty", "limit"), [(0.1, 0.25), (1e2, 0.02), (1e8, 0.02)])
def test_penalty_extremes_consistent(penalty, limit):
    """Default-tier subset of the sweep above (measured 19.1 %: the penalty
    compliance of kn h / E = 0.1 is in the jump; 1.01 %; 1.08 %)."""
    out, err, _ = run_crack(Crack(penalty=penalty))
    assert out.converged, out.error
    assert err < limit, err


@pytest.mark.parametrize("penalty", [1e2, pytest.param(1e4, marks=SLOW)])
def test_penalty_sweep_secant(penalty):
    out, err, _ = run_crack(Crack(penalty=penalty), "secant")
    assert out.converged, out.error
    assert err < 0.02


@SLOW
def test_secant_with_extreme_penalty_converges_or_says_why():
    """kn h / E = 1e8 with the secant tangent: measured here, no convergence
    (the secant drops the n-t coupling of the slip law); the message must say
    to lower the penalty or use the consistent tangent.  (With the contact
    patches of a later main it converges in 8 iterations: then the slip must
    be right.)"""
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        text, path = Crack(penalty=1e8).write(Path(tmp))
        out = solve(text, path, "secant", max_step_cuts=0)  # cuts cannot help
    if out.converged:
        err, _ = crack_error(Crack(penalty=1e8), out)
        assert err < 0.02
        return
    assert "kn*h/E up to 1.0e+08" in out.error
    assert "lower kn/kt" in out.error and 'tangent = "consistent"' in out.error
    assert not out.steps


# ----------------------------------------------------- friction and cohesion


@pytest.mark.parametrize("tangent", TANGENT_TIERS)
@pytest.mark.parametrize("friction", [0.0, pytest.param(0.1, marks=SLOW), 0.6, 1.5])
def test_friction_range(friction, tangent):
    """f = 0 .. 1.5 on the 30-degree crack: slips for f < 0.247, sticks above
    (closed form; the check is the slip profile or the absence of SLIP)."""
    crack = Crack(friction=friction)
    out, err, ref = run_crack(crack, tangent)
    assert out.converged, out.error
    if crack.no_slip_cohesion() > 0:
        assert err < 0.02
    else:
        assert ref.startswith("sticks") and err == 0.0


@pytest.mark.parametrize("tangent", TANGENT_TIERS)
@pytest.mark.parametrize(
    "fraction",
    [pytest.param(0.0, marks=SLOW), 0.5, pytest.param(0.9, marks=SLOW), 1.01, 1.2, 2.0],
)
def test_cohesion_up_to_no_slip(fraction, tangent):
    """Cohesion from 0 to twice the no-slip value c* = |tau| - f |sigma_n|
    (crack at 50 degrees, f = 0.3): below c* the slip is the closed form's;
    from 1.2 c* no point slips.  Just above c* (1.01 .. 1.1 c*) the discrete
    tractions, which deviate near the tips (docs/robustness.md, known limits), let
    some points slip (measured SLIP share 38 % at 1.01 c*, 4 % at 1.05, 2 % at
    1.1), but by no more than the elastic penalty jump: max |slip| 0.29 % of
    that of the cohesionless crack."""
    base = Crack(psi=50.0, friction=0.3)
    crack = Crack(psi=50.0, friction=0.3, cohesion=fraction * base.no_slip_cohesion())
    out, err, ref = run_crack(crack, tangent)
    assert out.converged, out.error
    if fraction < 1.0:
        assert err < (0.02 if fraction <= 0.5 else 0.06), err
    elif fraction < 1.2:
        free, _, _ = run_crack(base, tangent)
        assert out.max_slip < 0.005 * free.max_slip
    else:
        assert ref.startswith("sticks") and err == 0.0


# ------------------------------------------------------------ hard geometry

GEOMETRY = {
    "through-nodes": Crack(psi=45.0, center=(0.0, 0.0)),
    "tips-on-nodes": Crack(psi=45.0, center=(0.0, 0.0), a=math.sqrt(2) * 6 * H32),
    "along-edges": Crack(psi=0.0, center=(0.0, 0.0), stress=SHEAR_STRESS),
    "tips-on-edges": Crack(psi=0.0, center=(0.0, 0.5 * H32), stress=SHEAR_STRESS),
    "1e-9h-from-edge": Crack(psi=0.0, center=(0.0, 1e-9 * H32), stress=SHEAR_STRESS),
    "tip-1e-9h-from-edge": Crack(
        psi=0.0, center=(1e-9 * H32, 0.5 * H32), stress=SHEAR_STRESS
    ),
    "tip-one-element-from-boundary": Crack(
        psi=0.0, center=(0.0, 0.5 * H32), a=1.0 - 1.5 * H32, stress=SHEAR_STRESS
    ),
}


@pytest.mark.parametrize("tangent", TANGENT_TIERS)
@pytest.mark.parametrize("name", list(GEOMETRY))
def test_hard_geometry_matches_the_closed_form(name, tangent):
    """Measured relative L2 slip errors 0.8 .. 1.4 % (h = a/16, both tangents)."""
    out, err, _ = run_crack(GEOMETRY[name], tangent)
    assert out.converged, out.error
    assert err < 0.02, err


@pytest.mark.parametrize("tangent", TANGENT_TIERS)
def test_two_parallel_fractures_one_element_apart(tangent):
    """Two 0.6 m fractures at 45 degrees, one element (h = 1/20) apart
    (measured perpendicular): both converge and slip; the stiffer neighbour
    shields each one, so each slips less than a single fracture alone."""
    h = 1.0 / 20
    d = h / math.sqrt(2)  # half the perpendicular offset, along (-1, 1)/sqrt 2
    one = reservoir_text(n=20, points=[[0.29, 0.29], [0.71, 0.71]])
    pts_a = [[0.29 - d, 0.29 + d], [0.71 - d, 0.71 + d]]
    pts_b = [[0.29 + d, 0.29 - d], [0.71 + d, 0.71 - d]]
    two = reservoir_text(n=20, points=pts_a, extra_fractures=[pts_b])
    single = solve(one, RESERVOIR, tangent)
    pair = solve(two, RESERVOIR, tangent)
    assert single.converged and pair.converged, pair.error
    gt, state = point_fields(pair.steps[-1].contact)
    frac = pair.model.ip.fracture
    for i in (0, 1):
        assert np.mean(state[frac == i] == SLIP) > 0.5
        assert np.max(np.abs(gt[frac == i])) < single.max_slip
    assert np.all(np.isfinite(pair.steps[-1].u))


def test_overlapping_fractures_are_refused():
    # crossing fractures make a network; one on top of the other
    # (collinear overlap) is still refused
    pts = [[0.4, 0.4], [0.9, 0.9]]
    text = reservoir_text(n=20, extra_fractures=[pts])
    with pytest.raises(GeometryError, match="overlap"):
        build_model(loads_case(text, RESERVOIR))


# ------------------------------------------- block on a through-going fault


@pytest.mark.parametrize("tangent", TANGENT_TIERS)
@pytest.mark.parametrize(
    ("friction", "cohesion", "fraction"),
    [
        pytest.param(0.5, 0.0, 0.5, marks=SLOW),
        (0.5, 0.0, 0.9),
        (0.5, 2.0e6, 0.9),
        pytest.param(1.5, 0.0, 0.5, marks=SLOW),
    ],
)
def test_block_below_the_sliding_threshold_holds(friction, cohesion, fraction, tangent):
    """Top block held by the fault alone, loaded by (tau, -p) on its top edge:
    below tau* = f p + c it is in equilibrium, and the fault carries exactly
    the load (statics of the top block: integral of p_T = tau L, of
    p_N = -p L), with no point beyond the Coulomb bound."""
    p, length = 10.0e6, 2.0
    tau = fraction * block_threshold(p, friction, cohesion)
    out = solve(
        block_text(shear=tau, friction=friction, cohesion=cohesion), RESERVOIR, tangent
    )
    assert out.converged, out.error
    res = out.steps[-1].contact
    w = out.model.contact.weight  # of each contact point (or patch)
    assert np.sum(w * res.pt) == pytest.approx(tau * length, rel=1e-6)
    assert np.sum(w * res.pn) == pytest.approx(-p * length, rel=1e-6)
    bound = cohesion - friction * res.pn
    closed = res.state != OPEN
    assert np.all(np.abs(res.pt[closed]) <= bound[closed] * (1 + 1e-9))
    assert np.any(res.state == STICK)


@pytest.mark.parametrize("fraction", [1.05, pytest.param(1.5, marks=SLOW)])
def test_block_beyond_the_threshold_is_reported(fraction):
    """Above tau* there is no equilibrium: a ConvergenceError that names the
    fracture, the rigid sliding and what to change (never a wrong answer)."""
    tau = fraction * block_threshold(10.0e6, 0.5, 2.0e6)
    out = solve(
        block_text(shear=tau, friction=0.5, cohesion=2.0e6),
        RESERVOIR,
        max_iterations=15,
        max_step_cuts=1,
    )
    assert not out.converged
    assert "fractures[0] cuts the domain in two" in out.error
    assert "rigid sliding" in out.error and "prescribe a displacement" in out.error


# ----------------------------------------------------------- material range


def test_nearly_incompressible_locking_is_measured():
    """nu = 0.499 (plane strain): volumetric locking stiffens the bulk; the
    slip error against the closed form grows from 0.94 % (nu = 0.3) to about
    8 % (measured 7.99 %; 3.18 % at nu = 0.49).  The intact cells' incompatible
    modes (kernels.bulk.rectangle_stiffness) relieve most of it -- with plain
    Q4 intact cells it was 19.7 % -- the enriched cells are plain Q4 and
    still lock.  Reported, not hidden: it converges, and the error is bounded
    here so a change is noticed."""
    base, _, _ = run_crack(Crack(nu=0.3))
    out, err, _ = run_crack(Crack(nu=0.499))
    assert out.converged, out.error
    assert 0.05 < err < 0.11
    assert out.max_slip < base.max_slip * 1.2  # locking: slip is underestimated


@pytest.mark.parametrize("tangent", TANGENT_TIERS)
def test_young_modulus_1e6_to_1e12(tangent):
    """E from 1e6 to 1e12 Pa (kn = 100 E / h): the problem is scale invariant,
    so the slip scales exactly as 1/E and the relative error is the same."""
    errs, slips = [], []
    for E in (1e6, 1e9, 1e12):
        out, err, _ = run_crack(Crack(E=E), tangent)
        assert out.converged, out.error
        errs.append(err)
        slips.append(out.max_slip * E)
    assert max(errs) < 0.02
    assert np.ptp(errs) < 1e-6
    np.testing.assert_allclose(slips, slips[0], rtol=1e-6)


# ------------------------------------------------------------- load steps


@pytest.mark.parametrize("tangent", TANGENT_TIERS)
def test_proportional_loading_1_and_10_steps_agree(tangent):
    """Measured: 3.5e-10 (consistent), 1.2e-8 (secant) relative difference."""
    one = solve(reservoir_text(n=16, steps=1), RESERVOIR, tangent)
    ten = solve(reservoir_text(n=16, steps=10), RESERVOIR, tangent)
    ref = one.steps[-1].u
    assert np.max(np.abs(ten.steps[-1].u - ref)) < 1e-7 * np.max(np.abs(ref))


@SLOW
def test_proportional_loading_1_and_100_steps_agree():
    one = solve(reservoir_text(n=16, steps=1), RESERVOIR)
    many = solve(reservoir_text(n=16, steps=100), RESERVOIR)
    ref = one.steps[-1].u
    assert np.max(np.abs(many.steps[-1].u - ref)) < 1e-7 * np.max(np.abs(ref))


@pytest.mark.parametrize("tangent", TANGENT_TIERS)
def test_load_unload_hysteresis(tangent):
    """In-situ isotropic compression 30 MPa, deviatoric load (-20, -40) MPa
    applied and removed three times.  Unloading is elastic: every point sticks
    and keeps the plastic slip of the loaded state (residual slip stays);
    reloading reaches the same loaded state; the cycles do not drift.
    Measured: residual slip 0.261 mm; cycles agree to 2e-9 (tolerance)."""
    text = reservoir_text(n=16, initial_stress=(-30e6, -30e6, 0.0), friction=0.3)
    out = solve(text, RESERVOIR, tangent, factors=[1, 0, 1, 0, 1, 0])
    assert out.converged, out.error
    loaded, unloaded = out.steps[0::2], out.steps[1::2]
    first = loaded[0].contact
    assert np.mean(first.state == SLIP) > 0.3  # premise: it slipped
    residual = np.max(np.abs(unloaded[0].contact.slip_plastic))
    assert residual > 0.5 * np.max(np.abs(first.gt))  # the residual slip stays
    for r in unloaded:
        assert np.all(r.contact.state == STICK)
        np.testing.assert_allclose(
            r.contact.slip_plastic, first.slip_plastic, rtol=0, atol=1e-9 * residual
        )
    scale = np.max(np.abs(loaded[0].u))
    for a, b in ((loaded[0], loaded[2]), (unloaded[0], unloaded[2])):
        assert np.max(np.abs(a.u - b.u)) < 1e-7 * scale  # no drift


# ------------------------------------------------------ stick/slip switching


@pytest.mark.parametrize("tangent", TANGENT_TIERS)
@pytest.mark.parametrize("friction", [0.1, pytest.param(0.3, marks=SLOW)])
def test_angles_across_the_slip_window_edges(friction, tangent):
    """1-degree steps across both edges of the slip window (stick/slip
    switching along the fracture): every angle converges; clear of the edges
    (> 3 deg) the classification is the closed form's."""
    sigma1, sigma3, dir1 = cf.principal((-20e6, -40e6, 0.0))
    lo, hi = cf.slip_window(sigma1, sigma3, friction)
    edges = [dir1 + lo, dir1 + hi]
    for edge in edges:
        for angle in range(round(edge) - 4, round(edge) + 5, 2):
            out = solve(
                reservoir_text(n=12, angle=angle, friction=friction), RESERVOIR, tangent
            )
            assert out.converged, (angle, out.error)
            inside, distance = window_reference(angle, friction)
            share = np.mean(out.steps[-1].contact.state == SLIP)
            if distance > 3.0:
                assert (share >= 0.8) if inside else (share == 0.0), (angle, share)


@pytest.mark.slow
@pytest.mark.parametrize(("tangent", "every"), [("consistent", 1), ("secant", 3)])
def test_angle_sweep_0_to_180(tangent, every):
    """Every angle 0..180 in 1-degree steps (every third with the secant
    tangent) converges with finite values (f = 0.1, 12 x 12)."""
    failed = []
    for angle in range(0, 181, every):
        out = solve(reservoir_text(n=12, angle=angle), RESERVOIR, tangent)
        if not out.converged:
            failed.append((angle, out.error))
        else:
            assert np.all(np.isfinite(out.steps[-1].u))
    assert not failed, failed
