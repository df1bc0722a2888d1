"""Newton: the consistent tangent is exact once the stick/slip set has settled,
the secant tangent (paper eq. 28) converges to the same answer, more slowly."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from xfemslip.case import build, loads_case
from xfemslip.errors import ConvergenceError
from xfemslip.simulation import build_model
from xfemslip.solve.linear import KRYLOV_RTOL
from xfemslip.solve.newton import NewtonSolver

CASE = Path(__file__).resolve().parents[3] / "cases" / "reservoir_depletion.toml"


def _solve(tangent, steps=1, n=20, friction=0.1):
    keys = {
        "mesh.elements": [n, n],
        "fractures.0.friction": friction,
        "loading.steps": steps,
    }
    text = build.case_text(build.file_case(CASE, **keys))
    model = build_model(loads_case(text, CASE))
    # without the stick/slip predictor: these tests watch Newton's own
    # iterates settle (the predictor's first solve lands on the final set
    # directly; tests/unit/contact/test_predictor.py)
    solver = NewtonSolver(model.problem, 1e-10, 60, tangent, predictor=False)
    return solver.run(steps)


@pytest.mark.parametrize("friction", [0.1, 0.3])
def test_consistent_tangent_converges_in_one_iteration_once_the_set_settles(friction):
    """Within a fixed stick/slip set the discrete problem is linear in u and the
    consistent tangent is its exact Jacobian: the iteration after the first one
    without a switch must land on round-off (not just decrease)."""
    checked = 0
    # 4 steps: a step may also converge in one solve (no iterate i >= 2 to
    # check) when its first solve lands on the final set; every patch that
    # slipped in the step before starts the step exactly on the Coulomb bound,
    # so which steps do is decided by round-off (kernel backend, BLAS)
    for step in _solve("consistent", steps=4, friction=friction):
        eta, sw = step.residuals, step.switches
        assert eta[-1] <= 1e-10
        # sw[i] = switches between the states at iterates i-1 and i: when it is
        # 0 (i >= 2), the solve from iterate i-1 used the tangent of the final
        # set, so iterate i is exact up to round-off and the linear solve's
        # own tolerance (a Krylov solve on a kept factorization stops at a
        # relative residual KRYLOV_RTOL: the inexact Newton bound); a wrong
        # Jacobian would leave a fixed fraction of eta[i - 1]
        for i in range(2, len(eta)):
            if sw[i] == 0:
                bound = 1e-12 + 2.0 * KRYLOV_RTOL * eta[i - 1]
                assert eta[i] < bound, (i, eta, sw)
                checked += 1
    assert checked >= 3


def test_secant_tangent_reaches_the_same_solution_linearly():
    cons = _solve("consistent")[-1]
    sec = _solve("secant")[-1]
    np.testing.assert_allclose(sec.contact.gt, cons.contact.gt, rtol=1e-6, atol=1e-12)
    assert sec.iterations > cons.iterations
    # linear convergence: successive ratios of eta bounded away from zero
    eta = np.array(sec.residuals[1:])
    ratios = eta[1:] / eta[:-1]
    assert np.all(ratios < 1.0)
    assert np.median(ratios) > 1e-3


# Shipped reservoir case: E = 5 GPa, h = 0.02 m, so E/h = 2.5e11 Pa/m.
E_OVER_H = 5.0e9 / 0.02


def _stiff(ratio, tangent="consistent"):
    """The shipped reservoir with kn = kt = ratio * E/h, no step cutting."""
    kn = ratio * E_OVER_H
    keys = {"fractures.0.kn": kn, "fractures.0.kt": kn}
    text = build.case_text(build.file_case(CASE, **keys))
    model = build_model(loads_case(text, CASE))
    return NewtonSolver(model.problem, 1e-8, 30, tangent, max_step_cuts=0)


def test_penalty_above_the_measured_range_is_named_with_the_value_to_use():
    """kn = kt = 1e8 E/h (benchmarks/penalty_range.py: Newton stalls at eta
    about 5e-8 > 1e-8, round-off): the failure names both ratios and the
    largest measured value in Pa/m, 1e6 E/h = 2.5e17 Pa/m."""
    with pytest.raises(ConvergenceError) as info:
        _stiff(1e8).run(1)
    text = str(info.value)
    assert "kn*h/E up to 1.0e+08, kt*h/E up to 1.0e+08" in text
    assert "lower kn/kt to at most 2.5e+17 Pa/m (1e+06 E/h" in text
    assert "default 1000 E/h = 2.5e+14 Pa/m" in text
    assert text.count("kn*h/E") == 1


def test_penalty_at_the_top_of_the_measured_range_converges():
    """kn = kt = 1e6 E/h converges, and the default 1e3 E/h gives its slip
    to the 0.04 % of the maximum slip the failure message promises (measured
    6e-4 % here, 0.03 % on the shipped depleting reservoir)."""
    stiff = _stiff(1e6).run(1)[-1].contact.point_gt
    default = _stiff(1e3).run(1)[-1].contact.point_gt
    assert np.max(np.abs(default - stiff)) < 4e-4 * np.max(np.abs(stiff))
