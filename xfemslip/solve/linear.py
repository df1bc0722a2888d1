"""Linear solves of the Newton systems (K_ff + K_c) du = r.

K_ff, the bulk stiffness on the free dofs, is the same for the whole run; only
K_c, the contact tangent on the enriched dofs along the fractures, changes
between Newton iterations and load steps.  The strategies (``[solver]
linear_solver``) each keep what does not change.  They stay in one module
(about 750 lines) because LinearSolver switches between them within a run
(a failed AMG or PARDISO solve falls back to the kept SuperLU path, checked
by the same backward error) and shares its statistics and band masks among
them; PARDISO's own machinery is in pardiso.py.

- ``"superlu"``: sparse LU (scipy SuperLU in symmetric mode, the grid's
  nested dissection (ordering.py) or minimum degree on A^T + A by the share
  of enriched dofs, GRID_ORDER_MAX_ENRICHED; a residual-checked fallback to
  COLAMD with partial pivoting).
  The first Newton matrix of the run is factored and the factorization kept.
  A system whose contact tangent equals the factored one (no fracture, a
  fracture that stays stuck, a settled set under the secant tangent) costs one
  back-solve.  Otherwise the change (on the enriched dofs only) is handled by
  GMRES preconditioned with one multiplicative Schwarz sweep: back-solve with
  the kept factorization, then an exact LU solve of the current matrix on a
  band of LU_BAND_LAYERS matrix neighbours around the enriched dofs (small:
  the dofs along the fractures).  Measured on the reservoir case at 400 x 400:
  11 GMRES iterations, about 0.3 of a refactorization (GMRES with the kept
  factorization alone needs 121 at 200 x 200; a second back-solve after the
  band solve saves at most one iteration and cost 11.0 against 8.9 s).  If
  GMRES has not converged in REUSE_MAX_ITERATIONS iterations the matrix is
  refactored and kept.  A crowded network (the contact blocks of PARDISO's
  low-rank path, up to lowrank.AUGMENTED_MAX_ROWS patch jumps) is solved on
  ONE factorization for the run: the stuck matrix bordered by the patch
  jumps, factored with the jumps last (lowrank.AugmentedLU), every Newton
  system two back-solves and a dense LU of its change.  Otherwise, where
  the band would hold more than LU_BAND_MAX_FRACTION of the dofs (a
  network reaching most of the mesh), a system whose tangent changed in
  few contact patches (a change of rank at most 2 per patch) is solved by
  GMRES preconditioned with the kept factorization alone, within that rank
  bound (KEPT_GMRES_MAX); a larger change is refactored.
- ``"amg"``: GMRES preconditioned with the same Schwarz sweep: one
  multigrid V-cycle on the standard dofs in place of the back-solve (the
  grid's own coarse grids, xfemslip.solve.amg; smoothed aggregation with
  the rigid-body modes where the nodes are not a whole rectilinear grid),
  then the exact band solve, which carries the enrichment and the stiff,
  non-symmetric contact coupling (a second V-cycle after it saves
  iterations but not time: 28 against 42 iterations, 2.0 against 1.5 s
  CPU at 200 x 200 with smoothed aggregation; 21 against 23 iterations,
  5.6 against 3.6 s at 400 x 400 with the grid's).  The multigrid
  hierarchy is built once per run (the standard block is part of K_ff);
  only the small band is refactored per Newton system.  A system without
  enriched dofs is solved by AMG-preconditioned CG.
  If the Krylov solve does not converge, that system and the rest of the run
  go to SuperLU.  The time lost on the AMG attempt is bounded: GMRES stops
  as soon as its residual, extrapolated at its mean rate, would not reach
  KRYLOV_RTOL within AMG_MAX_ITERATIONS (checked every STALL_CHECK
  iterations of the first scipy call, and after each call), and the
  attempt is logged (warning: iterations, seconds lost) and counted in
  stats["amg_fallbacks"], stats["amg_fallback_time"].
- ``"pardiso"``: MKL PARDISO (the mkl extra), xfemslip.solve.pardiso: one SPD
  factorization of K_ff for the run with the contact dofs eliminated last,
  and a dense LU of their Schur complement per contact tangent; with more
  contact dofs than that allows (networks), xfemslip.solve.lowrank: one SPD
  factorization of the stuck matrix with the Schur complement on the patch
  jumps, and per contact tangent a dense LU of its low-rank change.  A PARDISO
  failure sends the run to SuperLU (warning, stats["pardiso_fallbacks"]).
- ``"auto"`` (default): ``"pardiso"`` from AUTO_PARDISO_MIN_DOFS free dofs
  when the mkl extra is installed; otherwise ``"amg"`` from AUTO_AMG_MIN_DOFS
  free dofs up on meshes with cell aspect ratios up to AUTO_AMG_MAX_ASPECT
  whose AMG band (the enriched dofs and AMG_BAND_LAYERS matrix neighbours:
  what the band LU of every Newton system factors) holds at most
  AUTO_AMG_MAX_BAND of the free dofs (pyamg installed, node coordinates
  known), ``"superlu"`` otherwise.  All three inputs are known before the
  first solve (system_facts); the choice is logged at debug level.

Why SuperLU refactors a single fracture's matrix instead of a low-rank
(Woodbury) update or a Schur complement on the contact dofs: through
SuperLU's solves both cost one back-solve per contact dof, and on the
reservoir case at 200 x 200 (82k dofs, 518 contact dofs) one back-solve is
1/40 of a factorization, so the update would cost about 13
factorizations.  PARDISO forms the Schur complement inside its one
factorization (pardiso.py); for networks, AugmentedLU makes SuperLU do the
same by ordering the patch jumps last and reading the trailing block of
its factors.

The friction tangent is not symmetric while slipping, hence GMRES (not CG)
whenever a contact tangent is present.  Iterative solves stop at a relative
residual KRYLOV_RTOL, far below the Newton tolerance, so Newton converges as
with the direct solve.
"""

from __future__ import annotations

import contextlib
import importlib.util
import logging
import math
import time
from collections.abc import Callable

import numpy as np
import scipy.sparse as sp

from xfemslip.fem.assembly import coo_block
from xfemslip.solve import lowrank, ordering, pardiso, shared
from xfemslip.solve.backward import backward_error
from xfemslip.solve.guess import KEEP, PreviousSolutions

logger = logging.getLogger(__name__)

LINEAR_SOLVERS = ("auto", "superlu", "amg", "pardiso")

