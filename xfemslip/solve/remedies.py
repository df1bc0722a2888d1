"""Newton's remedies for a stick/slip set that does not settle.

Each linearization of the frictional contact law can be fine and Newton still
fail to settle which contact patches stick and which slip: a point may
alternate between two branches of the law, a full Newton step may jump a
patch over its narrow stick band from forward to backward slip, and next to
fracture junctions a patch may have no consistent branch while its
neighbours keep theirs.  The solver (xfemslip.solve.newton) detects these
between its iterations with the functions here:

- ping-pong (``ping_pong``): points whose branch alternates A, B, A, B, ...
  are frozen in stick;
- slip reversals (``slip_reversals``): patches the full step takes from
  forward to backward slip or back are held in stick, the state between;
- local branch search (``local_search``): a patch that keeps reversing after
  its holds gets, with its neighbours, a consistent stick/slip set
  (xfemslip.contact.branches).

Each remedy changes the law only until Newton converges; the solver then
restores the true law and goes on from there, so an accepted step always
satisfies it.
"""

from __future__ import annotations

import dataclasses
import logging

import numpy as np

from xfemslip.contact import branches as local_branches
from xfemslip.contact.branches import force_branches
from xfemslip.conventions import OPEN, SLIP, SLIP_BACKWARD, TANGENT_CONSISTENT
from xfemslip.fem.assembly import coo_block

logger = logging.getLogger(__name__)

# Ping-pong remedy: a contact point whose branch of the law (stick, slip +t,
# slip -t) alternates A, B, A, B, A, B over six successive iterates is
# cycling.  It is then frozen in STICK (force_branches) until Newton
# converges; the true law is then restored and Newton continues from there,
# so an accepted step always satisfies the true law.  At most
# PINGPONG_MAX_FREEZES freezes per attempt; after that the attempt fails and
# the load step is bisected.
PINGPONG_MAX_FREEZES = 2
# Periods A, B of the alternation that count as cycling (3: six iterates).
PINGPONG_PERIODS = 3
# Slip-reversal remedy (slip_reversals): times a patch may be held
# in stick within one Newton solve.  Once (a patch that reverses again after
# the release is let through) left 5 of the 20 allow-DFN seeds failing with
# the predictor on; without a limit a patch can be held and released
# forever (seed 1, predictor off); 2 and 3 converge on all 20 seeds both
# ways (docs/networks.md, "Newton on networks").
REVERSAL_HOLDS = 2
# Local branch searches (xfemslip.contact.branches) per Newton solve: a patch
# that reverses its slip again after REVERSAL_HOLDS holds has no consistent
# branch while its neighbours keep theirs (refined DFN realizations:
# docs/performance.md, "Fracture networks", refined meshes); the
# stick/slip set of it and its neighbours is then searched.
LOCAL_SEARCHES = 2


def regimes(state, pt):
    """Branch of the contact law at each point: open, stick, slip forward (+t),
    slip backward.  A switch between any two changes the tangent, so it is what
    the log and the ConvergenceError count as a stick/slip switch."""
    return np.where(state == SLIP, np.where(pt >= 0.0, SLIP, SLIP_BACKWARD), state)


def ping_pong(history):
    """Points whose tangential branch alternated A, B, A, B, ... over the last
    PINGPONG_PERIODS * 2 iterates (A != B, both closed), or None."""
    n = 2 * PINGPONG_PERIODS
    if len(history) < n:
        return None
    last = history[-n:]
    a, b = last[-2], last[-1]
    mask = (a != b) & (a != OPEN) & (b != OPEN)
    for i, regime in enumerate(last):
        mask &= regime == (a if i % 2 == 0 else b)
    return mask if mask.any() else None


