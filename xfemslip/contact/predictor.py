"""A first guess of the stick/slip set of a load step (fewer Newton solves).

Within a fixed assignment of contact branches (open, stick, slip forward,
slip backward) the penalty Coulomb law is affine in the jump (kernels.contact:
p_N = k_N g_N + p_N0; stick p_T = k_T (g_T - g_T^p); slip p_T = s (c - f p_N)),
so with the consistent tangent one Newton solve from any point lands on the
exact solution of that branch.  Newton started from the previous step
evaluates the law there, where every closed face is stuck: its first solve
has the all-stick tangent, the second the slip tangent.  If the first solve
already uses the branches of the converged state, the step converges in one
solve followed by a residual check.

The guess: the committed tractions of each contact patch plus the increment
of the far-field stress (``loading.stress`` less ``loading.initial_stress``,
when the case has a ``loading.stress``) resolved on the patch,
p_N = p_N,committed + d_lambda n.sigma.n and
p_T = p_T,committed + d_lambda t.sigma.n, put through the return map's
tests (open if p_N > 0, slip with the sign of p_T if |p_T| > c - f p_N).
The far-field stress is the stress of the uncracked body only when every
loaded edge carries it, so this is a guess, never an answer: the predicted
branches only choose the tangent and residual of the first solve
(:func:`predicted_law`), the true return map then decides, and a wrong guess
costs Newton iterations, never accuracy.  The converged state satisfies the
true law to the Newton tolerance as without the guess.
"""

from __future__ import annotations

import numpy as np

from xfemslip.contact.branches import force_branches
from xfemslip.contact.interface import ContactSet
from xfemslip.conventions import OPEN, SLIP, STICK


def stress_increment(loading):
    """(xx, yy, xy) [Pa] of the far-field stress added from load factor 0 to
    1: ``loading.stress`` less ``loading.initial_stress`` (the edges carry
    lambda (sigma - sigma0) . n, boundary.traction_load), or None without a
    ``loading.stress``."""
    if loading.stress is None:
        return None
    sig = np.array(loading.stress, float)
    if loading.initial_stress is not None:
        sig = sig - np.array(loading.initial_stress, float)
    return tuple(float(v) for v in sig)


def predict_state(c: ContactSet, pn_committed, stress, d_lambda):
    """(state, sign) of every patch predicted for a load increment.

    c : the contact set (normals, tangents, friction, cohesion, committed p_T);
    pn_committed : (m,) committed normal traction [Pa] (p_N0 before step 1);
    stress : far-field stress added from load factor 0 to 1, (xx, yy, xy)
        [Pa] (:func:`stress_increment`), or None (no
        increment: the committed state is the guess, which is what a
        displacement-driven step of a monotonic loading needs);
    d_lambda : load-factor increment of the step.
    Returns state (m,) int8 OPEN | STICK | SLIP and sign (m,) +-1 of the slip.
    """
    pn, pt = pn_committed, c.pt_committed
    if stress is not None:
        sxx, syy, sxy = (float(v) for v in stress)
        sig = np.array([[sxx, sxy], [sxy, syy]])
        trac = c.normal @ sig  # sigma . n (sigma symmetric)
        pn = pn + d_lambda * np.einsum("mk,mk->m", trac, c.normal)
        pt = pt + d_lambda * np.einsum("mk,mk->m", trac, c.tangent)
    bound = c.shear_bound(pn)
    # a committed slipping patch sits on its bound (|p_T| = bound up to
    # round-off): it keeps slipping unless the increment moves it inside
    on_bound = (c.state_committed == SLIP) & (
        np.abs(pt) >= bound - 1.0e-12 * np.abs(bound)
    )
    slips = (np.abs(pt) > bound) | on_bound
    state = np.where(pn > 0.0, OPEN, np.where(slips, SLIP, STICK)).astype(np.int8)
    sign = np.where(pt >= 0.0, 1.0, -1.0)
    return state, sign


def predicted_law(c: ContactSet, state, sign) -> ContactSet:
    """The contact set whose return map gives the predicted branch
    (:func:`xfemslip.contact.branches.force_branches`): open, stick or slip
    with ``sign`` as ``state`` says.  A closed branch whose normal jump is
    open at the evaluation point stays open: that patch is simply not
    predicted.  A slip-weakening patch predicted to slip is not forced
    either: its slip branch depends on the slip increment, which a forced
    branch does not know (force_branches), so the true law decides it.
    Never committed.
    """
    is_slip = (state == SLIP) & ~c.weakens
    return force_branches(
        c,
        open_at=state == OPEN,
        stick_at=state == STICK,
        slip_at=is_slip,
        sign=sign[is_slip],
    )