# "auto" switches from SuperLU to AMG at this many free dofs (measured on the
# reservoir case, docs/performance.md "Scaling"), on meshes whose
# cells are no more elongated than AUTO_AMG_MAX_ASPECT: on a graded mesh with
# cells up to 146:1 the AMG-preconditioned GMRES did not converge in 300
# iterations (58k dofs).
AUTO_AMG_MIN_DOFS = 50_000
# "auto" takes PARDISO (the mkl extra) from this many free dofs: below it,
# loading MKL (0.3-0.5 s) costs more than SuperLU's whole solve.  Whole
# `xfemslip run` of the reservoir case (benchmarks/scaling.py, docs/
# performance.md "Scaling"): 2.03 s with PARDISO against 1.45 s by default
# (SuperLU) at 22k dofs, 2.82 against 3.28 s (AMG) at 83k.
AUTO_PARDISO_MIN_DOFS = 50_000
# Without the mkl extra, a run from this many free dofs says in one line what
# PARDISO would gain: the measured range of the ratio of the AMG path's
# linear-solve time to PARDISO's, whole runs at 323k-519k free dofs
# (docs/performance.md, "Load steps after the first"): 1.7 on the reservoir
# case's single step, 4.3 on the plate's 5 steps, 5.2 on the depleting
# reservoir's 10.
PARDISO_HINT_MIN_DOFS = 200_000
PARDISO_GAIN = (1.7, 5.2)
# ... and a crowded network taking the augmented SuperLU path
# (lowrank.AugmentedLU), below that size, what the whole run gained with it:
# 100 branch-tipped fractures on 200 x 200 cells (147k dofs), whole
# processes without thread variables (benchmarks/network_floor.py, docs/
# performance/network_floor.md, medians of 5): 12.9 s by default against
# 6.5 s with PARDISO on a quiet machine, 21.6 against 9.4 s on a loaded one
# before the default path's one-pass solves.
PARDISO_NETWORK_GAIN = 2.0
AUTO_AMG_MAX_ASPECT = 4.0
# ... and whose AMG band (enriched dofs and AMG_BAND_LAYERS neighbours) holds
# at most this share of the free dofs.  Measured on generated networks of
# 1-100 fractures, 80k-375k dofs (benchmarks/auto_choice.py, docs/
# performance.md "Automatic linear solver choice"): the band LU of every Newton system
# grows with the band, and AMG's CPU time on the same Newton systems from
# 80k dofs up was 0.58-1.0 of SuperLU's with bands of 12-64 % (two
# exceptions: 1.15 at 51 %, 1.61 at 6.5 % where SuperLU kept one
# factorization), and 1.01-1.53 with bands of 67-86 % (two of them fell back
# to SuperLU).  Above 0.65 AMG no longer gains.
AUTO_AMG_MAX_BAND = 0.65
# SuperLU factors the whole matrix in the grid's nested-dissection order
# (ordering.py) when the enriched dofs are at most this share of the free
# dofs, in its minimum-degree order otherwise.  Enriched dofs crowd the
# grid's separator lines and their contact blocks couple nodes across them.
# Whole runs with SuperLU, the linear solves of the run in either order
# (one process each): the reservoir case at 200 x 200 cells (83k dofs, 2.8 %
# enriched) 0.86-0.90 against 1.07-1.24 s; generated networks on 200 x 200
# cells of 10 fractures (88k dofs, 8.4 % enriched) 3.3 against 4.3 s, of
# 20 (97k, 16.5 %) 26.5 against 15.4 s and of 30 (104k, 22 %) 14.3
# against 9.6 s; the shipped network (18k dofs, 25 %) 3.4 against 1.9 s;
# the shipped cases of 6k-29k dofs with 2-11 % enriched within 0.03-0.9 s
# either way.
GRID_ORDER_MAX_ENRICHED = 0.10
# Relative residual ||A x - b|| / ||b|| at which the Krylov solves stop.
KRYLOV_RTOL = 1.0e-10
# GMRES iterations with a kept factorization tried before refactoring, and
# the layers of the band solved exactly with the current matrix.
REUSE_MAX_ITERATIONS = 20
LU_BAND_LAYERS = 12
# A band holding more than this fraction of the dofs costs about as much as a
# refactorization: GMRES with the kept factorization alone instead (below).
LU_BAND_MAX_FRACTION = 0.25
# Without a band (a network whose fractures reach most of the mesh), a changed
# contact tangent is a change of rank at most 2 per changed contact patch, so
# GMRES preconditioned by the kept factorization converges in at most that
# rank + 1 iterations in exact arithmetic; KEPT_GMRES_EXTRA more are allowed
# for round-off.  It is tried when that bound is at most KEPT_GMRES_MAX
# iterations, and the matrix refactored (and kept) otherwise or when GMRES has
# not converged there (it can stall: the factors are an unpivoted LU's).  A
# fixed bound, not a measured cost, so that a rerun takes the same path: on
# 100 branch-tipped fractures on 200 x 200 cells (147k dofs) a factorization
# costs about 35 back-solves, so 17 iterations are about half of one; most
# Newton iterations there change 0-8 patches (benchmarks/network_floor.py).
KEPT_GMRES_MAX = 17
KEPT_GMRES_EXTRA = 4
# GMRES restart length and total iteration cap of the AMG path.
AMG_RESTART = 60
AMG_MAX_ITERATIONS = 150
# Largest AMG coarse level (solved by LU). Measured on the reservoir case's
# first Newton system (GMRES iterations to 1e-10 with pyamg's default of 10
# unknowns -> with 1000): 32 -> 26 at 324k dofs, 41 -> 34 at 986k, the set-up
# no slower (the levels below a thousand unknowns only cost V-cycle work).
AMG_MAX_COARSE = 1000
# Layers of matrix neighbours around the enriched dofs in the exact band solve.
AMG_BAND_LAYERS = 3
# Stop the AMG path's GMRES after a restart cycle whose residual, extrapolated
# at its mean rate, would not reach KRYLOV_RTOL within AMG_MAX_ITERATIONS
# (docs/performance.md, "Automatic linear solver choice").
AMG_STALL_STOP = True
# ... checked every STALL_CHECK iterations within the first restart cycle.
STALL_CHECK = 20

# SuperLU settings for K + K_contact, whose sparsity pattern is symmetric even
# when the slip tangent's values are not: minimum degree on A^T + A in symmetric
# mode, diagonal pivots only (measured: 2x faster than the default COLAMD
# at 82k dofs, 0.19 vs 0.31 s at 21k).  Pivot threshold 0: the diagonal pivot
# is always taken, so the fill is that of the symmetric ordering; with a
# threshold of 0.1 the row exchanges for the non-symmetric friction
# coupling raised the fill of the 100 x 100 reservoir matrix from 3.6M to 6.2M
# entries and the factorization from 0.15 to 0.37 s (relative residual
# 2e-11 either way).  A solve whose residual is poor is redone with COLAMD and
# full partial pivoting (LU_SAFE).  No relaxed supernodes (relax 1, SuperLU's
# default groups up to 20 columns at the leaves of the elimination tree): the
# same fill, and the factorization of the stuck matrix of 100 branch-tipped
# fractures on 200 x 200 cells (147k dofs, 42M entries in L + U) in 2.8-3.1 s
# against 6.7-8.4 s; 1.22-1.30 against 1.55-1.74 s on the shipped network at
# 200 x 200, and the same (1.3 s, 7.8-9.0 s) on the reservoir case at 200 x 200
# and 400 x 400 (one BLAS thread, measured in one process each).
LU_FAST = {
    "permc_spec": "MMD_AT_PLUS_A",
    "diag_pivot_thresh": 0.0,
    "relax": 1,
    "options": {"SymmetricMode": True},
}
LU_SAFE = {"permc_spec": "COLAMD", "diag_pivot_thresh": 1.0}
# A direct solve is accepted when its normwise backward error (Rigal & Gaches
# 1967; Higham 2002, Accuracy and Stability of Numerical Algorithms, ch. 7; in the
# infinity norm)  ||A x - b|| / (||A|| ||x|| + ||b||)  is at most
# LU_BACKWARD_ERROR, after one step of iterative refinement with the kept
# factors if needed; otherwise it is redone with LU_SAFE.  Not the relative
# residual ||A x - b|| / ||b|| (e.g. <= 1e-8), which an exact-to-round-off
# solve of an ill-conditioned system can fail: with branch
# tips on a 30-fracture network the fast LU's relative residual on the bulk
# matrix (b = 1) is already 3.5e-10 at 50 x 50 cells (16k dofs) and 6.6e-10
# at 100 x 100 (45k), 1/15 of that threshold, while the backward error is
# 8e-19; the COLAMD fallback a failed test triggers solves no better
# (residual 1.4e-9) and costs 1.4 s at 16k dofs (17M fill entries) and over
# 90 s at 45k, where the fast factorization takes 0.22 and 0.57 s
# (docs/performance.md, "Fracture networks").
LU_BACKWARD_ERROR = 1.0e-10

