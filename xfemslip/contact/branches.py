"""Local branch search: a consistent stick/slip set for a small cluster of
contact patches (NewtonSolver, for patches that keep reversing their slip).

Within a fixed branch (stick, slip forward, slip backward) the penalty
Coulomb law of a patch is affine in its jump (g_N, g_T):
stick p = (k_N g_N + p_N0, k_T (g_T - g_T^p)); slip s = +-1
p = (k_N g_N + p_N0, s (c - f (k_N g_N + p_N0))).  With every other patch kept
on its branch the whole residual is affine too, so for each of the 3^k branch
combinations of a cluster of k patches the exact solution follows from a
(2k x 2k) system: with K' the tangent with the cluster in stick (never
singular where the cluster holds a fragment of the body),
M = G K'^-1 G^T (G: the jump rows of the cluster) and S = diag(k_N, k_T),

    (I + M W (A - S)) d = -G K'^-1 r0 - M W (A g + a),

d the jump increment, r0 the residual without the cluster's contact force,
W the patch lengths, p = A g + a the branch.  A combination is consistent when
the return map at g + d gives back its own branches (closed, stick inside the
bound, slip outside it with the same sign).

Why: with non-associated friction (the slip traction depends on p_N, the
tangent is not symmetric) a patch near junctions can have no consistent branch
while its neighbours keep theirs: the tangents of the branches then differ in
the sign of their determinant, the full Newton step from slip forward lands in
slip backward and back, and no line search or load-step cut helps
(docs/performance.md, "Fracture networks", refined meshes).  The cure is
a neighbour changing branch, which this search finds.  Only the branches of
the first solve are taken from it: Newton then goes on under the true law.
"""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np
import scipy.sparse as sp

from xfemslip.conventions import SLIP

# Largest cluster searched: 3**10 = 59049 combinations of 20 x 20 systems
# (~1 s), solved CHUNK at a time: each work array of a chunk (CHUNK x 20 x
# 20 doubles, 2.3 MB) stays below the allocator's mmap threshold
# (memory.MMAP_THRESHOLD), so the chunks reuse the same heap memory instead
# of mapping and faulting in fresh pages (7 MB arrays at 3**7 cost 0.6
# million page faults on a crowded network).
MAX_CLUSTER = 10
CHUNK = 3**6


def neighbours(c_dofs, K_ff, patches) -> np.ndarray:
    """Mask of the patches ``patches`` (mask) and those coupled to them
    through the bulk matrix (a jump dof of one shares a cell with one of the
    other)."""
    m, width = c_dofs.shape
    rows = np.repeat(np.arange(m), width)
    cols = c_dofs.ravel()
    keep = cols >= 0
    P = sp.csr_matrix(
        (np.ones(int(keep.sum())), (rows[keep], cols[keep])),
        shape=(m, K_ff.shape[0]),
    )
    seed = np.asarray(P[np.nonzero(patches)[0]].sum(axis=0)).ravel() > 0
    reach = (abs(K_ff) @ seed.astype(float)) > 0
    return ((P @ reach.astype(float)) > 0) | patches


def jump_rows(c, c_dofs, idx, n_free) -> np.ndarray:
    """(2k, n_free): rows 2a, 2a+1 give g_N, g_T of patch idx[a] from the free
    dofs."""
    G = np.zeros((2 * idx.size, n_free))
    for a, i in enumerate(idx):
        for kk in range(c.coef.shape[1]):
            for d in range(2):
                dof = c_dofs[i, 2 * kk + d]
                if dof >= 0:
                    G[2 * a, dof] += c.coef[i, kk] * c.normal[i, d]
                    G[2 * a + 1, dof] += c.coef[i, kk] * c.tangent[i, d]
    return G


def search(c, c_dofs, K_stick, u_free, res, r, idx):
    """Branches (k,) int: 0 stick, +1 / -1 slip forward / backward of the
    patches idx, consistent with the return map, or None.

    c : the true ContactSet; c_dofs : (m, 2J) free-dof numbers (-1: none);
    K_stick : free-dof tangent with the patches idx in stick and every other
    patch on its branch of ``res``; u_free : current free dofs; res : contact
    result at u (the law Newton evaluates); r : its residual on the free dofs.
    Among several consistent combinations the one with the smallest jump
    increment is returned.
    """
    k = idx.size
    if k == 0 or k > MAX_CLUSTER:
        return None
    # here, not at the top: scipy.sparse.linalg is 90 ms of imports that a
    # run on the PARDISO path without stuck clusters does not need
    import scipy.sparse.linalg as spla

    G = jump_rows(c, c_dofs, idx, u_free.size)
    lu = spla.splu(sp.csc_matrix(K_stick))
    M = G @ lu.solve(G.T.copy())
    g = G @ u_free
    W = np.repeat(c.weight[idx], 2)
    p_now = np.column_stack([res.pn[idx], res.pt[idx]]).ravel()
    q0 = -G @ lu.solve(r - G.T @ (W * p_now))
    law = (c.kn[idx], c.kt[idx], c.friction[idx], c.cohesion[idx])
    law += (c.slip_committed[idx], c.pn0[idx])
    combos = np.array(list(itertools.product((0, 1, -1), repeat=k)), np.int64)
    ok = np.zeros(combos.shape[0], bool)
    size = np.full(combos.shape[0], np.inf)
    for lo in range(0, combos.shape[0], CHUNK):
        part = slice(lo, lo + CHUNK)
        ok[part], size[part] = _check(combos[part], M * W[None, :], g, q0, law)
    if not ok.any():
        return None
    # several consistent sets: the smallest move (on seed 1 of the refined
    # DFN the other two moved the jumps by 1e8 m: near-singular systems of a
    # cluster around a fragment of the body)
    best = np.nonzero(ok)[0][np.argmin(size[ok])]
    return combos[best]


