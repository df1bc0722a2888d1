"""Newton control: load-step bisection and the ping-pong remedy.

- Bisection: a load step that fails is retried from the last committed state
  in halves.  The friction history must be exactly that of a run that takes
  the converged sub-steps as ordinary load steps: same answer to the last bit
  (so a failed attempt leaves no trace in the committed state).
- Ping-pong: points whose stick/slip branch alternates are held in stick
  until Newton converges; the true law is then restored and checked, so an
  accepted step satisfies the true Coulomb law and is the same solution as
  without the remedy.

Measured (reservoir 18 x 18, k_N h / E = 1e8, cohesion 2.5 MPa, secant
tangent, max_iterations = 8): the full step fails, the step is cut once, the
sub-steps converge at load factors [0.5, 1.0] (14 iterations), and the plain
run over those factors gives a bitwise-identical displacement.  (On 20 x 20:
5 cuts, sub-steps [0.5, 0.75, 0.875, 1.0], also bitwise identical.)
"""

from __future__ import annotations

import numpy as np
import pytest

import xfemslip.solve.newton as solver_module
from tests.support.matrix import (
    RESERVOIR,
    SLIP,
    STICK,
    block_text,
    block_threshold,
    reservoir_text,
    solve,
)
from xfemslip.contact.branches import force_branches
from xfemslip.errors import ConvergenceError
from xfemslip.solve import remedies
from xfemslip.solve.remedies import ping_pong

pytestmark = pytest.mark.verification

E, N = 5.0e9, 18


def stiff_cohesive_case():
    kn = 1.0e8 * E * N  # kn h / E = 1e8
    return reservoir_text(n=N, cohesion=2.5e6, kn=kn)


# Largest load increment a Newton attempt may take in the bisection test.
MAX_INCREMENT = 0.3


def test_bisection_keeps_the_friction_history_exact(monkeypatch):
    """A load step cut by bisection ends bitwise where the same sub-steps run
    as ordinary load steps end: a failed attempt leaves no trace (committed
    friction history, predictor state).

    The failures are forced: every Newton attempt runs in full (so it mutates
    whatever it mutates) and is then declared failed when it spans more than
    MAX_INCREMENT of the load.  A natural failure will not do: the secant
    tangent's stall on this stiff-penalty case (kn h / E = 1e8) is the
    round-off floor of eta, 1.3e-8 to 1.9e-8 against the tolerance 1e-8,
    which moves with every change of summation order (with eta = 5e-8 the
    full step converges uncut)."""
    text = stiff_cohesive_case()
    real = solver_module.NewtonSolver._newton

    def capped(self, u, lam, k, steps, contact=None):
        out = real(self, u, lam, k, steps, contact)
        if lam - self._lam_committed > MAX_INCREMENT + 1e-12:
            raise ConvergenceError(
                f"load step {k} did not converge: forced by the test",
                step=k,
                iteration=out[2].iterations,
                residual=1.0,
            )
        return out

    monkeypatch.setattr(solver_module.NewtonSolver, "_newton", capped)
    cut = solve(text, RESERVOIR, "consistent")
    assert cut.converged, cut.error
    step = cut.steps[-1]
    assert step.factors == [0.25, 0.5, 0.75, 1.0] and step.cuts == 4
    monkeypatch.undo()
    # the converged sub-steps as ordinary load steps: the same bits
    explicit = solve(text, RESERVOIR, "consistent", factors=step.factors)
    assert explicit.converged and explicit.cuts == 0
    np.testing.assert_array_equal(explicit.steps[-1].u, step.u)
    for name in ("slip_plastic", "state", "pt", "pn"):
        np.testing.assert_array_equal(
            getattr(explicit.steps[-1].contact, name), getattr(step.contact, name)
        )
    # premise: the sub-steps slip, so there is a friction history to keep
    assert np.any(step.contact.state == 2)
    # ... and the secant tangent agrees to the tolerance (without the
    # predictor; the near-rigid sliding of the last sub-step leaves the
    # displacements uncertain to a few 1e-4 at eta = 1e-8 otherwise)
    sec = solve(
        text,
        RESERVOIR,
        "secant",
        factors=step.factors,
        max_iterations=200,
        predictor=False,
    )
    scale = np.max(np.abs(step.u))
    assert np.max(np.abs(sec.steps[-1].u - step.u)) < 1e-5 * scale


def test_exhausted_bisection_says_what_was_tried():
    """Beyond the rigid-sliding threshold the block has no equilibrium."""
    text = block_text(shear=1.1 * block_threshold(10e6, 0.5, 0.0), friction=0.5)
    out = solve(text, RESERVOIR, "consistent", max_iterations=10, max_step_cuts=2)
    assert not out.converged
    assert "even after a fixed point on the normal traction" in out.error
    assert "cutting the load step 2 time(s)" in out.error
    assert "(sub-steps down to 0.25 of it)" in out.error
    assert "fractures[0] cuts the domain in two" in out.error
    assert "prescribe a displacement" in out.error