# Memory of the solvers' structures (solver_bytes), measured against the
# peak resident memory of whole runs (xfemslip.memory, docs/robustness.md):
# per stiffness non-zero, K, K_ff, K_ff + K_contact and its CSC copy, 12 B
# each (8 B value, 4 B index) [B]
MATRIX_BYTES = 48.0
LU_BYTES = 5.0  # per stiffness non-zero and per log2(n_dofs), one factor [B]
LU_FACTORS = 2  # factorizations held at once
# lowrank.AugmentedLU holds one factorization of the stuck matrix bordered
# by the patch jumps: 56.0M entries in L + U against 42.5M for the stuck
# matrix alone on 100 branch-tipped fractures at 200 x 200 cells
AUGMENTED_FILL = 1.35
# MKL PARDISO's factorization, per stiffness non-zero and per log2(n_dofs):
# whole runs of the reservoir case peaked at 1043 / 2987 / 5892 MB at 324k /
# 986k / 2.0M dofs (benchmarks/scaling.py), 5.2-5.6 B after the other terms [B]
PARDISO_BYTES = 6.0
AMG_BYTES = 40.0  # per stiffness non-zero: hierarchy and its set-up [B]


def pyamg_available() -> bool:
    return importlib.util.find_spec("pyamg") is not None


def enriched_mask(free, node_xy) -> np.ndarray:
    """Which free dofs are enriched (global dof from 2 * n_nodes on)."""
    return np.asarray(free) >= 2 * node_xy.shape[0]


def band_mask(K, seed, layers) -> np.ndarray:
    """The dofs `seed` (bool) and their matrix neighbours up to `layers` deep."""
    band = np.array(seed, dtype=bool)
    if band.any() and layers > 0:
        pattern = sp.csr_matrix(K, copy=True)
        pattern.data = np.ones_like(pattern.data)
        for _ in range(layers):
            band |= (pattern @ band.astype(float)) > 0
    return band


def system_facts(K, free, node_xy) -> dict:
    """What "auto" can know before the first solve: the free dofs, the share
    of them that is enriched, and the share in the AMG band (enriched dofs and
    AMG_BAND_LAYERS matrix neighbours), with the band itself ("band", free-dof
    indices) for the AMG path to keep."""
    n = K.shape[0]
    enr = enriched_mask(free, node_xy)
    band = band_mask(K, enr, AMG_BAND_LAYERS)
    return {
        "n_free": n,
        "enriched_share": float(enr.sum()) / max(n, 1),
        "band_share": float(band.sum()) / max(n, 1),
        "band": np.nonzero(band)[0],
    }


def grid_order_applies(enriched_share: float | None) -> bool:
    """Whether SuperLU factors the whole matrix in the grid's nested-
    dissection order (GRID_ORDER_MAX_ENRICHED; None: not known, no)."""
    return enriched_share is not None and enriched_share <= GRID_ORDER_MAX_ENRICHED


def auto_choice(
    n_free: int,
    aspect: Callable[[], float] | None,
    band_share: Callable[[], float],
) -> str:
    """The strategy "auto" stands for: "pardiso" from AUTO_PARDISO_MIN_DOFS
    free dofs when the mkl extra is installed; else "amg" from
    AUTO_AMG_MIN_DOFS free dofs on meshes with cells up to
    AUTO_AMG_MAX_ASPECT : 1 whose AMG band (the enriched dofs and
    AMG_BAND_LAYERS matrix neighbours, system_facts) holds at most
    AUTO_AMG_MAX_BAND of the free dofs; "superlu" otherwise.

    aspect() gives the mesh's largest cell aspect ratio (None: the mesh is
    not known, no AMG), band_share() the share of the free dofs in the AMG
    band; each is called only when it decides (the band costs a sparse
    product per layer)."""
    if n_free >= AUTO_PARDISO_MIN_DOFS and pardiso.available():
        return "pardiso"
    if (
        n_free >= AUTO_AMG_MIN_DOFS
        and aspect is not None
        and aspect() <= AUTO_AMG_MAX_ASPECT
        and pyamg_available()
        and band_share() <= AUTO_AMG_MAX_BAND
    ):
        return "amg"
    return "superlu"


def choose(
    method: str,
    n_free: int,
    node_xy: np.ndarray | None = None,
    band_share: float | Callable[[], float] = 0.0,
) -> str:
    """The strategy of ``linear_solver = method`` for n_free free dofs on the
    mesh with nodes node_xy: method itself, or what "auto" stands for
    (auto_choice).  band_share: a number, or a function called only when it
    decides."""
    if method != "auto":
        return method
    share = band_share if callable(band_share) else _constant(band_share)
    if node_xy is None:
        return auto_choice(n_free, None, share)
    nodes = node_xy
    return auto_choice(n_free, lambda: cell_aspect_ratio(nodes), share)


def planned_solver(
    method: str,
    n_free: int,
    x: np.ndarray,
    y: np.ndarray,
    band_share: Callable[[], float] | None = None,
) -> str:
    """The strategy a run will take (choose) on the rectilinear mesh with
    grid lines x, y and about n_free free dofs, known before the mesh or the
    stiffness is built (the memory estimate asks this).  band_share() as in
    auto_choice; None: not known yet, taken as 0."""
    if method != "auto":
        return method
    share = _constant(0.0) if band_share is None else band_share
    return auto_choice(n_free, lambda: grid_aspect_ratio(x, y), share)


def _constant(value: float) -> Callable[[], float]:
    return lambda: value


def cell_aspect_ratio(node_xy: np.ndarray) -> float:
    """Largest cell aspect ratio of a structured rectilinear mesh, from its
    nodes (grid_aspect_ratio of their distinct x and y)."""
    x, y, _, _ = ordering.node_grid(node_xy)
    return grid_aspect_ratio(x, y)


def grid_aspect_ratio(x: np.ndarray, y: np.ndarray) -> float:
    """Largest cell aspect ratio of the rectilinear mesh with increasing grid
    lines x, y: max(max hx / min hy, max hy / min hx)."""
    hx = np.diff(x)
    hy = np.diff(y)
    if hx.size == 0 or hy.size == 0:
        return 1.0
    return float(max(hx.max() / hy.min(), hy.max() / hx.min()))


def grid_band_share(
    shape: tuple[int, int], enriched_nodes: np.ndarray, n_dofs: int
) -> float:
    """The share of n_dofs in the AMG band (system_facts) estimated before
    the stiffness exists, on a structured grid of shape (nx, ny) cells: the
    enriched dofs (two per entry of enriched_nodes, one entry per enrichment
    function of a node) and the standard ones of the nodes within
    AMG_BAND_LAYERS node rings of an enriched node (an enriched dof couples
    to the nodes of its support, each layer adds a ring)."""
    nx, ny = shape
    grid = np.zeros((ny + 1, nx + 1), bool)
    grid.flat[np.unique(enriched_nodes)] = True
    for _ in range(AMG_BAND_LAYERS):
        ring = grid.copy()
        ring[1:] |= grid[:-1]
        ring[:-1] |= grid[1:]
        ring[:, 1:] |= ring[:, :-1].copy()
        ring[:, :-1] |= ring[:, 1:].copy()
        grid = ring
    return (2.0 * grid.sum() + 2.0 * enriched_nodes.size) / max(n_dofs, 1)