def slip_reversals(law, u, du, free, mode, regime, pt_prev, gt_prev, held, scratch):
    """Patches whose slip the full Newton step reverses, or None.

    A patch slipping forward at u and backward at u - du (or the other way
    round) jumps over its stick band, |g_T - g_T^p| <= (c - f p_N) / k_T,
    which is narrow (about 1e-6 m with stiff penalties) however long the
    step.  Next to fracture junctions the next step often reverses it
    back (the slip tangent has no tangential stiffness, d p_T / d g_T = 0,
    so nothing in the linearization holds the patch), and the line search
    then only shortens steps that keep cycling.  The continuous path
    between the two slip branches passes through stick: those patches are
    held in stick (force_branches) until Newton converges, then the true law
    is restored and checked, as for ping-pong.  A patch is held at most
    REVERSAL_HOLDS times per Newton solve (``held``, counts).  Returns
    (patches to hold, or None; patches that reverse again after their
    holds, or None): for the latter the stick/slip set of them and their
    neighbours is searched (local_search; a patch with no consistent
    branch of its own, refined DFN meshes); when the search finds nothing,
    the step is taken.  Consistent tangent only.
    """
    if mode != TANGENT_CONSISTENT:
        return None, None
    trial = u.copy()
    trial[free] -= du
    res = law.evaluate(trial, mode, pt_prev, gt_prev, scratch=scratch())
    new = regimes(res.state, res.pt)
    mask = ((regime == SLIP) & (new == SLIP_BACKWARD)) | (
        (regime == SLIP_BACKWARD) & (new == SLIP)
    )
    stubborn = mask & (held >= REVERSAL_HOLDS)
    mask &= held < REVERSAL_HOLDS
    return (mask if mask.any() else None), (stubborn if stubborn.any() else None)


def cluster_base(c, law, mask):
    """``law`` with the patches of ``mask`` given back their own law of
    ``c``, on which a local search forces its branches: a patch held in
    stick by a hold gets its finite bound back (a forced slip needs it),
    and one forced to slip by an earlier search its own committed slip
    (held in stick with that search's infinite slip, its traction would be
    infinite: a 100-fracture network's Newton solve stopped on it with
    NaN in the linear solve)."""
    return dataclasses.replace(
        law,
        cohesion=np.where(mask, c.cohesion, law.cohesion),
        cohesion_dynamic=np.where(mask, c.cohesion_dynamic, law.cohesion_dynamic),
        slip_committed=np.where(mask, c.slip_committed, law.slip_committed),
    )


def local_search(c, law, u, res, r, stubborn, c_dofs, K_ff, free, mode):
    """The law with the branches of ``stubborn`` and their neighbours
    forced to a consistent local set (xfemslip.contact.branches), or None
    when the search finds none or only the current set.

    c : the true contact law; c_dofs, K_ff, free : its dofs on, the bulk
    stiffness of, and the free dofs of the Newton system; mode : the tangent.
    """
    # slip-weakening patches stay out: on them the slip branch is not affine
    # in the jump (the bound softens with the slip increment), which the
    # search's closed form assumes; Newton handles them under the true law
    constant = ~c.weakens
    first = np.nonzero(stubborn & constant)[0]
    if first.size == 0:
        return None
    near = local_branches.neighbours(c_dofs, K_ff, stubborn)
    # open neighbours stay out: the search has no open branch, and its
    # Woodbury form assumes a closed (stick) block for every member
    rest = np.nonzero(near & ~stubborn & constant & (res.state != OPEN))[0]
    idx = np.concatenate([first, rest])[: local_branches.MAX_CLUSTER]
    mask = np.zeros(c.n, bool)
    mask[idx] = True
    stick = force_branches(law, stick_at=mask).evaluate(
        u, mode, law.pt_committed, law.gt_committed
    )
    # the tangent of res with the cluster's blocks in stick, formed in
    # the stick evaluation's array (not a copy of res.blocks: one array
    # of the padded blocks less, memory.NEWTON_BLOCKS)
    blocks = stick.blocks
    np.copyto(blocks, res.blocks, where=~mask[:, None, None])
    K = K_ff + coo_block(c_dofs, blocks, free.size, c.kernels)
    branches = local_branches.search(c, c_dofs, K, u[free], res, r, idx)
    if branches is None:
        logger.info("local branch search: no consistent stick/slip set")
        return None
    now = local_branches.current_branches(res, idx)
    if np.array_equal(branches, now):
        return None
    logger.info(
        "local branch search over %d patch(es): %d change branch",
        idx.size,
        int(np.count_nonzero(branches != now)),
    )
    base = cluster_base(c, law, mask)
    branches = np.asarray(branches)
    moving = branches != 0
    return force_branches(
        base, stick_at=idx[~moving], slip_at=idx[moving], sign=branches[moving]
    )