def _fail_true_law(monkeypatch, fail=1):
    """NewtonSolver._newton made to fail on its first ``fail`` calls under
    the true contact law (contact None); every call is recorded as (load
    factor, the law: "coulomb", "raised" (FIXED_POINT_START times the
    friction) or "tresca" (no friction, a finite cohesion))."""
    real = solver_module.NewtonSolver._newton
    calls = []

    def kind(self, contact):
        if contact is None:
            return "coulomb"
        c = self.p.contact
        if np.allclose(contact.friction, solver_module.FIXED_POINT_START * c.friction):
            return "raised"
        assert np.all(contact.friction == 0.0) and np.all(np.isfinite(contact.cohesion))
        return "tresca"

    def newton(self, u, lam, k, steps, contact=None):
        calls.append((lam, kind(self, contact)))
        if contact is None and sum(r == "coulomb" for _, r in calls) <= fail:
            raise ConvergenceError(
                f"load step {k} did not converge: forced by the test",
                step=k,
                iteration=3,
                residual=1.0,
            )
        return real(self, u, lam, k, steps, contact)

    monkeypatch.setattr(solver_module.NewtonSolver, "_newton", newton)
    return calls


def test_normal_traction_fixed_point_ends_at_the_newton_answer(monkeypatch):
    """A load step that Newton fails on is solved, before any cut, by the
    fixed point on the normal traction (Tresca problems, the Coulomb bound
    frozen at the last normal traction): it stops where the Coulomb law
    meets the Newton tolerance, so the answer is the step's, the same as
    Newton's to that tolerance; the next step goes on from it."""
    text = reservoir_text(n=12, friction=0.3, steps=2)
    plain = solve(text, RESERVOIR)
    assert plain.converged, plain.error
    calls = _fail_true_law(monkeypatch)
    fixed = solve(text, RESERVOIR)
    monkeypatch.undo()
    assert fixed.converged, fixed.error
    # step 1: the forced failure, the start under raised friction, then
    # Tresca problems only (accepted by the Coulomb residual, no Newton on
    # the Coulomb law); step 2 by Newton from there
    first = [r for lam, r in calls if lam == 0.5]
    assert first[:2] == ["coulomb", "raised"] and len(first) >= 4
    assert set(first[2:]) == {"tresca"}
    assert [r for lam, r in calls if lam == 1.0] == ["coulomb"]
    step = fixed.steps[0]
    assert step.cuts == 0 and step.fixed_point == len(first) - 2
    assert fixed.steps[1].fixed_point == 0
    # premise: the step slips, so the friction bound decides the answer
    assert np.any(plain.steps[0].contact.state == SLIP)
    for a, b in zip(plain.steps, fixed.steps, strict=True):
        scale = np.max(np.abs(a.u))
        assert np.max(np.abs(a.u - b.u)) <= 1e-6 * scale
        np.testing.assert_allclose(
            b.contact.slip_plastic,
            a.contact.slip_plastic,
            atol=1e-6 * np.max(np.abs(a.contact.slip_plastic)),
        )
        assert np.array_equal(a.contact.state, b.contact.state)
    # every Newton solve's iterations are counted (each logs its start too)
    assert len(step.residuals) == step.iterations + len(first) - 1


def test_anderson_acceleration_of_a_linear_fixed_point():
    """x = M x + b with a contraction M of ratio 0.95: the plain iteration
    gains a digit in about 45 iterations, Anderson over five differences
    converges in a few more than the dimension (Walker & Ni 2011)."""
    rng = np.random.default_rng(3)
    Q, _ = np.linalg.qr(rng.standard_normal((5, 5)))
    M = Q @ np.diag([0.95, 0.9, 0.5, -0.6, 0.2]) @ Q.T
    b = rng.standard_normal(5)
    exact = np.linalg.solve(np.eye(5) - M, b)
    X, G = [], []
    x = np.zeros(5)
    iterations = 0
    while np.linalg.norm(x - exact) > 1e-10 * np.linalg.norm(exact):
        X.append(x)
        G.append(M @ x + b - x)
        del X[:-6], G[:-6]
        x = solver_module._anderson(X, G)
        iterations += 1
        assert iterations <= 8
    # one iterate: the plain step x + g
    np.testing.assert_allclose(solver_module._anderson([b], [M @ b]), b + M @ b)


def test_failed_fixed_point_is_named_then_the_step_is_cut(monkeypatch):
    """Where the fixed point fails too, the step is cut as before (the fixed
    point once per load step), and the error names both."""
    text = reservoir_text(n=12, friction=0.3, steps=2)
    calls = _fail_true_law(monkeypatch, fail=1000)
    monkeypatch.setattr(solver_module, "FIXED_POINT_MAX", 3)
    out = solve(text, RESERVOIR, max_step_cuts=1)
    assert not out.converged and len(out.steps) == 0
    assert (
        "even after a fixed point on the normal traction (Tresca problems) and "
        "cutting the load step 1 time(s)" in out.error
    )
    # the full step, its fixed point (the start and 3 Tresca problems, none
    # meeting the tolerance of a case that slips), then the half step
    assert calls == [(0.5, "coulomb"), (0.5, "raised")] + [(0.5, "tresca")] * 3 + [
        (0.25, "coulomb")
    ]