def solver_bytes(
    method: str, nnz: float, n_dofs: int, contact_dofs: float, patches: float = 0.0
) -> float:
    """The memory the linear solver of a run holds at once [B], for a
    stiffness with nnz non-zeros on n_dofs dofs, contact_dofs of them in the
    contact blocks; method a strategy ("superlu", "amg" or "pardiso", as
    choose resolves it).

    The stiffness, its free-dof part, the Newton matrix and its CSC copy
    (MATRIX_BYTES per non-zero) and: with "superlu", LU_FACTORS sparse LU
    factorizations (the kept one while the next is built), whose fill grows
    like nnz log2(n_dofs) with a fill-reducing ordering (LU_BYTES per
    non-zero and per log2); with "pardiso", one factorization (PARDISO_BYTES
    per non-zero and per log2) and the dense Schur complement of the contact
    dofs with its LU (16 B per entry, up to pardiso.SCHUR_MAX_DOFS of them)
    or, with more contact dofs, that of the patches' jumps and its inverse
    part (lowrank.LowRankSystems: 2 rows per patch, 16 B per entry, up to
    lowrank.MAX_ROWS rows) -- with "superlu" on such networks, the one
    augmented factorization of lowrank.AugmentedLU (AUGMENTED_FILL times a
    factorization), whose jump clique, S and G take 28 B per entry; with
    "amg", its hierarchy and set-up (AMG_BYTES
    per non-zero), the GMRES basis (AMG_RESTART + 1 vectors) and the kept
    solutions that start each solve (guess.KEEP vectors).  A run whose AMG
    solve fails over to SuperLU may need more."""
    if method == "amg":
        out = nnz * (MATRIX_BYTES + AMG_BYTES)
        out += (AMG_RESTART + 1 + KEEP) * 8.0 * n_dofs
    elif method == "pardiso":
        log_n = math.log2(max(n_dofs, 2))
        out = nnz * (MATRIX_BYTES + PARDISO_BYTES * log_n)
        if contact_dofs <= pardiso.SCHUR_MAX_DOFS:
            out += 16.0 * contact_dofs**2
        elif 2.0 * patches <= lowrank.MAX_ROWS:
            out += 16.0 * (2.0 * patches) ** 2
    else:
        log_n = math.log2(max(n_dofs, 2))
        factors = float(LU_FACTORS)
        augmented = (
            contact_dofs > pardiso.SCHUR_MAX_DOFS
            and 0.0 < 2.0 * patches <= lowrank.AUGMENTED_MAX_ROWS
        )
        if augmented:  # lowrank.AugmentedLU: one factorization, more fill
            factors = AUGMENTED_FILL
        out = nnz * (MATRIX_BYTES + factors * LU_BYTES * log_n)
        if augmented:  # the jump clique (12 B per entry), S and G (16 B)
            out += 28.0 * (2.0 * patches) ** 2
    return out


def _splu(A, settings):
    from scipy.sparse.linalg import splu

    return splu(A, **settings)


class OrderedLU:
    """SuperLU's factors of A[order][:, order] taken in that order
    (ordering.py), solving A x = b."""

    def __init__(self, A, order, settings):
        self.order = np.asarray(order, dtype=np.int64)
        self.lu = _splu(
            ordering.permuted(A, self.order), dict(settings, permc_spec="NATURAL")
        )

    def solve(self, b):
        x = np.empty(np.shape(b))
        x[self.order] = self.lu.solve(np.asarray(b, dtype=float)[self.order])
        return x


def lu_factor(A, stats=None, order=None):
    """SuperLU factorization with the fast settings, and a solve function that
    refines once and then falls back to COLAMD with partial pivoting when the
    backward error stays above LU_BACKWARD_ERROR.

    stats : optional dict; "refinements", "fallbacks" and "fallback_time"
    [s] are added to it.  order : the elimination order of the dofs
    (LinearSolver.elimination_order), or None: SuperLU's minimum degree."""
    A = sp.csc_matrix(A)
    lu = _splu(A, LU_FAST) if order is None else OrderedLU(A, order, LU_FAST)
    norm_A = float(abs(A).sum(axis=1).max()) if A.nnz else 0.0
    stats = {} if stats is None else stats

    def solve(b):
        x = lu.solve(b)
        err = backward_error(A, x, b, norm_A)
        if err <= LU_BACKWARD_ERROR:
            return x
        if np.isfinite(err):  # one step of iterative refinement: a back-solve
            stats["refinements"] = stats.get("refinements", 0) + 1
            x = x + lu.solve(b - A @ x)
            err = backward_error(A, x, b, norm_A)
            if err <= LU_BACKWARD_ERROR:
                return x
        logger.debug("linear solve: backward error %.1e, refactoring with COLAMD", err)
        t = time.perf_counter()
        x = _splu(A, LU_SAFE).solve(b)
        stats["fallbacks"] = stats.get("fallbacks", 0) + 1
        stats["fallback_time"] = (
            stats.get("fallback_time", 0.0) + time.perf_counter() - t
        )
        return x

    return lu, solve


class _Stalled(Exception):
    pass


def _projected(iterations, reduction):
    """Iterations to reduce a residual by KRYLOV_RTOL at the mean rate per
    iteration of `reduction` in `iterations` (inf if it did not fall)."""
    if not reduction < 1.0:
        return np.inf
    return iterations * np.log(KRYLOV_RTOL) / np.log(max(reduction, 1e-300))


