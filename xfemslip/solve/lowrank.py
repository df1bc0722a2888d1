"""The Newton systems of a crowded fracture network on one factorization
(PARDISO's, LowRankSystems, or SuperLU's, AugmentedLU): the contact tangent
as a low-rank change of the stuck matrix.

The contact tangent is a sum over the contact patches,

    K_c = sum_i L_i^T D_i L_i,

with L_i (2 x n) the jump of patch i averaged over it ([[u]]_i = L_i u, the
coefficients ``coef`` on the x and y dofs ``dofs``, xfemslip.contact.interface)
and D_i (2 x 2) the patch length times the return map's tangent
d(traction)/d[[u]] in x-y (xfemslip.kernels.contact: each patch block is
w c c^T (x) C).  A network has far more contact dofs than patches (10,778
against 988 on 100 fractures at 200 x 200 cells), so the Schur complement on
the contact dofs (pardiso.SchurSystems) would be a dense block of 10,778^2
entries, but one on the 2m patch jumps is small.

With D0_i = w_i (k_N n n^T + k_T t t^T) the tangent of a stuck patch and
M = D0^1/2 L (2m x n), the stuck matrix R = K_ff + M^T M is factored ONCE
per run in SPD mode (Cholesky), inside the augmented matrix

    B = [[R, -M^T], [-M, 2 I]]

with the 2m jump rows eliminated last: PARDISO returns their dense Schur
complement 2 I - G, G = M R^-1 M^T (eigenvalues in [0, 1], so the block is
well conditioned), and the factors of R for the partial solves.  B is SPD
whenever R is: x^T B x = x^T K_ff x + |M x - z|^2 + |z|^2.  Every Newton
matrix is then

    A = R + M^T E M,   E_i = D0_i^-1/2 (D_i - D0_i) D0_i^-1/2,

where E_i is zero on the stuck patches, of rank 1 on a slipping one (the
consistent and the secant tangent change only the shear row) and -I on an
open one.  With E = P_U P_V^T (the 2 x 2 SVDs, k columns, k = the rank of
the change), Sherman-Morrison-Woodbury gives

    x0 = R^-1 r,   (I + P_V^T G P_U) y = P_V^T M x0,   x = x0 - R^-1 M^T P_U y:

a dense LU of size k per new tangent, and per system one forward and one
backward substitution with B's factors (M x0 comes out of the forward one
on the jump rows, and the correction goes into the backward one there:
LowRankSystems._solve).  Measured on the 100-fracture network (147k dofs,
988 patches, 2 threads, loaded machine): the factorization with the Schur
block 7.9 s against 11.1 s analysis and 3.8 s per factorization of the
unsymmetric matrix; each later system 0.4-0.6 s for k = 300-550.  Every
solve is checked against the whole matrix by its backward error, as
everywhere.
"""

from __future__ import annotations

import logging
import time

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from xfemslip.solve.backward import refined
from xfemslip.solve.pardiso import MTYPE_SPD, Handle, PardisoError

logger = logging.getLogger(__name__)

# Largest number of patch jump rows (2 per patch) of the Schur block: it takes
# 8 (2m)^2 bytes (288 MB at 6000) and a dense LU of up to that size per new
# contact tangent.  Larger networks use pardiso.PardisoSystems.
MAX_ROWS = 6000
# A patch block is of the form w c c^T (x) C when it differs from that
# product by at most this much of its largest entry (round-off: 1.4e-16
# measured); a tangent change E_i, relative to the stuck tangent, smaller
# than this is none (the stuck patches' tangents, formed by the kernel, equal
# D0 to round-off).
FORM_RTOL = 1.0e-12
# Patches checked for that form at a time (patch_tangents).
FORM_CHUNK = 128


def stick_tangents(weight, kn, kt, normal, tangent) -> np.ndarray:
    """D0 (m, 2, 2) [N/m^2 . m]: the patch length times the stuck patch's
    tangent k_N n n^T + k_T t t^T (xfemslip.kernels.contact), in x-y."""
    nn = normal[:, :, None] * normal[:, None, :]
    tt = tangent[:, :, None] * tangent[:, None, :]
    return weight[:, None, None] * (kn[:, None, None] * nn + kt[:, None, None] * tt)


