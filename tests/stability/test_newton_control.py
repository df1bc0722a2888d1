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
    assert "even after cutting the load step" in out.error
    assert "(sub-steps down to 0.25 of it)" in out.error
    assert "fractures[0] cuts the domain in two" in out.error
    assert "prescribe a displacement" in out.error


def _fail_first_true_law(monkeypatch, fail=1):
    """NewtonSolver._newton made to fail on its first ``fail`` calls under
    the true contact law (contact None); the calls, (load factor, friction
    factor or None), are recorded."""
    real = solver_module.NewtonSolver._newton
    calls = []

    def newton(self, u, lam, k, steps, contact=None):
        raised = (
            None
            if contact is None
            else float(np.max(contact.friction / self.p.contact.friction))
        )
        calls.append((lam, raised))
        if contact is None and sum(r is None for _, r in calls) <= fail:
            raise ConvergenceError(
                f"load step {k} did not converge: forced by the test",
                step=k,
                iteration=3,
                residual=1.0,
            )
        return real(self, u, lam, k, steps, contact)

    monkeypatch.setattr(solver_module.NewtonSolver, "_newton", newton)
    return calls


def test_friction_continuation_ends_at_the_plain_answer(monkeypatch):
    """A load step that fails after bisection is solved again by
    continuation in friction (1.4, 1.3, ... times it, the true law last):
    the answer is the step's under the true law, the same as the plain
    Newton solve's to the tolerance, and nothing of the raised stages is
    committed before it."""
    text = reservoir_text(n=12, friction=0.3, steps=2)
    plain = solve(text, RESERVOIR, max_step_cuts=0)
    assert plain.converged, plain.error
    calls = _fail_first_true_law(monkeypatch)
    cont = solve(text, RESERVOIR, max_step_cuts=0)
    monkeypatch.undo()
    assert cont.converged, cont.error
    # step 1: the forced failure, then 1.4, 1.3, 1.2, 1.1 times the
    # friction and the true law; step 2 plainly
    factors = [r for lam, r in calls if lam == 0.5]
    assert factors[0] is None and factors[-1] is None
    np.testing.assert_allclose(factors[1:-1], [1.4, 1.3, 1.2, 1.1], rtol=1e-12)
    assert [r for lam, r in calls if lam == 1.0] == [None]
    # premise: the step slips, so the friction decides the answer
    assert np.any(plain.steps[0].contact.state == SLIP)
    for a, b in zip(plain.steps, cont.steps, strict=True):
        scale = np.max(np.abs(a.u))
        assert np.max(np.abs(a.u - b.u)) <= 1e-7 * scale
        np.testing.assert_allclose(
            b.contact.slip_plastic,
            a.contact.slip_plastic,
            atol=1e-7 * np.max(np.abs(a.contact.slip_plastic)),
        )
        assert np.array_equal(a.contact.state, b.contact.state)
    # the stages' iterations are counted (each stage logs its start too)
    first = cont.steps[0]
    assert len(first.residuals) == first.iterations + 5


def test_failed_friction_continuation_is_named_and_keeps_the_steps(monkeypatch):
    """Where the continuation fails too, the error says that bisection and
    the continuation were tried, and the converged steps are kept."""
    text = reservoir_text(n=12, friction=0.3, steps=2)
    calls = _fail_first_true_law(monkeypatch, fail=1000)
    out = solve(text, RESERVOIR, max_step_cuts=1)
    assert not out.converged and len(out.steps) == 0
    assert "even after cutting the load step 1 time(s)" in out.error
    assert "and a continuation in friction (from 1.4 times it)" in out.error
    # the stages went down to the true law, were retried at half the
    # decrement from the last converged one, three times, then gave up
    tried = [r for _, r in calls if r is not None]
    np.testing.assert_allclose(
        tried, [1.4, 1.3, 1.2, 1.1, 1.05, 1.025, 1.0125], rtol=1e-12
    )


def test_frictionless_failure_skips_the_continuation(monkeypatch):
    """No friction to continue in: the failure is reported as it was."""
    text = reservoir_text(n=12, friction=0.0)
    calls = _fail_first_true_law(monkeypatch, fail=1000)
    out = solve(text, RESERVOIR, max_step_cuts=0)
    assert not out.converged
    assert "forced by the test" in out.error
    assert "continuation" not in out.error
    assert all(r is None for _, r in calls) and len(calls) == 1


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
