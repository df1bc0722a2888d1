"""The multigrid hierarchies of the AMG path (:mod:`linear`): geometric on
the structured grid, smoothed aggregation where the dofs' nodes are not a
rectilinear grid.

Geometric (``geometric``): the standard dofs of a structured Q4 mesh are
the unknowns of plain elasticity on a rectilinear grid (a fracture enriches
other dofs), so the coarse grids are every other grid line (the last one
kept when a direction has an odd number of cells; across the short side
only where the cells are elongated, SEMI_COARSENING), the prolongation is the
bilinear interpolation of each displacement component by the node
coordinates (graded grids too), and the coarse operators are Galerkin
products P^T A P, so several rock units need no extra care.  A coarse dof
on a fixed fine dof (a Dirichlet edge, a pinned node) is left out.
Measured on the standard dofs of the reservoir case at 400 x 400 cells
(321k dofs, CG to 1e-10, one V-cycle with symmetric Gauss-Seidel per step):
set-up 0.22 s and 11 iterations in 1.32 s, against smoothed aggregation's
1.44 s and 15 iterations in 2.25 s (docs/solvers.md).

Smoothed aggregation (``smoothed_aggregation``) is the hierarchy
``pyamg.smoothed_aggregation_solver`` builds with the options the AMG path
uses (symmetric strength of connection with theta 0, standard aggregation,
the tentative prolongator fitted to the near-nullspace B, one Jacobi step
with omega = 4/3 smoothing it, P^T as restriction, symmetric block
Gauss-Seidel relaxation, a sparse LU on the coarsest level), made of
pyamg's own pieces with one difference: the spectral radius rho of D^-1 A
that scales the Jacobi step.

pyamg estimates it by a restarted Arnoldi iteration (up to 6 restarts of 15
steps, every step orthogonalised against all earlier ones, from a random
vector), which took 6.7 s of an 8.0 s set-up at 321k dofs (the reservoir
case at 400 x 400).  K is symmetric positive definite, so rho(D^-1 A) is the
largest eigenvalue of the symmetric D^-1/2 A D^-1/2, which LANCZOS_STEPS
steps of the Lanczos three-term recurrence estimate (the largest Ritz value,
from below like Arnoldi's) at the cost of as many products: 0.4 s there,
2.560 against Arnoldi's 2.596, which leaves the hierarchy's size and the
CG iterations as they were (19 to 1e-10 on that matrix).  The start vector
is drawn from a fixed seed, so a run's hierarchy, its Krylov iterations and
its answer no longer depend on numpy's global random state.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

# Lanczos steps of the spectral radius estimate (largest Ritz value of
# D^-1/2 A D^-1/2); on the 321k-dof reservoir matrix 10 / 20 / 30 steps are
# 2.5 / 1.4 / 0.9 % below the converged 2.597: omega / rho changes by as much
OMEGA = 4.0 / 3.0
LANCZOS_STEPS = 20
SEED = 0


def jacobi_spectral_radius(A, steps: int = LANCZOS_STEPS) -> float:
    """The largest eigenvalue of D^-1 A (A symmetric positive definite, D
    its diagonal) from ``steps`` Lanczos steps on D^-1/2 A D^-1/2: the
    largest eigenvalue of the tridiagonal matrix of the recurrence."""
    d = np.asarray(A.diagonal(), dtype=float)
    # a row without a positive diagonal is left out, as pyamg's D^-1 does
    s = np.zeros_like(d)
    np.divide(1.0, np.sqrt(d, where=d > 0, out=np.zeros_like(d)), out=s, where=d > 0)
    n = A.shape[0]
    v = np.random.default_rng(SEED).random(n)
    v /= np.linalg.norm(v)
    v_old = np.zeros(n)
    alpha, beta = [], [0.0]
    for _ in range(min(steps, n)):
        w = s * (A @ (s * v)) - beta[-1] * v_old
        a = float(v @ w)
        w -= a * v
        b = float(np.linalg.norm(w))
        alpha.append(a)
        if b <= 1e-12 * abs(a):  # an invariant subspace: the Ritz values are exact
            break
        beta.append(b)
        v_old, v = v, w / b
    k = len(alpha)
    off = np.asarray(beta[1:k])
    T = np.diag(alpha) + np.diag(off, 1) + np.diag(off, -1)
    return float(np.linalg.eigvalsh(T)[-1])


# A direction is coarsened while its (median) cell size is at most this
# times the other's: on elongated cells the point smoother only smooths
# along the short side, so only that side is coarsened there.
SEMI_COARSENING = 2.0


def grid_interpolation(x: np.ndarray) -> tuple[np.ndarray, sp.csr_matrix]:
    """The coarse grid of the 1-D grid x (m + 1 increasing coordinates):
    the indices of its nodes in x (every other one, and the last), and the
    (m + 1, m_c + 1) linear interpolation from it to x."""
    m = x.size - 1
    keep = np.arange(0, m + 1, 2)
    if keep[-1] != m:
        keep = np.append(keep, m)
    i = np.arange(m + 1)
    b = np.searchsorted(keep, i)  # the first coarse node at or right of i
    at = keep[b] == i
    a = np.where(at, b, b - 1)
    t = np.ones(m + 1)
    inside = ~at
    xa, xb = x[keep[a[inside]]], x[keep[b[inside]]]
    t[inside] = (x[inside] - xa) / (xb - xa)
    rows = np.concatenate([i, i[inside]])
    cols = np.concatenate([b, a[inside]])
    vals = np.concatenate([t, 1.0 - t[inside]])
    return keep, sp.csr_matrix((vals, (rows, cols)), shape=(m + 1, keep.size))


def geometric(A, node_xy: np.ndarray, dof: np.ndarray, max_coarse: int):
    """The pyamg MultilevelSolver of A (SPD, the standard dofs ``dof``: node
    dof // 2, component dof % 2) on the rectilinear grid of ``node_xy``
    (module doc), down to at most ``max_coarse`` nodes on the coarsest
    level; None when the nodes are not every node of one rectilinear grid."""
    from pyamg.multilevel import MultilevelSolver
    from pyamg.relaxation.smoothing import change_smoothers

    from xfemslip.solve.ordering import node_grid

    x, y, col, row = node_grid(node_xy)
    if x.size * y.size != col.size or np.unique(row * x.size + col).size != col.size:
        return None
    dof = np.asarray(dof, dtype=np.int64)
    # each row's dof on the full grid of this level: 2 (j nx + i) + component
    key = 2 * (row[dof // 2] * x.size + col[dof // 2]) + dof % 2
    A = sp.csr_matrix(A, dtype=float)
    levels = [MultilevelSolver.Level()]
    levels[-1].A = A
    while len(levels) < 20 and x.size * y.size > max_coarse:
        hx, hy = (
            float(np.median(np.diff(v))) if v.size > 1 else np.inf for v in (x, y)
        )
        (kx, Px), (ky, Py) = (
            grid_interpolation(v)
            if v.size > 2 and h <= SEMI_COARSENING * h_other
            else (np.arange(v.size), sp.identity(v.size, format="csr"))
            for v, h, h_other in ((x, hx, hy), (y, hy, hx))
        )
        if kx.size == x.size and ky.size == y.size:
            break
        P = sp.kron(sp.kron(Py, Px), sp.identity(2), format="csr")
        # the coarse dofs whose fine dof is one of this level's
        fine = 2 * (ky[:, None] * x.size + kx[None, :]).ravel()
        fine = np.stack([fine, fine + 1], axis=1).ravel()
        present = np.zeros(2 * x.size * y.size, dtype=bool)
        present[key] = True
        kept = np.nonzero(present[fine])[0]
        P = P[key][:, kept].tocsr()
        level = levels[-1]
        level.P, level.R = P, P.T.tocsr()
        coarse = MultilevelSolver.Level()
        coarse.A = (level.R @ level.A @ P).tocsr()
        levels.append(coarse)
        key, x, y = kept, x[kx], y[ky]
    ml = MultilevelSolver(levels, coarse_solver="splu")
    sweep = ("gauss_seidel", {"sweep": "symmetric"})
    change_smoothers(ml, sweep, sweep)
    return ml


def smoothed_aggregation(A: sp.csr_matrix, B: np.ndarray, max_coarse: int):
    """The pyamg MultilevelSolver of A (SPD) with near-nullspace B (module
    doc), down to at most ``max_coarse`` unknowns (nodes: blocks of the
    coarse levels' BSR matrices) on the coarsest level."""
    from pyamg.aggregation import fit_candidates, standard_aggregation
    from pyamg.multilevel import MultilevelSolver
    from pyamg.relaxation.smoothing import change_smoothers
    from pyamg.strength import symmetric_strength_of_connection
    from pyamg.util.utils import get_diagonal, scale_rows

    A = sp.csr_matrix(A, dtype=float)
    A.symmetry = "hermitian"
    levels = [MultilevelSolver.Level()]
    levels[-1].A, levels[-1].B = A, np.asarray(B, dtype=float)

    def nodes(M) -> int:
        return M.shape[0] // (M.blocksize[0] if M.format == "bsr" else 1)

    while len(levels) < 10 and nodes(levels[-1].A) > max_coarse:
        level = levels[-1]
        A, B = level.A, level.B
        C = symmetric_strength_of_connection(A, theta=0.0)
        aggregates, _ = standard_aggregation(C)
        T, B = fit_candidates(aggregates, B)
        # pyamg's jacobi_prolongation_smoother, rho estimated as above
        D_inv_A = scale_rows(A, get_diagonal(A, inv=True), copy=True)
        D_inv_A = (OMEGA / jacobi_spectral_radius(A)) * D_inv_A
        P = T - (D_inv_A @ T)
        level.P, level.R = P, P.T.conjugate()
        coarse = MultilevelSolver.Level()
        coarse.A = level.R @ A @ P
        coarse.A.symmetry = "hermitian"
        coarse.B = B
        levels.append(coarse)
    ml = MultilevelSolver(levels, coarse_solver="splu")
    sweep = ("block_gauss_seidel", {"sweep": "symmetric"})
    change_smoothers(ml, sweep, sweep)
    return ml


def v_cycle(ml):
    """b -> one V-cycle of the hierarchy ``ml`` from zero.

    pyamg's own preconditioner (MultilevelSolver.aspreconditioner) runs
    ``solve`` with one cycle, which forms the residual norm before and
    after it: two products with the finest matrix per application.  Without
    them (and with the band's residual from the band's rows, linear.py) a
    run of the reservoir case at 400 x 400 cells took 3.5-3.9 s instead of
    5.0-5.9 s, the same 23 GMRES iterations."""
    levels = ml.levels
    last = len(levels) - 1

    def cycle(b):
        x = np.zeros_like(b)
        level = 0
        rhs = [b]
        xs = [x]
        # down: smooth, restrict the residual
        while level < last:
            L = levels[level]
            L.presmoother(L.A, xs[level], rhs[level])
            rhs.append(L.R @ (rhs[level] - L.A @ xs[level]))
            xs.append(np.zeros_like(rhs[-1]))
            level += 1
        xs[last][:] = ml.coarse_solver(levels[last].A, rhs[last])
        # up: correct, smooth
        for level in range(last - 1, -1, -1):
            L = levels[level]
            xs[level] += L.P @ xs[level + 1]
            L.postsmoother(L.A, xs[level], rhs[level])
        return xs[0]

    return cycle