def _sqrt_spd2(D, power):
    """D^power (m, 2, 2) of symmetric positive definite 2 x 2 matrices."""
    lam, Q = np.linalg.eigh(D)
    return np.einsum("mij,mj,mkj->mik", Q, lam**power, Q)


def jump_matrix(dofs, coef, n) -> sp.csr_matrix:
    """L (2m, n): row 2i + a gives component a of patch i's jump from the n
    free dofs (dofs (m, 2J), -1 skipped; coef (m, J))."""
    m = coef.shape[0]
    rows, cols, vals = [], [], []
    for a in (0, 1):
        d = dofs[:, a::2]
        ok = d >= 0
        rows.append(np.broadcast_to((2 * np.arange(m) + a)[:, None], d.shape)[ok])
        cols.append(d[ok])
        vals.append(coef[ok])
    return sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=(2 * m, n),
    )


def changed_patches(blocks, ref) -> np.ndarray:
    """The patches (indices) whose contact blocks (m, k, k) differ from
    those of ``ref`` in some entry."""
    return np.nonzero(np.any(blocks != ref, axis=(1, 2)))[0]


def patch_tangents(blocks, coef, dofs):
    """D (m, 2, 2) with blocks[i] = c_i c_i^T (x) D_i, or None when some block
    is not of that form (to FORM_RTOL).  D_i is read at the coefficient of
    largest magnitude whose two dofs are free (0 for a patch without one)."""
    m, J = coef.shape
    free = (dofs[:, 0::2] >= 0) & (dofs[:, 1::2] >= 0)
    k = np.argmax(np.where(free, np.abs(coef), -1.0), axis=1)
    ck = coef[np.arange(m), k]
    live = free[np.arange(m), k] & (ck != 0.0)
    D = np.zeros((m, 2, 2))
    i = np.nonzero(live)[0]
    for a in (0, 1):
        for b in (0, 1):
            D[i, a, b] = blocks[i, 2 * k[i] + a, 2 * k[i] + b] / ck[i] ** 2
    # the check in chunks of patches: its temporaries are a few copies of
    # the blocks, which on a crowded network (988 patches of up to 96 x 96)
    # would otherwise add to the run's peak memory
    for p in range(0, m, FORM_CHUNK):
        q = slice(p, p + FORM_CHUNK)
        cc = coef[q, :, None] * coef[q, None, :]  # (chunk, J, J)
        recon = cc[:, :, None, :, None] * D[q, None, :, None, :]
        recon = recon.reshape(-1, 2 * J, 2 * J)
        recon -= blocks[q]
        scale = np.abs(blocks[q]).max(axis=(1, 2))
        if np.any(np.abs(recon).max(axis=(1, 2)) > FORM_RTOL * scale):
            return None
    return D


