"""Newton: the consistent tangent is exact once the stick/slip set has settled,
the secant tangent (paper eq. 28) converges to the same answer, more slowly."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from xfemslip.case import loads_case
from xfemslip.simulation import build_model
from xfemslip.solver import NewtonSolver

CASE = Path(__file__).resolve().parents[2] / "cases" / "reservoir_depletion.toml"


def _solve(tangent, steps=1, n=20, friction=0.1):
    text = CASE.read_text().replace("elements = [50, 50]", f"elements = [{n}, {n}]")
    text = text.replace("friction = 0.1", f"friction = {friction}")
    text = text.replace("steps = 1", f"steps = {steps}")
    model = build_model(loads_case(text, CASE))
    # without the stick/slip predictor: these tests watch Newton's own
    # iterates settle (the predictor's first solve lands on the final set
    # directly; tests/unit/test_predictor.py)
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
        # set, so iterate i is exact up to round-off
        for i in range(2, len(eta)):
            if sw[i] == 0:
                assert eta[i] < 1e-12, (i, eta, sw)
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