def _gmres(A, b, M, restart, maxiter, give_up=False, x0=None):
    """GMRES from `x0` (default zero) until ||A x - b|| <= KRYLOV_RTOL ||b|| (the true
    residual: scipy's test is on the preconditioned one), at most `maxiter`
    iterations: one scipy call runs as many whole restart cycles as the cap
    leaves, and is repeated from its answer while the true residual is too
    large (scipy tightens its inner tolerance from cycle to cycle within a
    call, so a call per cycle would cost iterations).

    With `give_up` (for a caller that has a fall-back), stop as soon as the
    solve is projected not to converge within `maxiter`: during the first
    call, every STALL_CHECK iterations, when the preconditioned residual's
    fall since the first iteration, extrapolated at its mean rate, would not
    reach KRYLOV_RTOL within `maxiter`; after each call, the same with the
    true residual.  Returns (x, converged, iterations, residual ratio): the
    true relative residual ||A x - b|| / ||b||, or after a stop within the
    first call the preconditioned residual's fall (x is then not usable)."""
    from scipy.sparse.linalg import gmres

    count = [0]
    first = []  # preconditioned residuals of the first call

    def callback(pr):
        count[0] += 1
        if give_up and len(first) == count[0] - 1:
            first.append(pr)
            k = count[0]
            if k % STALL_CHECK == 0 and k < maxiter:
                ratio = pr / first[0] if first[0] > 0.0 else 0.0
                if 1 + _projected(k - 1, ratio) > maxiter:
                    first.append(ratio)
                    raise _Stalled

    x = np.zeros_like(b) if x0 is None else np.array(x0, dtype=b.dtype)
    norm_b = np.linalg.norm(b)
    target = KRYLOV_RTOL * norm_b
    ok = False
    rel = 1.0
    while count[0] < maxiter:
        before = count[0]
        try:
            x, _ = gmres(
                A,
                b,
                x0=x,
                M=M,
                rtol=KRYLOV_RTOL,
                atol=0.0,
                # as many whole cycles as the cap leaves, in one call: scipy
                # tightens its inner (preconditioned) tolerance from one cycle
                # to the next, which a call per cycle would reset (measured:
                # 13 calls and 65 V-cycles instead of 1 and 41 on the
                # 400 x 400 reservoir case, 5.9 against 4.1 s)
                restart=min(restart, maxiter - before),
                maxiter=max(1, (maxiter - before) // min(restart, maxiter - before)),
                callback=callback,
                callback_type="pr_norm",
            )
        except _Stalled:
            return x, False, count[0], float(first[-1])
        first.append(None)  # the first call is over
        if not np.all(np.isfinite(x)):
            rel = np.inf
            break
        res = np.linalg.norm(A @ x - b)
        rel = res / norm_b if norm_b > 0.0 else res
        ok = res <= target
        if ok or count[0] == before:
            break
        if give_up and count[0] < maxiter and _projected(count[0], rel) > maxiter:
            break
    return x, bool(ok), count[0], float(rel)


def rigid_body_modes(xy: np.ndarray, component: np.ndarray) -> np.ndarray:
    """(m, 3) translations and in-plane rotation at dofs of the given node
    coordinates (m, 2) and components (m,) 0 = x, 1 = y."""
    B = np.zeros((xy.shape[0], 3))
    B[component == 0, 0] = 1.0
    B[component == 1, 1] = 1.0
    xc = xy - xy.mean(axis=0)
    B[:, 2] = np.where(component == 0, -xc[:, 1], xc[:, 0])
    return B


class LinearSolver:
    """Solves (K_ff + K_c) x = r for a run, keeping what does not change.

    K_ff : bulk stiffness on the free dofs (constant for the run).
    method : "auto" | "superlu" | "amg".
    free : global dof of each free dof (n_free,).
    node_xy : (n_nodes, 2) node coordinates; standard dofs are 2*node + c and
        every dof from 2*n_nodes on is enriched.  Needed by "amg" (rigid-body
        modes); without it "auto" means "superlu".
    dof_node : (n_free,) the node of each dof: SuperLU factors the whole
        matrix in a nested-dissection order of the grid (ordering.py, with
        node_xy); None: in its own minimum-degree order.
    """

    def __init__(
        self,
        K_ff,
        method="auto",
        free=None,
        node_xy=None,
        contact_dofs=None,
        kernels="numpy",
        contact_coef=None,
        contact_stick=None,
        dof_node=None,
    ):
        if method not in LINEAR_SOLVERS:
            raise ValueError(f"linear solver must be one of {LINEAR_SOLVERS}")
        self.K = sp.csr_matrix(K_ff)
        n = self.K.shape[0]
        self.free = np.arange(n) if free is None else np.asarray(free)
        self.node_xy = node_xy
        # free-dof index of each contact block row/column (-1: none), for
        # solve_contact
        self.contact_dofs = (
            np.zeros((0, 0), np.int64) if contact_dofs is None else contact_dofs
        )
        # the patches' jump coefficients (m, J) on contact_dofs and their
        # stuck tangents (m, 2, 2) (lowrank.stick_tangents): with both, a
        # network's PARDISO systems are low-rank changes of the stuck matrix
        self.contact_coef = contact_coef
        self.contact_stick = contact_stick
        # the kernel backend that gathers the contact blocks (the model's)
        self.kernels = kernels
        self.dof_node = dof_node
        self._order: np.ndarray | None = None  # elimination_order(), once made
        self.facts = {"n_free": n}

        def band_share() -> float:
            self.facts = system_facts(self.K, self.free, node_xy)
            return self.facts["band_share"]

        # the share of enriched dofs, for the grid's order (None: no order
        # without the nodes of the dofs and their coordinates)
        self.enriched_share = (
            None
            if node_xy is None or dof_node is None
            else float(enriched_mask(self.free, node_xy).mean())
            if n
            else 0.0
        )
        self.method = choose(method, n, node_xy, band_share)
        if self.method == "amg" and node_xy is None:
            raise ValueError("the AMG linear solver needs the node coordinates")
        if self.method == "pardiso" and not pardiso.available():
            raise ValueError(
                "linear_solver 'pardiso' needs MKL PARDISO: pip install 'xfemslip[mkl]'"
            )
        hint = method == "auto" and self.method != "pardiso"
        # a crowded network on SuperLU says once what PARDISO would gain,
        # unless the line below has (_solve_augmented)
        self._network_hint = (
            hint and n < PARDISO_HINT_MIN_DOFS and not pardiso.available()
        )
        if hint and n >= PARDISO_HINT_MIN_DOFS:
            logger.info(
                "linear solver: %s; with MKL PARDISO (pip install "
                "'xfemslip[mkl]') the linear solves of meshes this size took "
                "1/%.1f to 1/%.1f of the time",
                self.method,
                *PARDISO_GAIN,
            )
        self.stats = {
            "method": self.method,
            "factorizations": 0,
            "factor_time": 0.0,
            "setup_time": 0.0,
            "solves": 0,
            "krylov_iterations": 0,
            "guesses_exact": 0,
            "solve_time": 0.0,
            "refinements": 0,
            "fallbacks": 0,
            "fallback_time": 0.0,
            "amg_fallbacks": 0,
            "amg_fallback_time": 0.0,
            "pardiso_analyses": 0,
            "pardiso_spd": 0,
            "pardiso_unsym": 0,
            "pardiso_schur": 0,
            "schur_factorizations": 0,
            "pardiso_fallbacks": 0,
            "pardiso_lowrank": 0,
            "lowrank_superlu": 0,
            "lowrank_updates": 0,
            "lowrank_rank": 0,
            "shared_reuses": 0,
        }
        # pardiso.SchurSystems or PardisoSystems, made on the first solve, and
        # the pattern of the sparse Kc they were made for (None: the blocks')
        self._pardiso = None
        self._pardiso_key = None
        self._lu = None  # (SuperLU object, checked solve, K_c it factors)
        # lowrank.AugmentedLU for a crowded network on SuperLU, made on the
        # first contact solve; False: not used in this run
        self._augmented: lowrank.AugmentedLU | bool | None = None
        # the contact blocks of the system being solved and of the factored
        # one (solve_contact), for _kept_gmres
        self._blocks_now = None
        self._lu_blocks = None
        # shared.SharedSchurSystems within shared.sharing(); False: not usable
        self._shared: shared.SharedSchurSystems | bool | None = None
        self._amg = None  # V-cycle on the standard dofs
        # the Krylov solves start from the best combination of the last
        # solutions (solve/guess.py)
        self._previous = PreviousSolutions()
        self._band_lu = None  # (band, Kc, SuperLU of the band's matrix)
        # the AMG band of "auto"'s facts is the one the AMG path solves on
        self._bands = (
            {AMG_BAND_LAYERS: self.facts["band"]} if "band" in self.facts else {}
        )
        if "band_share" in self.facts:
            logger.debug(
                "linear solver: %s (auto: %d free dofs, %.1f %% enriched, "
                "AMG band %.1f %% of them (AMG up to %.0f %%), cells up to "
                "%.1f:1 (AMG up to %.0f:1))",
                self.method,
                n,
                100.0 * self.facts["enriched_share"],
                100.0 * self.facts["band_share"],
                100.0 * AUTO_AMG_MAX_BAND,
                cell_aspect_ratio(node_xy),
                AUTO_AMG_MAX_ASPECT,
            )
        elif method == "auto":
            logger.debug(
                "linear solver: %s (auto: %d free dofs, AMG from %d)",
                self.method,
                n,
                AUTO_AMG_MIN_DOFS,
            )
        else:
            logger.debug("linear solver: %s (%d free dofs)", self.method, n)
        if self.method in ("superlu", "amg") and self.enriched_share is not None:
            logger.debug(
                "SuperLU order: %s (%.1f %% of the dofs enriched; the grid's "
                "up to %.0f %%)",
                "nested dissection of the grid"
                if grid_order_applies(self.enriched_share)
                else "minimum degree",
                100.0 * self.enriched_share,
                100.0 * GRID_ORDER_MAX_ENRICHED,
            )

    def elimination_order(self) -> np.ndarray | None:
        """SuperLU's order of the free dofs for the whole matrix: the nested
        dissection of the grid (ordering.py) where it applies
        (grid_order_applies), made once; None: SuperLU's minimum degree
        (also without dof_node or node_xy: no enriched share then)."""
        if self._order is None and grid_order_applies(self.enriched_share):
            self._order = ordering.grid_order(self.dof_node, self.node_xy)
        return self._order

    def blas_threads(self) -> contextlib.AbstractContextManager:
        """The context the Newton solve runs in: OpenBLAS on one thread
        when PARDISO solves (its MKL threads and OpenBLAS's would wait for
        each other's cores: xfemslip.kernels.threads) and on the bordered
        SuperLU factorization of a crowded network (lowrank.AugmentedLU),
        else nothing.  The latter's dense work is a LU of a few hundred rows
        per new tangent and products with the jump block: on the
        100-fracture network the LU took 1-4 ms on one thread and, at
        random, 80-100 ms on two (0.24-0.39 s against 0.04 s per run)."""
        if not (
            self.method == "pardiso"
            or (self.method == "superlu" and self._augmented_applies())
        ):
            return contextlib.nullcontext()
        from xfemslip.kernels.threads import one_openblas_thread

        return one_openblas_thread()

    # ------------------------------------------------------------------ #
    def solve_contact(self, blocks, r):
        """x with (K_ff + sum of the contact blocks) x = r; blocks (m, k, k)
        on the rows and columns contact_dofs (m, k), or None."""
        # the paths that keep a factorization of their own, in turn; each
        # returns None when it does not apply or has failed
        for applies, path in (
            (lambda: self.method == "pardiso", self._solve_pardiso_contact),
            (lambda: self.method == "superlu" and shared.active(), self._solve_shared),
            (
                lambda: self.method == "superlu" and self._augmented is not False,
                self._solve_augmented,
            ),
        ):
            if applies():
                start = time.perf_counter()
                x = path(blocks, r)
                if x is not None:
                    self.stats["solves"] += 1
                    self.stats["solve_time"] += time.perf_counter() - start
                    return x
        Kc = None
        if blocks is not None and np.size(blocks):
            Kc = coo_block(self.contact_dofs, blocks, self.K.shape[0], self.kernels)
        self._blocks_now = blocks
        try:
            return self.solve(Kc, r)
        finally:
            self._blocks_now = None

    def _solve_pardiso_contact(self, blocks, r):
        """The PARDISO solve of the contact blocks, made on the first call;
        after a failure of the low-rank path, once more on the general one
        (None when PARDISO has failed altogether)."""
        if self._pardiso is None:
            self._make_pardiso_contact()
        x = self._solve_pardiso(blocks, self._symmetric(blocks), r)
        if x is None and self.method == "pardiso":  # low-rank failed
            x = self._solve_pardiso(blocks, self._symmetric(blocks), r)
        return x

    def _solve_augmented(self, blocks, r):
        """The solve on one SuperLU factorization of the stuck matrix
        augmented by the patch jumps (lowrank.AugmentedLU), for networks
        whose contact blocks would go to PARDISO's low-rank path; None when
        it does not apply or has failed (logged once; this and the later
        systems of the run go to the kept factorization of the whole
        matrix)."""
        if self._augmented is None:
            if not self._augmented_applies():
                self._augmented = False
                return None
            dofs = self._patch_dofs()
            rows = 2 * dofs.shape[0]
            self._augmented = lowrank.AugmentedLU(
                self.K,
                dofs,
                self.contact_coef,
                self.contact_stick,
                LU_BACKWARD_ERROR,
                self.stats,
                LU_FAST,
                kernels=self.kernels,
            )
            if self._network_hint:
                logger.info(
                    "linear solver: SuperLU, one factorization bordered by %d "
                    "patch jumps; with MKL PARDISO (pip install 'xfemslip[mkl]') "
                    "crowded networks ran in about 1/%.1f of the time",
                    rows,
                    PARDISO_NETWORK_GAIN,
                )
        assert isinstance(self._augmented, lowrank.AugmentedLU)
        t = time.perf_counter()
        try:
            return self._augmented.solve(self._augmented.values(blocks), False, r)
        except RuntimeError as exc:
            logger.warning(
                "%s after %.2f s; SuperLU on the whole matrix solves this and "
                "the later systems of the run",
                exc,
                time.perf_counter() - t,
            )
            self._augmented.release()
            self._augmented = False
            return None

    def _solve_shared(self, blocks, r):
        """The solve on the Schur factors kept between runs of the same
        bulk matrix (xfemslip.solve.shared), or None: none apply (too many
        contact dofs, K_ii singular) or the solve missed LU_BACKWARD_ERROR
        (then this and the later systems of the run take the kept SuperLU
        path)."""
        if self._shared is None:
            dofs = np.asarray(self.contact_dofs, dtype=np.int64)
            if dofs.ndim != 2:
                dofs = dofs.reshape(len(dofs), -1)
            c = np.unique(dofs[dofs >= 0])
            try:
                schur = shared.kept_schur(self.K, c, LU_FAST, self.stats)
            except RuntimeError:  # K_ii singular: a part held by contact only
                schur = None
            if schur is None:
                self._shared = False
                return None
            self._shared = shared.SharedSchurSystems(
                schur, dofs, LU_BACKWARD_ERROR, self.stats
            )
        if self._shared is False:
            return None
        x = self._shared.solve(blocks, r)
        if x is None:
            logger.debug("shared Schur solve missed the backward error; SuperLU")
            self._shared = False
        return x

    def _symmetric(self, blocks) -> bool:
        """Whether the contact blocks are symmetric (pardiso.symmetric_blocks;
        not needed by the low-rank systems, whose dense LU takes either)."""
        if isinstance(self._pardiso, lowrank.LowRankSystems):
            return False
        return pardiso.symmetric_blocks(blocks)

    def _make_pardiso_contact(self, lowrank_ok=True):
        """The PARDISO systems for the contact blocks: pardiso.make_systems
        (the Schur complement on up to SCHUR_MAX_DOFS contact dofs, else a
        fixed pattern), or, for more contact dofs with the patches' jump
        coefficients known and at most lowrank.MAX_ROWS jump rows, the
        low-rank changes of the stuck matrix (lowrank.LowRankSystems)."""
        dofs = np.asarray(self.contact_dofs, dtype=np.int64)
        if dofs.ndim != 2:  # (m, k): m = 0 without a fracture
            dofs = dofs.reshape(len(dofs), -1)
        if lowrank_ok and self._lowrank_applies(dofs):
            self._release_pardiso()
            self._pardiso = lowrank.LowRankSystems(
                self.K,
                dofs,
                self.contact_coef,
                self.contact_stick,
                LU_BACKWARD_ERROR,
                self.stats,
            )
            return
        k = dofs.shape[1]
        shape = (dofs.shape[0], k, k)
        self._make_pardiso(
            np.broadcast_to(dofs[:, :, None], shape),
            np.broadcast_to(dofs[:, None, :], shape),
            None,
        )

    def _patch_dofs(self) -> np.ndarray:
        """contact_dofs as (patches, dofs of a patch)."""
        dofs = np.asarray(self.contact_dofs, dtype=np.int64)
        return dofs if dofs.ndim == 2 else dofs.reshape(len(dofs), -1)

    def _augmented_applies(self) -> bool:
        """Whether the contact blocks go to lowrank.AugmentedLU (with
        SuperLU): the low-rank form holds and the jump rows are few enough."""
        if self._augmented is not None:
            return self._augmented is not False
        dofs = self._patch_dofs()
        return (
            self._lowrank_applies(dofs)
            and 2 * dofs.shape[0] <= lowrank.AUGMENTED_MAX_ROWS
        )

    def _lowrank_applies(self, dofs) -> bool:
        """Whether the contact blocks go to lowrank.LowRankSystems."""
        if self.contact_coef is None or self.contact_stick is None:
            return False
        m = dofs.shape[0]
        if m == 0 or 2 * m > lowrank.MAX_ROWS:
            return False
        if np.unique(dofs[dofs >= 0]).size <= pardiso.SCHUR_MAX_DOFS:
            return False  # the Schur complement on the contact dofs is smaller
        D0 = np.asarray(self.contact_stick)
        return bool(
            np.all(np.isfinite(D0)) and np.all(np.linalg.eigvalsh(D0)[:, 0] > 0.0)
        )

    def _make_pardiso(self, rows, cols, key):
        """The PARDISO systems for contact entries at (rows, cols); `key`: the
        pattern of the sparse Kc they are made for (None: the blocks')."""
        self._release_pardiso()
        self._pardiso = pardiso.make_systems(
            self.K, rows, cols, LU_BACKWARD_ERROR, self.stats
        )
        self._pardiso_key = key

    def _solve_pardiso(self, entries, symmetric, r):
        """The PARDISO solve on the kept pattern, or None after a failure
        (logged; this and the later systems of the run go to SuperLU)."""
        t = time.perf_counter()
        try:
            return self._pardiso.solve(self._pardiso.values(entries), symmetric, r)
        except pardiso.PardisoError as exc:
            if isinstance(self._pardiso, lowrank.LowRankSystems):
                # the general PARDISO path solves this and the later systems
                logger.warning(
                    "%s after %.2f s; PARDISO on the whole matrix solves this "
                    "and the later systems of the run",
                    exc,
                    time.perf_counter() - t,
                )
                self.stats["pardiso_fallbacks"] += 1
                self._make_pardiso_contact(lowrank_ok=False)
                return None
            self.stats["pardiso_fallbacks"] += 1
            logger.warning(
                "%s after %.2f s; SuperLU solves this and the later systems of the run",
                exc,
                time.perf_counter() - t,
            )
            self._release_pardiso()
            self.method = "superlu"
            return None

    def _release_pardiso(self):
        if self._pardiso is not None:
            self._pardiso.release()
        self._pardiso = None
        self._pardiso_key = None

    def solve(self, Kc, r):
        """x with (K_ff + Kc) x = r; Kc is (n_free, n_free) sparse or None.

        Raises RuntimeError when the matrix is singular (as SuperLU does).
        """
        start = time.perf_counter()
        if Kc is None:
            Kc = sp.csr_matrix(self.K.shape)
        Kc = sp.csr_matrix(Kc)
        if self.method == "pardiso":
            x = self._solve_pardiso_matrix(Kc, r)
        elif self.method == "amg":
            x = self._solve_amg(Kc, r)
        else:
            x = self._solve_superlu(Kc, r)
        self.stats["solves"] += 1
        self.stats["solve_time"] += time.perf_counter() - start
        return x

    def _solve_pardiso_matrix(self, Kc, r):
        """solve() with a sparse Kc on PARDISO: its stored entries are the
        contact entries of systems kept while Kc's pattern stays."""
        Kc.sort_indices()
        key = self._pardiso_key
        if (
            self._pardiso is None
            or key is None
            or not np.array_equal(key[0], Kc.indptr)
            or not np.array_equal(key[1], Kc.indices)
        ):
            coo = Kc.tocoo()
            self._make_pardiso(coo.row, coo.col, (Kc.indptr.copy(), Kc.indices.copy()))
        symmetric = Kc.nnz == 0 or pardiso.matrix_symmetric(Kc)
        x = self._solve_pardiso(Kc.data, symmetric, r)
        if x is None:
            return self._solve_superlu(Kc, r)
        return x

    # ------------------------------------------------------------------ #
    def _band(self, layers, Kc):
        """Free dofs within `layers` matrix neighbours of the enriched dofs
        (without node coordinates: of the dofs the contact tangent touches)."""
        if layers not in self._bands:
            if self.node_xy is None:
                seed = np.diff(sp.csr_matrix(Kc).indptr) > 0
            else:
                seed = enriched_mask(self.free, self.node_xy)
            self._bands[layers] = np.nonzero(band_mask(self.K, seed, layers))[0]
        return self._bands[layers]

    def _schwarz_gmres(
        self, A, Kc, r, coarse, band, cycles, restart, cap, give_up=False
    ):
        """GMRES on A = K_ff + Kc, A x = r, preconditioned by one
        multiplicative Schwarz sweep: `coarse` (an approximate inverse: the
        kept factorization, or the AMG V-cycle on the standard dofs), an exact
        LU solve on the dofs `band` with the current matrix (kept while Kc,
        which lives on the band, does not change), and (cycles == 2) `coarse`
        again.  None when
        GMRES does not converge or the band matrix is singular (then
        self._krylov_end holds the iterations and relative residual reached).
        `give_up`: see _gmres."""
        from scipy.sparse.linalg import LinearOperator

        x0, res0 = self._previous.guess(A, r)
        if x0 is not None and res0 <= KRYLOV_RTOL * np.linalg.norm(r):
            self.stats["guesses_exact"] += 1
            self._krylov_end = (0, res0 / max(np.linalg.norm(r), 1e-300))
            logger.debug("linear solve: the earlier solutions span this one")
            return x0
        kept = self._band_lu
        if kept is not None and kept[0] is band and _same(Kc, kept[1]):
            band_lu = kept[2]
        else:
            t = time.perf_counter()
            try:
                band_lu, _ = lu_factor(A[band][:, band], self.stats)
            except RuntimeError:  # singular band: let SuperLU judge the whole matrix
                self._krylov_end = (0, np.inf)
                return None
            self.stats["factor_time"] += time.perf_counter() - t
            self._band_lu = (band, Kc, band_lu)

        # the band's rows of A: the band solve needs the residual there only
        # (a product with the whole of A was about a tenth of a sweep)
        A_band = A[band]

        def sweep(v):
            x = coarse(v)
            x[band] += band_lu.solve(v[band] - A_band @ x)
            if cycles == 2:
                x += coarse(v - A @ x)
            return x

        M = LinearOperator(A.shape, matvec=sweep, dtype=float)
        x, ok, its, rel = _gmres(A, r, M, restart, cap, give_up, x0)
        self.stats["krylov_iterations"] += its
        if ok:
            self._previous.add(x)
        self._krylov_end = (its, rel)
        logger.debug("linear solve: Schwarz-GMRES, %d iterations (%s)", its, ok)
        return x if ok else None

    def _factor(self, A, Kc):
        t = time.perf_counter()
        lu, solve = lu_factor(A, self.stats, self.elimination_order())
        self.stats["factorizations"] += 1
        self.stats["factor_time"] += time.perf_counter() - t
        self._lu = (lu, solve, Kc)
        blocks = self._blocks_now
        self._lu_blocks = None if blocks is None else np.array(blocks, copy=True)
        return solve

    def _change_rank(self) -> int | None:
        """An upper bound of the rank of the change of the contact tangent
        since the factored system: 2 per contact patch whose block changed
        (None when the blocks are not known)."""
        now, ref = self._blocks_now, self._lu_blocks
        if now is None or ref is None or np.shape(now) != ref.shape:
            return None
        now = np.asarray(now)
        if now.size == 0:
            return 0
        return 2 * int(lowrank.changed_patches(now, ref).size)

    def _kept_gmres(self, A, r):
        """GMRES on A x = r preconditioned by the kept factorization alone,
        or None when the change since it is unknown or too large
        (KEPT_GMRES_MAX) or GMRES has not converged within its bound."""
        from scipy.sparse.linalg import LinearOperator

        rank = self._change_rank()
        if rank is None or rank + 1 + KEPT_GMRES_EXTRA > KEPT_GMRES_MAX:
            return None
        cap = rank + 1 + KEPT_GMRES_EXTRA
        x0, res0 = self._previous.guess(A, r)
        if x0 is not None and res0 <= KRYLOV_RTOL * np.linalg.norm(r):
            self.stats["guesses_exact"] += 1
            return x0
        lu = self._lu[0]
        M = LinearOperator(A.shape, matvec=lu.solve, dtype=float)
        x, ok, its, rel = _gmres(A, r, M, cap, cap, False, x0)
        self.stats["krylov_iterations"] += its
        logger.debug(
            "linear solve: GMRES with the kept factorization, %d iterations "
            "(change of rank <= %s; %s, residual ratio %.1e)",
            its,
            rank,
            "converged" if ok else "refactoring",
            rel,
        )
        if not ok:
            return None
        self._previous.add(x)
        return x

    def _solve_superlu(self, Kc, r):
        # CSR for the products of the Krylov solves; SuperLU's CSC made only
        # for a factorization (a conversion per Newton system was 0.1 s of
        # each at 147k dofs)
        if self._lu is not None and _same(Kc, self._lu[2]):
            return self._lu[1](r)
        A = sp.csr_matrix(self.K + Kc)
        if self._lu is not None:
            lu, solve, Kc_ref = self._lu
            band = self._band(LU_BAND_LAYERS, Kc)
            if 0 < band.size <= LU_BAND_MAX_FRACTION * A.shape[0]:
                x = self._schwarz_gmres(
                    A,
                    Kc,
                    r,
                    lu.solve,
                    band,
                    1,
                    REUSE_MAX_ITERATIONS,
                    REUSE_MAX_ITERATIONS,
                )
            else:
                x = self._kept_gmres(A, r)
            if x is not None:
                return x
            # the old factors go before the new ones are made: two at once
            # were 0.4 GB more at the peak of a 100-fracture network
            del lu, solve, Kc_ref
            self._lu = self._lu_blocks = None
        return self._factor(A.tocsc(), Kc)(r)

    # ------------------------------------------------------------------ #
    def _setup_amg(self):
        from xfemslip.solve.amg import geometric, smoothed_aggregation, v_cycle

        t = time.perf_counter()
        n_std = 2 * self.node_xy.shape[0]
        std = np.nonzero(self.free < n_std)[0]
        dof = self.free[std]
        K_ss = self.K[std][:, std].tocsr()
        # the hierarchies stop at up to AMG_MAX_COARSE nodes, solved exactly
        # by a sparse LU, rather than pyamg's default of 10 (pseudo-inverse).
        # The grid's own coarse grids where the nodes are a rectilinear grid
        # (solve.amg), else smoothed aggregation: B is the exact
        # near-nullspace (the rigid-body modes), so pyamg's relaxation of the
        # candidates is left out (the same GMRES iterations on the reservoir
        # case at 986k dofs, the set-up 1.0 s shorter); the spectral radius
        # of the prolongation smoother by Lanczos (solve.amg)
        ml = geometric(K_ss, self.node_xy, dof, AMG_MAX_COARSE)
        kind = "geometric"
        if ml is None:
            B = rigid_body_modes(self.node_xy[dof // 2], dof % 2)
            ml = smoothed_aggregation(K_ss, B, AMG_MAX_COARSE)
            kind = "smoothed aggregation"
        V = v_cycle(ml)

        def cycle(v):
            x = np.zeros(v.shape)
            x[std] = V(v[std])
            return x

        self._amg = cycle
        self.stats["setup_time"] += time.perf_counter() - t
        logger.debug(
            "multigrid (%s): %d levels, operator complexity %.2f",
            kind,
            len(ml.levels),
            ml.operator_complexity(),
        )

    def _solve_amg(self, Kc, r):
        from scipy.sparse.linalg import LinearOperator, cg

        start = time.perf_counter()
        if self._amg is None:
            self._setup_amg()
        A = (self.K + Kc).tocsr()
        band = self._band(AMG_BAND_LAYERS, Kc)
        if band.size == 0:  # no enrichment: SPD, CG with the V-cycle
            count = [0]

            def callback(_):
                count[0] += 1

            M = LinearOperator(A.shape, matvec=self._amg, dtype=float)
            x0, _ = self._previous.guess(A, r)
            x, info = cg(
                A,
                r,
                x0=x0,
                M=M,
                rtol=KRYLOV_RTOL,
                atol=0.0,
                maxiter=AMG_MAX_ITERATIONS,
                callback=callback,
            )
            self.stats["krylov_iterations"] += count[0]
            if info == 0 and np.all(np.isfinite(x)):
                self._previous.add(x)
                return x
            its = count[0]
            rel = np.linalg.norm(A @ x - r) / max(np.linalg.norm(r), 1e-300)
        else:
            x = self._schwarz_gmres(
                A,
                Kc,
                r,
                self._amg,
                band,
                1,
                AMG_RESTART,
                AMG_MAX_ITERATIONS,
                AMG_STALL_STOP,
            )
            if x is not None:
                return x
            its, rel = self._krylov_end
        # the time spent on AMG for this system (its set-up if it was the
        # first, the band LU, the Krylov iterations) is lost
        wasted = time.perf_counter() - start
        self.method = "superlu"
        self.stats["amg_fallbacks"] += 1
        self.stats["amg_fallback_time"] += wasted
        logger.warning(
            "AMG-preconditioned Krylov solve did not converge (%d iterations, "
            "residual ratio %.1e, %.2f s lost); SuperLU solves this and the "
            "later systems of the run",
            its,
            rel,
            wasted,
        )
        return self._factor(A.tocsc(), Kc)(r)


def _same(a, b) -> bool:
    """Two sparse matrices equal entry by entry (same stored pattern)."""
    return (
        a.shape == b.shape
        and a.nnz == b.nnz
        and np.array_equal(a.indptr, b.indptr)
        and np.array_equal(a.indices, b.indices)
        and np.array_equal(a.data, b.data)
    )