class LowRankSystems:
    """The Newton systems of one run: one SPD factorization of the stuck
    matrix with the Schur complement on the patch jumps, and per contact
    tangent a dense LU of its low-rank change (module docstring).

    K : (n, n) the bulk stiffness on the free dofs (symmetric).
    dofs : (m, 2J) free-dof index of each patch's jump dofs (-1: none);
    coef : (m, J) their coefficients; D0 : (m, 2, 2) stick_tangents.
    solve(blocks, symmetric, r) as pardiso.SchurSystems (the blocks (m, 2J,
    2J) are the contact entries' values); raises PardisoError on a PARDISO
    error, a block not of the patch form or a solve above `max_error`.
    """

    def __init__(self, K, dofs, coef, D0, max_error: float, stats: dict):
        K = sp.csr_matrix(K)
        n = K.shape[0]
        self.n = n
        self.dofs = np.asarray(dofs, dtype=np.int64)
        self.coef = np.asarray(coef, dtype=np.float64)
        self.D0 = D0
        self.D0_mhalf = _sqrt_spd2(D0, -0.5)
        self.L = jump_matrix(self.dofs, self.coef, n)
        M = sp.block_diag(list(_sqrt_spd2(D0, 0.5)), format="csr") @ self.L
        self.M = M.tocsr()
        self.Mt = self.M.T.tocsr()
        self.K = K
        self.max_error = max_error
        self.stats = stats
        self._row_abs_K = np.asarray(abs(K).sum(axis=1)).ravel()
        self._absL = abs(self.L).tocsr()
        self.G = None  # M R^-1 M^T (2m, 2m), after the factorization
        self._update = None  # (blocks, D, patch rows of the change, P_U, P_V, LU)
        self._prepare()

    def _prepare(self):
        """The PARDISO handle of B with the jump rows eliminated last."""
        n, m2 = self.n, self.M.shape[0]
        # the upper triangle of B, block by block (the whole of R and B
        # would be two more copies of the stiffness at once)
        upper = sp.bmat(
            [
                [sp.triu(self.K) + sp.triu(self.Mt @ self.M), -self.Mt],
                [None, 2.0 * sp.identity(m2)],
            ],
            format="csr",
        )
        upper.sum_duplicates()
        upper.sort_indices()
        self.handle = Handle(
            MTYPE_SPD, upper.indptr, upper.indices, schur=np.arange(n, n + m2)
        )
        self._upper = upper.data

    def values(self, entries):
        if entries is None:
            return np.zeros((self.coef.shape[0],) + (2 * self.coef.shape[1],) * 2)
        return np.asarray(entries, dtype=np.float64)

    @property
    def analyses(self) -> int:
        return self.handle.analyses

    def release(self):
        self.handle.release()

    def _factor(self):
        t = time.perf_counter()
        self.handle.factor(self._upper)
        S = self.handle.schur_matrix
        self.G = 2.0 * np.eye(S.shape[0]) - S
        self.handle.schur_matrix = None
        self.stats["factorizations"] += 1
        self.stats["pardiso_analyses"] += 1
        self.stats["factor_time"] += time.perf_counter() - t

    def _changed(self, blocks):
        """The patches whose blocks differ from the last tangent's (indices),
        or None when there is no last tangent to compare with."""
        last = self._update
        if last is None or last[0].shape != blocks.shape:
            return None
        return changed_patches(blocks, last[0])

    def _tangents(self, blocks, changed):
        """patch_tangents of `blocks`, read again only on the ``changed``
        patches (None: all) since the last tangent (most Newton iterations
        change a few: reading and checking all 988 blocks of a 100-fracture
        network took 54 ms per system)."""
        if changed is None:
            return patch_tangents(blocks, self.coef, self.dofs)
        D = self._update[1].copy()
        part = patch_tangents(blocks[changed], self.coef[changed], self.dofs[changed])
        if part is None:
            return None
        D[changed] = part
        return D

    def _set_tangent(self, blocks, changed=None):
        """The dense LU of I + P_V^T G P_U for the tangent of `blocks`, of
        which the ``changed`` patches differ from the last tangent's (None:
        no last tangent)."""
        t = time.perf_counter()
        D = self._tangents(blocks, changed)
        if D is None:
            raise PardisoError(0, 0, "contact blocks not of the patch form")
        E = self.D0_mhalf @ (D - self.D0) @ self.D0_mhalf
        act = np.nonzero(np.abs(E).max(axis=(1, 2)) > FORM_RTOL)[0]
        U, sig, Vt = np.linalg.svd(E[act])  # (a, 2, 2), (a, 2), (a, 2, 2)
        p, s = np.nonzero(sig > FORM_RTOL)  # column k: patch act[p], value s
        pu = U[p, :, s] * sig[p, s][:, None]  # (k, 2)
        pv = Vt[p, s, :]  # (k, 2)
        rows = 2 * act[p]  # first jump row of each column's patch
        # P_V^T G P_U from the four (k, k) blocks G[rows + a, rows + b]: each
        # column of P_U and P_V has its two entries on its patch's two rows
        # (the (2m, k) columns G P_U first took 20 ms per tangent at 2m =
        # 1,976, k = 550: a strided gather)
        cap = np.eye(rows.size)
        for a in (0, 1):
            for b in (0, 1):
                cap += pv[:, a : a + 1] * self.G[np.ix_(rows + a, rows + b)] * pu[:, b]
        if not np.all(np.isfinite(cap)):
            raise PardisoError(22, 0)
        lu = sla.lu_factor(cap, check_finite=False) if rows.size else None
        # the blocks compared with next time: the last copy with its changed
        # patches replaced (a whole copy took 8 ms per system on the
        # 100-fracture network), once nothing above can fail any more
        if changed is None:
            ref = blocks.copy()
        else:
            ref = self._update[0]
            ref[changed] = blocks[changed]
        self._update = (ref, D, rows, pu, pv, lu)
        self.stats["lowrank_updates"] += 1
        self.stats["lowrank_rank"] = max(self.stats["lowrank_rank"], int(rows.size))
        self.stats["factor_time"] += time.perf_counter() - t

    def _scatter(self, rows, pu, y) -> np.ndarray:
        """P_U y (2m,): column c of P_U is pu[c] on rows[c] and rows[c] + 1
        (an open patch has two columns on the same rows)."""
        m2 = self.M.shape[0]
        return np.bincount(rows, pu[:, 0] * y, m2) + np.bincount(
            rows + 1, pu[:, 1] * y, m2
        )

    def _solve(self, r):
        """One forward and one backward substitution with B's factors: the
        forward one leaves g0 = M R^-1 r on the jump rows; with z = -E M x
        there, B [x; z] = [r; s] is A x = r, and M x = g0 + G z gives
        z = -P_U (I + P_V^T G P_U)^-1 P_V^T g0 (Woodbury); the backward one
        then returns x = R^-1 (r + M^T z).  (Two solves with R, one for
        R^-1 r and one for the correction, took twice the substitutions:
        1.7 s against 0.94 s for the 23 systems of a 100-fracture network.)"""
        b = np.zeros(self.handle.n)
        b[: self.n] = r
        return self.handle.solve_schur(b, self._jumps)[: self.n]

    def _jumps(self, g0):
        """z = -P_U (I + P_V^T G P_U)^-1 P_V^T g0 on the jump rows, for the
        tangent of the current system (_solve)."""
        _, _, rows, pu, pv, lu = self._update
        if lu is None:
            return np.zeros_like(g0)
        y = sla.lu_solve(lu, pv[:, 0] * g0[rows] + pv[:, 1] * g0[rows + 1])
        return -self._scatter(rows, pu, y)

    def _apply(self, x):
        """A x = K x + L^T D L x with the tangent of the current system."""
        assert self._update is not None, "apply() follows update()"
        D = self._update[1]
        j = (self.L @ x).reshape(-1, 2)
        return self.K @ x + self.L.T @ np.einsum("mab,mb->ma", D, j).ravel()

    def _norm_bound(self) -> float:
        """An upper bound of ||A||_inf: the |K| row sums plus those of the
        patch blocks |c_k c_l D_ab| (no cancellation counted)."""
        assert self._update is not None, "the bound follows update()"
        D = self._update[1]
        absc = self._absL @ np.ones(self.n)  # sum_l |c_l| per jump row
        w = (np.abs(D) * absc.reshape(-1, 2)[:, None, :]).sum(axis=2).ravel()
        return float((self._row_abs_K + self._absL.T @ w).max(initial=0.0))

    # the stats counter of the systems solved, and the name errors give
    SOLVED = "pardiso_lowrank"
    NAME = "PARDISO"

    def solve(self, blocks, symmetric: bool, r) -> np.ndarray:
        if self.G is None:
            self._factor()
        changed = self._changed(blocks)
        if changed is None or changed.size:
            self._set_tangent(blocks, changed)
        norm = self._norm_bound()
        x, err = refined(self._solve, self._apply, r, norm, self.max_error, self.stats)
        if err <= self.max_error:
            self.stats[self.SOLVED] += 1
            return x
        raise PardisoError(
            33, 0, f"{self.NAME} low-rank solve: backward error {err:.1e}"
        )


