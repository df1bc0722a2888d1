"""The stick/slip predictor (xfemslip/contact/predictor.py) saves Newton solves and
never changes the converged answer.

Reference for "the same answer": the run without the predictor.  Both runs
end on an exact solve of the same affine branch of the contact law, so they
agree to the round-off of that solve: the standard displacements, the
tractions and the plastic slip to 1e-9 relative (the penalty system's
condition number times machine epsilon; the enriched dofs themselves are less
well determined, only their jumps are physical), the stick/slip states
exactly.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from tests.support.casegen import fracture_case
from xfemslip import conventions
from xfemslip.case import build, loads_case
from xfemslip.contact.predictor import predict_state, predicted_law, stress_increment
from xfemslip.conventions import SLIP, STICK
from xfemslip.reference.closed_form import slip_window
from xfemslip.simulation import build_model
from xfemslip.solve.newton import NewtonSolver

ROOT = Path(__file__).resolve().parents[3]
RESERVOIR = ROOT / "cases" / "reservoir_depletion.toml"
PLATE = ROOT / "cases" / "liu_borja_plate.toml"


def _reservoir(n=20, angle=45.0, friction=0.1, steps=1):
    keys = {
        "mesh.elements": [n, n],
        "fractures.0.angle": angle,
        "fractures.0.friction": friction,
        "loading.steps": steps,
    }
    return loads_case(build.case_text(build.file_case(RESERVOIR, **keys)), RESERVOIR)


def _run(spec, predictor, steps=None, problem_change=None, path=None):
    model = build_model(spec)
    if problem_change:
        model.problem = dataclasses.replace(model.problem, **problem_change)
    solver = NewtonSolver(model.problem, 1e-10, 60, "consistent", predictor=predictor)
    if path is None:
        solver.run(steps or spec.loading.steps)
    else:
        solver.run_path(path)
    return solver, model


def _same_answer(a, b, model):
    """The converged steps of two solvers agree (see the module doc)."""
    n_std = 2 * model.mesh.nodes.shape[0]
    for x, y in zip(a.completed, b.completed, strict=True):
        assert x.residuals[-1] <= 1e-10 and y.residuals[-1] <= 1e-10
        scale = np.abs(x.u[:n_std]).max()
        assert np.abs(x.u[:n_std] - y.u[:n_std]).max() <= 1e-9 * scale
        # the states agree wherever they are defined: a patch whose traction
        # sits on the Coulomb bound to round-off is both stuck and slipping
        c = model.problem.contact
        bound = c.cohesion - c.friction * x.contact.pn
        clear = np.abs(np.abs(x.contact.pt) - bound) > 1e-9 * np.abs(bound)
        np.testing.assert_array_equal(x.contact.state[clear], y.contact.state[clear])
        for name in ("pn", "pt", "slip_plastic"):
            p, q = getattr(x.contact, name), getattr(y.contact, name)
            assert np.abs(p - q).max() <= 1e-9 * max(np.abs(p).max(), 1e-30), name


def _solves(solver):
    return [s.iterations for s in solver.completed]


def test_reservoir_converges_in_one_solve_per_step():
    """All patches slip; the far-field stress predicts it: one solve per step
    (against two), one factorization for the whole 3-step run."""
    spec = _reservoir(steps=3)
    plain, model = _run(spec, False)
    guess, _ = _run(spec, True)
    _same_answer(plain, guess, model)
    assert np.all(guess.completed[-1].contact.state == SLIP)
    assert _solves(plain) == [2, 2, 2]
    assert _solves(guess) == [1, 1, 1]
    assert [s.predicted for s in guess.completed] == [1, 1, 1]
    assert guess.linear.stats["factorizations"] == 1
    assert guess.linear.stats["solves"] == 3


def test_stuck_fracture_takes_one_solve_and_no_guess():
    """Friction above the slip tendency (tau / -sigma_n = 1/3 at 45 deg): the
    predicted set is the all-stick set of the first iterate, so the guess is
    not used and the step is one solve and one residual check."""
    spec = _reservoir(friction=0.6)
    plain, model = _run(spec, False)
    guess, _ = _run(spec, True)
    _same_answer(plain, guess, model)
    assert np.all(guess.completed[-1].contact.state == STICK)
    assert _solves(plain) == _solves(guess) == [1]
    assert guess.completed[-1].predicted == 0
    st = guess.linear.stats  # shortest path: one factorization, no Krylov
    assert st["factorizations"] == 1 and st["krylov_iterations"] == 0


@pytest.mark.parametrize("edge", [0, 1])
@pytest.mark.parametrize("offset", [-0.5, 0.5])
def test_slip_window_edges(edge, offset):
    """Just inside and just outside both edges of the closed-form slip window:
    same states and fields; one solve wherever the crack slips."""
    lo_hi = slip_window(40.0e6, 20.0e6, 0.1)
    beta = lo_hi[edge] + (offset if edge == 0 else -offset)  # > 0: inside
    spec = _reservoir(angle=90.0 - beta)  # sigma_1 is vertical
    plain, model = _run(spec, False)
    guess, _ = _run(spec, True)
    _same_answer(plain, guess, model)
    slips = np.any(guess.completed[-1].contact.state == SLIP)
    assert slips == (offset > 0)
    assert _solves(guess) == [1]
    assert _solves(plain) == [2 if slips else 1]


def test_wrong_guess_costs_iterations_not_accuracy():
    """A far-field stress with sigma_1 and sigma_3 swapped predicts slip with
    the wrong sign everywhere: the answer is unchanged, Newton needs more
    solves than with the right guess."""
    spec = _reservoir()
    plain, model = _run(spec, False)
    wrong, _ = _run(spec, True, problem_change={"load_stress": (-40.0e6, -20.0e6, 0.0)})
    right, _ = _run(spec, True)
    _same_answer(plain, wrong, model)
    assert wrong.completed[-1].predicted == 1
    assert _solves(wrong)[0] > _solves(right)[0] == 1


@pytest.mark.parametrize("points", [[[1.5, 1.5], [4.5, 4.8]], [[1.0, 0.6], [5.0, 4.5]]])
def test_inclined_crack_near_a_clamped_edge(points):
    """Bottom edge clamped, sides free: the stress at the crack is not the
    far-field stress of the case file (sigma_xx is about 0, not -20 MPa), so
    the guess is an approximation; here it is right (the crack slips
    throughout) and the answer is unchanged."""
    spec = fracture_case(points, tip="branch", n=12, friction=0.3)
    plain, model = _run(spec, False)
    guess, _ = _run(spec, True)
    _same_answer(plain, guess, model)
    assert guess.completed[-1].predicted == 1
    assert _solves(plain) == [2] and _solves(guess) == [1]


def test_unloading_and_reloading():
    """Load to 1, unload to 0.3 (the crack sticks again), reload to 1 (it
    slips again, every patch ending on its bound).  The answer is unchanged;
    the unloading step takes one solve with the guess.  Without it the
    first full step reverses the slip of the patches (forward to backward,
    over the stick band); they are held in stick and the step is solved again
    (remedies.slip_reversals: 2 solves; before that remedy the plain iterates
    wandered between the sets for 46 iterations)."""
    plain, model = _run(_reservoir(friction=0.2), False, path=[1.0, 0.3, 1.0])
    guess, _ = _run(_reservoir(friction=0.2), True, path=[1.0, 0.3, 1.0])
    _same_answer(plain, guess, model)
    assert np.all(guess.completed[1].contact.state == STICK)
    assert _solves(guess) == [1, 1, 1]
    assert [s.reversals for s in guess.completed] == [0, 0, 0]
    assert plain.completed[1].reversals == 1 and _solves(plain)[1] == 1


def test_displacement_driven_steps_use_the_committed_state():
    """cases/liu_borja_plate.toml (no loading.stress, 5 steps): from step 2
    the committed slip set is the guess; the plate slips from step 1 on."""
    text = build.case_text(build.file_case(PLATE, **{"mesh.elements": [16, 16]}))
    spec = loads_case(text, PLATE)
    plain, model = _run(spec, False)
    guess, _ = _run(spec, True)
    _same_answer(plain, guess, model)
    assert [s.predicted for s in guess.completed] == [0, 1, 1, 1, 1]
    assert _solves(guess)[1:] == [1, 1, 1, 1]
    assert sum(_solves(guess)) < sum(_solves(plain))


def test_predicted_law_is_the_true_law_on_its_branch():
    """At the converged displacement, the law forced to the converged states
    gives the same force, tractions and tangent as the true return map; and
    its tangent is the exact derivative of its force (central differences:
    the law is affine on the branch)."""
    solver, _ = _run(_reservoir(), False)
    step = solver.completed[-1]
    c = build_model(_reservoir()).contact  # the history before the step
    mode = conventions.TANGENT_CONSISTENT
    true = c.evaluate(step.u, mode, c.pt_committed, c.gt_committed)
    sign = np.where(true.pt >= 0.0, 1.0, -1.0)
    forced = predicted_law(c, true.state, sign).evaluate(
        step.u, mode, c.pt_committed, c.gt_committed
    )
    for name in ("force", "blocks", "pn", "pt", "slip_plastic"):
        np.testing.assert_allclose(
            getattr(forced, name), getattr(true, name), rtol=1e-12, atol=0.0
        )
    np.testing.assert_array_equal(forced.state, true.state)
    # FD check of the forced law's tangent along a random direction
    rng = np.random.default_rng(3)
    d = rng.standard_normal(step.u.size) * 1e-9
    law = predicted_law(c, true.state, sign)
    fp = law.evaluate(step.u + d, mode, c.pt_committed, c.gt_committed).force
    fm = law.evaluate(step.u - d, mode, c.pt_committed, c.gt_committed).force
    Kd = c.tangent_matrix(forced) @ d
    np.testing.assert_allclose(
        (fp - fm) / 2.0, Kd, rtol=1e-6, atol=1e-9 * np.abs(Kd).max()
    )


def test_predict_state_closed_form():
    """45 deg plane, sigma = (-20, -40, 0) MPa: sigma_n = -30, |tau| = 10 MPa;
    it slips for f < 1/3 with the sign of tau, sticks above, opens in tension."""
    c = build_model(_reservoir()).contact
    m = c.n
    pn0 = np.zeros(m)
    state, sign = predict_state(c, pn0, (-20.0e6, -40.0e6, 0.0), 1.0)
    tau = np.einsum("mk,kl,ml->m", c.tangent, np.diag([-20.0e6, -40.0e6]), c.normal)
    assert np.allclose(np.abs(tau), 10.0e6)
    assert np.all(state == SLIP) and np.all(sign == np.sign(tau))
    c.friction[:] = 0.34
    state, _ = predict_state(c, pn0, (-20.0e6, -40.0e6, 0.0), 1.0)
    assert np.all(state == STICK)
    state, _ = predict_state(c, pn0, (1.0e6, 1.0e6, 0.0), 1.0)
    assert np.all(state == 0)  # OPEN


def test_no_fracture_is_one_direct_solve():
    """Without a fracture a run is one factorization and one back-substitution
    (no Krylov, no band) and equals the direct solution of K u = F."""
    import scipy.sparse.linalg as spla

    keys = {"mesh.elements": [16, 16], "fractures": None}
    text = build.case_text(build.file_case(RESERVOIR, **keys))
    solver, model = _run(loads_case(text, RESERVOIR), True)
    st = solver.linear.stats
    assert _solves(solver) == [1] and st["solves"] == 1
    assert st["factorizations"] == 1 and st["krylov_iterations"] == 0
    p = model.problem
    u = np.zeros(p.n_dofs)
    u[p.fixed] = p.fixed_values
    free = solver.free
    u[free] = spla.spsolve(solver.K_ff.tocsc(), (p.F_unit - p.K @ u)[free])
    got = solver.completed[-1].u
    assert np.abs(got - u).max() <= 1e-10 * np.abs(u).max()


def test_initial_stress_is_not_a_load():
    """The edges carry lambda (sigma - sigma0) . n (boundary.traction_load),
    so the far-field increment that the predictor resolves on the patches is
    loading.stress less loading.initial_stress; the in-situ traction is in
    the committed tractions already.  With sigma0 = sigma there is no
    increment: the step converges at once, without a guess (the friction is
    raised to 0.5 so that the in-situ traction, |tau| / -sigma_n = 1/3, is
    admissible: with the case's 0.1 the first step would release the excess,
    ContactSet.in_situ_force)."""
    keys = {"mesh.elements": [16, 16], "fractures.0.friction": 0.5}

    def with_initial(xx, yy):
        initial = {"loading.initial_stress": {"xx": xx, "yy": yy, "xy": 0.0}}
        text = build.case_text(build.file_case(RESERVOIR, **keys, **initial))
        return loads_case(text, RESERVOIR)

    spec = with_initial(-10.0e6, -10.0e6)
    assert stress_increment(spec.loading) == (-10.0e6, -30.0e6, 0.0)
    assert build_model(spec).problem.load_stress == (-10.0e6, -30.0e6, 0.0)
    assert stress_increment(_reservoir().loading) == (-20.0e6, -40.0e6, 0.0)
    spec = with_initial(-20.0e6, -40.0e6)
    assert stress_increment(spec.loading) == (0.0, 0.0, 0.0)
    plain, model = _run(spec, False)
    guess, _ = _run(spec, True)
    _same_answer(plain, guess, model)
    assert _solves(guess) == _solves(plain) == [0]
    assert guess.completed[-1].predicted == 0