def _check(combos, MW, g, q0, law):
    """(consistent, max |jump increment|) of each branch combination."""
    kn, kt, f, coh, gp, pn0 = law
    n, k = combos.shape
    A = np.zeros((n, 2 * k, 2 * k))
    a = np.zeros((n, 2 * k))
    Sd = np.zeros(2 * k)
    for j in range(k):
        A[:, 2 * j, 2 * j] = kn[j]
        a[:, 2 * j] = pn0[j]
        Sd[2 * j], Sd[2 * j + 1] = kn[j], kt[j]
        stick = combos[:, j] == 0
        A[stick, 2 * j + 1, 2 * j + 1] = kt[j]
        a[stick, 2 * j + 1] = -kt[j] * gp[j]
        s = combos[~stick, j].astype(float)
        A[~stick, 2 * j + 1, 2 * j] = -s * f[j] * kn[j]
        a[~stick, 2 * j + 1] = s * (coh[j] - f[j] * pn0[j])
    lhs = np.eye(2 * k)[None] + MW[None] @ (A - np.diag(Sd)[None])
    rhs = q0[None] - (MW[None] @ ((A @ g) + a)[..., None])[..., 0]
    with np.errstate(all="ignore"):
        try:
            d = np.linalg.solve(lhs, rhs[..., None])[..., 0]
        except np.linalg.LinAlgError:  # a singular combination in the chunk
            d = np.stack([_solve_or_nan(L, b) for L, b in zip(lhs, rhs, strict=True)])
        gn, gt = (g + d)[:, 0::2], (g + d)[:, 1::2]
        pn = kn * gn + pn0
        trial = kt * (gt - gp)
        bound = coh - f * pn
        ok = np.isfinite(d).all(axis=1)[:, None] & (pn <= 0.0)
        ok &= np.where(
            combos == 0,
            np.abs(trial) <= bound,
            (np.abs(trial) > bound) & (np.sign(trial) == combos),
        )
        size = np.abs(d).max(axis=1)
    return ok.all(axis=1), size


def _solve_or_nan(L, b):
    """L^-1 b, or NaN (never consistent) for a singular L."""
    try:
        return np.linalg.solve(L, b)
    except np.linalg.LinAlgError:
        return np.full(b.shape, np.nan)


def current_branches(res, idx) -> np.ndarray:
    """Branches (0 stick or open, +-1 slip) of the patches idx in res."""
    return np.where(res.state[idx] == SLIP, np.sign(res.pt[idx]), 0).astype(np.int64)


def force_branches(c, *, open_at=None, stick_at=None, slip_at=None, sign=None):
    """The contact set ``c`` whose return map lands on a chosen branch at the
    selected patches (boolean masks or index arrays); the others as in ``c``.

    The one way the solver forces a branch (the predictor's first guess, the
    ping-pong and reversal holds, the branches of a local search).  Same
    kernel, same affine expressions; only the parameters that select a
    branch differ:

    - ``open_at``: k_N = 0 and p_N0 > 0, so zero traction and tangent;
    - ``stick_at``: an infinite cohesion, static and dynamic (so it does
      not weaken), so the trial traction is always inside the bound; the
      normal law stays free (a patch may still open);
    - ``slip_at``: a committed plastic slip of -sign * inf (``sign`` +-1 per
      selected patch), so the trial traction is infinite with that sign and
      is returned onto sign * (c - f p_N); the plastic slip g_T - p_T / k_T
      it reports does not depend on it.  On a slip-weakening patch the
      infinite trial passes the whole weakening range and lands on the
      dynamic bound sign * (c_d - f_d p_N): the predictor and the local
      search therefore leave weakening patches to the true law.

    A closed branch whose normal jump is open at the evaluation point stays
    open (the normal test comes first).  Never committed: the true law is
    restored and checked before a step is accepted.
    """
    changes = {}
    if open_at is not None:
        kn, pn0 = c.kn.copy(), c.pn0.copy()
        kn[open_at] = 0.0
        pn0[open_at] = 1.0
        changes |= {"kn": kn, "pn0": pn0}
    if stick_at is not None:
        cohesion = c.cohesion.copy()
        cohesion[stick_at] = math.inf
        dynamic = c.cohesion_dynamic.copy()
        dynamic[stick_at] = math.inf
        changes |= {"cohesion": cohesion, "cohesion_dynamic": dynamic}
    if slip_at is not None:
        committed = c.slip_committed.copy()
        committed[slip_at] = -np.asarray(sign) * math.inf
        changes["slip_committed"] = committed
    return dataclasses.replace(c, **changes)