# Jump rows (2 per patch) up to which AugmentedLU applies: its ordering
# trick stores the (2m)^2 entries of the jump block (a clique; 47 MB at
# 1,976 rows), and the dense Schur block and G take 16 (2m)^2 bytes more.
AUGMENTED_MAX_ROWS = 4000


class AugmentedLU(LowRankSystems):
    """The same Newton systems on ONE SuperLU factorization of the
    augmented matrix (the default install's way for crowded networks).

    SuperLU offers no Schur complement and no partial solves, so B is
    factored whole, with the jump rows eliminated last: their block is
    stored as a dense clique (explicit zeros beside the 2 I), so the
    minimum-degree ordering of A^T + A leaves them to the end (checked on
    the permutation; where it does not, on small meshes, that ordering with
    the jump rows moved last is factored as it stands).  The trailing
    block of the factors is then the Schur complement S = 2 I - G, read off
    as L22 U22.  With E = P_U P_V^T (LowRankSystems), a Newton system
    A x = r, A = R + M^T E M, is two solves with B:

        [x0; z0] = B^-1 [r; 0],   (I + G E) g = S z0   (Woodbury, size k),
        s = -(g + 2 E g),          x = x0 + (B^-1 [0; s])_x,

    since B [x; z] = [r; s] with z = -E M x is A x = r, and g = M x.
    Measured on the 100-fracture network (147k dofs, 988 patches, one BLAS
    thread): the factorization 7.8 s and S 0.4 s, once per run, against
    2.8-4.1 s per factorization of a Newton matrix.

    With the compiled kernels (``kernels="numba"``) a system is instead ONE
    pass through the factors L and U that S is read from, as
    LowRankSystems._solve does with PARDISO's: the forward substitution
    over the stuck matrix's columns leaves g0 = M R^-1 r on the jump rows,
    Woodbury gives z there, and the backward substitution with z held
    fixed returns x (kernels/triangular.py).  Measured there: 89 ms per
    system against 2 x 62 ms, and SuperLU's own copy of the factors is
    dropped once L and U are read.
    """

    SOLVED = "lowrank_superlu"
    NAME = "SuperLU"

    def __init__(self, K, dofs, coef, D0, max_error, stats, settings, kernels="numpy"):
        self._settings = dict(settings)
        self._lu = None
        # (L, U, perm_r, perm_c) for the one-pass solves (compiled kernels)
        self._factors = None
        self._partial = kernels == "numba"
        self._order = None  # the order B was factored in (None: as it is)
        super().__init__(K, dofs, coef, D0, max_error, stats)

    def _prepare(self):
        m2 = self.M.shape[0]
        clique = sp.csr_matrix(
            (
                np.where(np.arange(m2 * m2) % (m2 + 1) == 0, 2.0, 0.0),
                np.tile(np.arange(m2), m2),
                np.arange(0, m2 * m2 + 1, m2),
            ),
            shape=(m2, m2),
        )
        self._B = sp.bmat(
            [[self.K + self.Mt @ self.M, -self.Mt], [-self.M, clique]], format="csc"
        )

    @property
    def analyses(self) -> int:
        return int(self._lu is not None or self._factors is not None)

    def release(self):
        self._lu = None
        self._factors = None

    def _factor(self):
        from scipy.sparse.linalg import splu

        t = time.perf_counter()
        n, m2 = self.n, self.M.shape[0]

        def jumps_last(lu) -> bool:
            return min(lu.perm_r[n:].min(initial=n), lu.perm_c[n:].min(initial=n)) >= n

        lu = splu(self._B, **self._settings)
        order = None
        if not jumps_last(lu):
            # small meshes: the clique is not the last of the minimum
            # degrees; the same ordering with the jump rows moved to the end,
            # factored as it stands
            order = np.argsort(lu.perm_c)
            order = np.concatenate([order[order < n], np.arange(n, n + m2)])
            del lu
            B = self._B[order][:, order].tocsc()
            lu = splu(B, **dict(self._settings, permc_spec="NATURAL"))
            del B
            if not jumps_last(lu):
                raise RuntimeError("SuperLU pivoted a patch jump row forward")
        self._B = None  # factored: not needed again (12M entries at 147k dofs)
        self._order = order
        self.G = _trailing_G(lu, n)
        if self._partial:
            # SciPy's CSC copies of the factors, made for S, serve the solves
            self._factors = (lu.L, lu.U, lu.perm_r, lu.perm_c)
        else:
            self._lu = lu
        self.stats["factorizations"] += 1
        elapsed = time.perf_counter() - t
        self.stats["factor_time"] += elapsed
        logger.debug(
            "SuperLU: the stuck matrix bordered by %d patch jumps factored in "
            "%.2f s (%.1fM entries in L + U, jump rows %s)",
            m2,
            elapsed,
            lu.nnz / 1e6,
            "ordered last" if order is None else "moved last",
        )

    def _solve(self, r):
        if self._factors is not None:
            return self._solve_partial(r)
        _, _, rows, pu, pv, lu = self._update
        n, m2 = self.n, self.M.shape[0]
        w = self._solve_B(np.concatenate([r, np.zeros(m2)]))
        z0 = w[n:]
        x0, g = w[:n], 2.0 * z0 - self.G @ z0  # S z0
        if lu is not None:  # (I + G P_U P_V^T) g = S z0 by Woodbury
            y = sla.lu_solve(lu, pv[:, 0] * g[rows] + pv[:, 1] * g[rows + 1])
            g = g - self.G @ self._scatter(rows, pu, y)
        s = -g
        if lu is not None:  # - 2 P_U P_V^T g
            s -= self._scatter(
                rows, pu, 2.0 * (pv[:, 0] * g[rows] + pv[:, 1] * g[rows + 1])
            )
        w = self._solve_B(np.concatenate([np.zeros(n), s]))
        return x0 + w[:n]

    def _solve_partial(self, r):
        """A x = r in one forward and one backward substitution with B's
        factors, Pr^T L U Pc^T = B with the jump rows last (class
        docstring): the forward one over the first n columns of L leaves
        -L21 a on the jump rows, which is g0 = M R^-1 r in their own order;
        the backward one holds the jump entries at z."""
        from xfemslip.kernels import backend

        tri = backend("numba")
        L, U, perm_r, perm_c = self._factors
        n = self.n
        if self._order is not None:
            r = r[self._order[:n]]
        y = np.zeros(L.shape[0])
        y[perm_r[:n]] = r
        tri.lower_unit_forward(L.indptr, L.indices, L.data, y, n)
        z = self._jumps(y[perm_r[n:]])
        y[perm_c[n:]] = z
        tri.upper_backward(U.indptr, U.indices, U.data, y, n)
        x = y[perm_c[:n]]
        if self._order is None:
            return x
        out = np.empty_like(x)
        out[self._order[:n]] = x
        return out

    def _solve_B(self, b):
        """B^-1 b (through the order B was factored in)."""
        if self._order is None:
            return self._lu.solve(b)
        x = np.empty_like(b)
        x[self._order] = self._lu.solve(b[self._order])
        return x