def test_frictionless_failure_skips_the_fixed_point(monkeypatch):
    """No friction bound to freeze: the failure is reported as it was."""
    text = reservoir_text(n=12, friction=0.0)
    calls = _fail_true_law(monkeypatch, fail=1000)
    out = solve(text, RESERVOIR, max_step_cuts=0)
    assert not out.converged
    assert "forced by the test" in out.error
    assert "fixed point" not in out.error
    assert calls == [(1.0, "coulomb")]


def test_cycling_detection_and_frozen_law():
    A, B, O_ = STICK, SLIP, 0
    seq = [np.array([A, A, O_, B]), np.array([B, A, A, B])] * 3
    mask = ping_pong(seq)
    assert mask.tolist() == [True, False, False, False]
    assert ping_pong(seq[1:]) is None  # five iterates: not yet three periods
    # open <-> closed is left to the normal law (never frozen)
    assert ping_pong([np.array([A]), np.array([O_])] * 3) is None


def test_frozen_points_stick_but_may_open():
    text = reservoir_text(n=12, friction=0.1)
    out = solve(text, RESERVOIR)
    model, step = out.model, out.steps[-1]
    c = model.contact
    res = step.contact
    assert np.mean(res.state == SLIP) > 0.8  # premise
    frozen = np.zeros(c.n, bool)
    frozen[::2] = True
    law = force_branches(c, stick_at=frozen)
    # committed history is now the step's; from the previous one (zeros) the
    # same u evaluates stick at the frozen points, slip elsewhere
    zero = np.zeros(c.n)
    law.slip_committed = zero
    got = law.evaluate(step.u, 0, zero, zero)
    closed = got.state != 0
    assert np.all(got.state[frozen & closed] == STICK)
    np.testing.assert_allclose(
        got.pt[frozen & closed], c.kt[frozen & closed] * got.gt[frozen & closed]
    )
    assert c.cohesion.max() < np.inf  # the real contact set is untouched


def test_ping_pong_remedy_accepts_only_the_true_law(monkeypatch):
    """The freeze -> converge -> release -> check cycle, forced: with a
    detector of one period every switch counts as cycling, so the first
    stick -> slip switches of the reservoir fracture are frozen in stick.  The
    accepted step must still be the one found without the remedy, on the
    true Coulomb law (measured on 20 x 20: 1 freeze, 3 iterations against 2).
    With the default (three periods) no case of the stress matrix froze."""
    text = reservoir_text(n=20, angle=45.0, friction=0.1)
    monkeypatch.setattr(remedies, "PINGPONG_PERIODS", 1)
    # without the stick/slip predictor, which lands on the slip set in one
    # solve and so leaves nothing to freeze
    frozen = solve(text, RESERVOIR, predictor=False)
    monkeypatch.setattr(remedies, "PINGPONG_MAX_FREEZES", 0)
    free = solve(text, RESERVOIR, predictor=False)
    assert frozen.converged and free.converged
    assert frozen.freezes >= 1 and free.freezes == 0
    a, b = frozen.steps[-1], free.steps[-1]
    np.testing.assert_array_equal(a.contact.state, b.contact.state)
    scale = np.max(np.abs(b.u))
    assert np.max(np.abs(a.u - b.u)) < 1e-7 * scale
    # the true Coulomb law at every point of the accepted step
    c = frozen.model.contact
    bound = c.cohesion - c.friction * a.contact.pn
    closed = a.contact.state != 0
    assert np.all(np.abs(a.contact.pt[closed]) <= bound[closed] * (1 + 1e-12))
    slipping = a.contact.state == SLIP
    np.testing.assert_allclose(
        np.abs(a.contact.pt[slipping]), bound[slipping], rtol=1e-12
    )


def test_a_non_finite_residual_is_a_convergence_error_not_a_crash():
    """A residual with inf or NaN (a forced law gone wrong) stops the
    Newton solve with a ConvergenceError that names it, before the linear
    solver sees it (SciPy's dense LU raises ValueError on it)."""
    text = reservoir_text(n=12, friction=0.3)
    model = solve(text, RESERVOIR).model
    solver = solver_module.NewtonSolver(model.problem, 1e-8, 30, "consistent")
    c = model.contact
    u = np.zeros(model.problem.n_dofs)
    res = c.evaluate(u, solver.mode, c.pt_committed, c.gt_committed)
    r, _ = solver._residual(u, 1.0, res)
    r[0] = np.nan
    with pytest.raises(ConvergenceError, match="the residual is not finite"):
        solver._solve(res, r, 1, 4, float(np.linalg.norm(r)))