def _trailing_G(lu, n: int) -> np.ndarray:
    """G = 2 I - S from SuperLU's factors of B with the jump rows last: S is
    (L22 U22) in the original row and column order, Pr^T L U Pc^T = B.

    This is the run's memory peak on a crowded network: reading L or U makes
    SciPy keep CSC copies of both factors beside its own (633 MiB on 100
    branch-tipped fractures at 200 x 200 cells), so the dense blocks are
    read straight from those copies and formed with at most two of them
    alive at once: U22's columns in order, L22 U22 in their place (BLAS
    trmm), then the rows in order (measured there: 62 MiB above the factor
    copies, against 125 MiB for sparse slices of L22 and U22, their dense
    copies, their product and its permuted copy)."""
    rows, cols = lu.perm_r[n:] - n, lu.perm_c[n:] - n
    Q = _trailing_block(lu.U, n, cols)
    L22 = _trailing_block(lu.L, n, np.arange(cols.size))
    Q = sla.blas.dtrmm(1.0, L22, Q, lower=1, overwrite_b=1)
    del L22
    G = Q[rows]
    del Q
    np.negative(G, out=G)
    G[np.diag_indices_from(G)] += 2.0
    return G


def _trailing_block(F, n: int, columns) -> np.ndarray:
    """The dense trailing block F[n:, n + columns] of the CSC matrix F, in
    Fortran order, without a sparse copy of it."""
    m = F.shape[0] - n
    out = np.zeros((m, len(columns)), order="F")
    ptr, idx, val = F.indptr, F.indices, F.data
    for c, j in enumerate(columns):
        a, b = ptr[n + j], ptr[n + j + 1]
        r = idx[a:b]
        keep = r >= n
        out[r[keep] - n, c] = val[a:b][keep]
    return out
