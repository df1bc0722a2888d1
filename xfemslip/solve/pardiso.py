"""MKL PARDISO for the Newton systems (K_ff + K_c) du = r (``linear_solver =
"pardiso"``, the ``mkl`` extra: ``pip install 'xfemslip[mkl]'``, which brings
pypardiso and with it Intel MKL).  One module (about 550 lines): the ctypes
calling convention, the two ways below and their shared analysis state.

K_c only has entries among the contact dofs c (the rows and columns of the
contact blocks, along the fractures), and the rest of the matrix is K_ff,
fixed for the run.  Two ways to use that:

- SchurSystems (when the contact dofs are 1 to SCHUR_MAX_DOFS): K_ff is
  factored ONCE for the run in SPD mode (Cholesky, mtype 2) with the dofs c
  eliminated last; PARDISO returns their dense Schur complement S0 =
  K_cc - K_ci K_ii^-1 K_ic.  Every Newton system, symmetric or not (the
  consistent slip tangent couples n and t), is then a dense LU of
  S0 + K_c (m x m, m = |c|) and partial forward/backward substitutions.
  So the first system costs about one SPD factorization of the uncracked
  mesh (the floor) and every later one, in every Newton iteration, load step
  and deplete bisection step, a dense LU and a few substitutions.  Measured
  on the reservoir case at 400 x 400 (324k dofs, m = 1022, 2 threads): SPD
  analysis and factorization with the Schur block 2.2 s, dense LU 0.23 s,
  solve 0.2 s, against 5.4 s for the analysis and factorization of the
  unsymmetric matrix (mtype 11, 67M entries in L + U).
- PardisoSystems (more contact dofs, e.g. large networks, where the dense
  block would be too big): every Newton matrix on one union pattern
  (FixedPattern: the positions of the contact block entries in its CSR data
  found once, each matrix a copy of K_ff's data plus the block values),
  the symbolic analysis (phase 11) once per matrix type and run, then a
  numerical factorization (phase 22) per new matrix.  Two modes, one handle
  each so each keeps its analysis and its last factorization: SPD (mtype 2,
  upper triangle) when the contact blocks are symmetric -- no fracture, every
  patch stuck or open, frictionless, the secant tangent -- and unsymmetric
  (UNSYMMETRIC_MTYPE) for the consistent slip tangent, chosen per system
  from its blocks.

PARDISO is called directly through ctypes (MKL located by pypardiso), with
0-based int32 index arrays made once: pypardiso's own ``solve`` copies and
re-checks the whole matrix on every call.  Every solve is checked like the
SuperLU path's (xfemslip.solve.linear.lu_factor): normwise backward error at most
LU_BACKWARD_ERROR, one step of iterative refinement if not, and the caller
falls back to SuperLU (with a log line) when that fails or PARDISO reports an
error.
"""

from __future__ import annotations

import ctypes
import importlib.util
import logging
import os
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from xfemslip.solve.backward import backward_error, refined

logger = logging.getLogger(__name__)

MTYPE_SPD = 2  # real symmetric positive definite
# Real unsymmetric: 1 (structurally symmetric, no pivoting beyond perturbation)
# or 11 (general, with weighted matching and scaling).  The union pattern is
# structurally symmetric (K_ff symmetric, contact blocks square on their dofs).
# Measured on the reservoir case at 400 x 400, analysis + factorization, runs
# alternated (load 2.3-3.3 on 2 cores): 5.4 and 5.7 s (mtype 11), 5.0 and
# 5.0 s (mtype 1), the same 67M factor entries; 11 for its pivoting (matching
# and scaling) at under 10 % more.
UNSYMMETRIC_MTYPE = 11
# Blocks symmetric to this relative round-off go to the SPD mode (the backward
# error check below then judges the solve against the exact matrix).
SYMMETRY_RTOL = 1.0e-12


# the package that linear_solver = "pardiso" needs (the mkl extra)
PARDISO_PACKAGE = "pypardiso"


def available() -> bool:
    """Whether MKL PARDISO (the mkl extra: pypardiso) is installed."""
    return importlib.util.find_spec(PARDISO_PACKAGE) is not None


class PardisoError(RuntimeError):
    """PARDISO returned an error code (see the MKL PARDISO documentation)."""

    def __init__(self, phase: int, code: int, message: str = ""):
        super().__init__(message or f"PARDISO phase {phase} failed with error {code}")
        self.phase = phase
        self.code = code


_LIB = None


def _mkl_rt_path() -> str | None:
    """libmkl_rt of the installed ``mkl`` distribution, from its file list
    (or PYPARDISO_MKL_RT, pypardiso's own override); None when not found.

    pypardiso finds the library by walking every folder under sys.prefix
    (0.35 s in a virtual environment with the test packages, twice: its
    import makes a solver too); the distribution's record names the file."""
    override = os.environ.get("PYPARDISO_MKL_RT")
    if override:
        return override
    from importlib.metadata import PackageNotFoundError, distribution

    try:
        files = distribution("mkl").files or []
    except PackageNotFoundError:
        return None
    found = sorted((f for f in files if "mkl_rt" in f.name), key=lambda f: len(str(f)))
    for path in found:
        located = Path(str(path.locate()))
        if located.is_file():
            return str(located)
    return None


def _pardiso_function():
    """MKL's pardiso entry point with its ctypes signature (pypardiso's
    declaration); pypardiso itself is imported only when the library is not
    where the ``mkl`` distribution says."""
    global _LIB
    if _LIB is None:
        path = _mkl_rt_path()
        try:
            fn = ctypes.CDLL(path).pardiso if path else None
        except OSError:
            fn = None
        if fn is None:
            import pypardiso

            fn = pypardiso.PyPardisoSolver()._mkl_pardiso
        else:
            c_int_p = ctypes.POINTER(ctypes.c_int32)
            void_p = ctypes.POINTER(None)
            fn.argtypes = [
                ctypes.POINTER(ctypes.c_int64),  # pt
                *[c_int_p] * 5,  # maxfct, mnum, mtype, phase, n
                void_p,  # a
                *[c_int_p] * 5,  # ia, ja, perm, nrhs, iparm
                c_int_p,  # msglvl
                void_p,  # b
                void_p,  # x
                c_int_p,  # error
            ]
            fn.restype = None
        _LIB = fn
    return _LIB


class Handle:
    """One PARDISO instance: one matrix type, one pattern (0-based CSR,
    sorted column indices), its analysis and its last factorization.

    Counters: analyses (phase 11), factorizations (phase 22), solves (33)."""

    def __init__(self, mtype: int, indptr, indices, schur=None):
        self.fn = _pardiso_function()
        self.mtype = int(mtype)
        self.n = int(indptr.size - 1)
        self.ia = np.ascontiguousarray(indptr, dtype=np.int32)
        self.ja = np.ascontiguousarray(indices, dtype=np.int32)
        self.pt = np.zeros(64, dtype=np.int64)
        self.iparm = np.zeros(64, dtype=np.int32)
        ip = self.iparm
        ip[0] = 1  # the values below, not the defaults
        # the parallel (OpenMP) nested dissection and the two-level
        # factorization: measured on the uncracked reservoir mesh with a
        # 45-degree band of contact dofs eliminated last (2 threads, in-process,
        # 2 runs each), analysis + factorization 1.42-1.57 s -> 1.10-1.17 s at
        # 324k dofs (m = 1018) and 15.0-15.2 s -> 13.0-13.6 s at 2.0M (m =
        # 2546); the plain SPD factorization 0.95-1.27 -> 0.89-0.97 s and
        # 10.1-11.1 -> 8.3-8.5 s
        ip[1] = 3  # METIS nested dissection, parallel
        ip[23] = 1  # two-level factorization (parallel over the tree's top)
        ip[7] = 0  # refinement steps: the solver's automatic choice
        ip[9] = 13 if self.mtype == 11 else 8  # pivot perturbation 1e-13 / 1e-8
        ip[10] = 1 if self.mtype == 11 else 0  # scaling
        ip[12] = 1 if self.mtype == 11 else 0  # weighted matching
        ip[17] = -1  # report the factor's nonzeros
        ip[34] = 1  # 0-based indices
        self.perm = np.zeros(1, dtype=np.int32)
        # schur: rows (sorted) eliminated last; factor() then also returns
        # their dense Schur complement and the partial solves (phases 331 to
        # 333) work on the other rows
        self.schur = None if schur is None else np.asarray(schur)
        if self.schur is not None:
            self.perm = np.zeros(self.n, dtype=np.int32)
            self.perm[self.schur] = 1
            ip[35] = 2  # Schur complement and the factors of the other rows
        self.schur_matrix = None
        self.analyses = 0
        self.factorizations = 0
        self.solves = 0
        self.factored = None  # the data of the last factored matrix

    def _call(self, phase, data, b=None, x=None):
        n = self.n
        b = np.zeros(n) if b is None else np.ascontiguousarray(b, dtype=np.float64)
        if x is None:
            x = np.zeros(n)
        err = ctypes.c_int32(0)
        i32 = ctypes.POINTER(ctypes.c_int32)
        f64 = ctypes.POINTER(ctypes.c_double)
        self.fn(
            self.pt.ctypes.data_as(ctypes.POINTER(ctypes.c_int64)),
            ctypes.byref(ctypes.c_int32(1)),  # maxfct
            ctypes.byref(ctypes.c_int32(1)),  # mnum
            ctypes.byref(ctypes.c_int32(self.mtype)),
            ctypes.byref(ctypes.c_int32(phase)),
            ctypes.byref(ctypes.c_int32(n)),
            data.ctypes.data_as(f64),
            self.ia.ctypes.data_as(i32),
            self.ja.ctypes.data_as(i32),
            self.perm.ctypes.data_as(i32),
            ctypes.byref(ctypes.c_int32(1)),  # nrhs
            self.iparm.ctypes.data_as(i32),
            ctypes.byref(ctypes.c_int32(0)),  # msglvl
            b.ctypes.data_as(f64),
            x.ctypes.data_as(f64),
            ctypes.byref(err),
        )
        if err.value != 0:
            raise PardisoError(phase, err.value)
        return x

    def factor(self, data):
        """Numerical factorization of the matrix with values `data` (the
        analysis first, once)."""
        data = np.ascontiguousarray(data, dtype=np.float64)
        if self.analyses == 0:
            self._call(11, data)
            self.analyses += 1
        self.factored = None
        if self.schur is None:
            self._call(22, data)
        else:  # the dense Schur complement comes back in x
            m = self.schur.size
            out = np.zeros(max(m * m, self.n))
            self._call(22, data, None, out)
            self.schur_matrix = out[: m * m].reshape(m, m).copy()
        self.factorizations += 1
        self.factored = data.copy()

    def solve_schur(self, b, schur_solution):
        """With schur rows: x with A x = b, the schur rows' part x_s given by
        ``schur_solution(rhs_s)`` from the forward-eliminated right-hand side
        rhs_s = b_s - A_si A_ii^-1 b_i, and then x_i = A_ii^-1 (b_i - A_is
        x_s) on the other rows: one forward and one backward substitution
        (phases 331 and 333; the diagonal phase 332 between them also scales
        the schur rows, which are set again)."""
        y = self._call(331, self.factored, b)
        xs = np.asarray(schur_solution(y[self.schur].copy()), dtype=np.float64)
        y[self.schur] = xs
        w = self._call(332, self.factored, y)
        w[self.schur] = xs
        x = self._call(333, self.factored, w)
        x[self.schur] = xs
        self.solves += 1
        return x

    def solve(self, b):
        """x with A x = b for the last factored A."""
        x = self._call(33, self.factored, b)
        self.solves += 1
        return x

    def is_factored(self, data) -> bool:
        return self.factored is not None and np.array_equal(self.factored, data)

    @property
    def factor_nnz(self) -> int:
        return int(self.iparm[17])

    def release(self):
        """Free PARDISO's memory for this handle."""
        if self.analyses:
            try:
                self._call(-1, np.zeros(max(self.ja.size, 1)))
            except PardisoError:
                pass
            self.analyses = 0
            self.factored = None

    def __del__(self):
        try:
            self.release()
        except Exception:  # interpreter shutdown
            pass


class FixedPattern:
    """K_ff plus contact entries on a pattern fixed for the run.

    K : (n, n) sparse, the bulk stiffness on the free dofs.
    rows, cols : the row and column (free-dof index, -1: none) of every
        contact entry, flattened; from_blocks makes them for (m, k, k) blocks.

    ``data(values)`` is the CSR data of K plus the contact entries' values
    (duplicates summed) on the union pattern (indptr, indices); ``upper``
    indexes that data for the upper triangle (indptr_upper, indices_upper)
    the SPD mode factors.
    """

    def __init__(self, K, rows, cols):
        K = sp.csr_matrix(K)
        K.sum_duplicates()
        K.sort_indices()
        n = K.shape[0]
        rows = np.asarray(rows, dtype=np.int64).ravel()
        cols = np.asarray(cols, dtype=np.int64).ravel()
        self.valid = (rows >= 0) & (cols >= 0)
        rows, cols = rows[self.valid], cols[self.valid]
        ones = sp.csr_matrix((np.ones(K.nnz), K.indices, K.indptr), shape=(n, n))
        if rows.size:
            ones = ones + sp.csr_matrix((np.ones(rows.size), (rows, cols)), (n, n))
        ones.sum_duplicates()
        ones.sort_indices()
        self.n = n
        self.indptr = ones.indptr.astype(np.int32)
        self.indices = ones.indices.astype(np.int32)
        row_of = np.repeat(np.arange(n, dtype=np.int64), np.diff(ones.indptr))
        keys = row_of * n + ones.indices
        k_rows = np.repeat(np.arange(n, dtype=np.int64), np.diff(K.indptr))
        k_pos = np.searchsorted(keys, k_rows * n + K.indices)
        self.contact_pos = np.searchsorted(keys, rows * n + cols)
        self.base = np.zeros(keys.size)
        self.base[k_pos] = K.data
        up = ones.indices >= row_of
        self.upper = np.nonzero(up)[0]
        self.indptr_upper = np.concatenate(
            ([0], np.cumsum(np.bincount(row_of[up], minlength=n)))
        ).astype(np.int32)
        self.indices_upper = ones.indices[up].astype(np.int32)

    @classmethod
    def from_blocks(cls, K, dofs):
        """The pattern of K and (m, k, k) blocks on the dofs (m, k)."""
        dofs = np.asarray(dofs, dtype=np.int64)
        m = dofs.shape[0]
        if dofs.ndim != 2:
            dofs = dofs.reshape(m, -1)
        k = dofs.shape[1]
        rows = np.broadcast_to(dofs[:, :, None], (m, k, k))
        cols = np.broadcast_to(dofs[:, None, :], (m, k, k))
        return cls(K, rows, cols)

    def values(self, entries) -> np.ndarray:
        """The contact entries' values in the order of contact_pos, from
        `entries` shaped like the rows/cols given (e.g. the blocks)."""
        if entries is None or self.contact_pos.size == 0:
            return np.zeros(self.contact_pos.size)
        return np.asarray(entries, dtype=np.float64).reshape(-1)[self.valid]

    def data(self, values) -> np.ndarray:
        out = self.base.copy()
        if values.size:
            np.add.at(out, self.contact_pos, values)
        return out

    def matrix(self, data) -> sp.csr_matrix:
        """The CSR matrix with values `data` on the union pattern (shares it)."""
        return sp.csr_matrix(
            (data, self.indices, self.indptr), shape=(self.n, self.n), copy=False
        )


def symmetric_blocks(blocks) -> bool:
    """Whether every contact block equals its transpose to SYMMETRY_RTOL."""
    if blocks is None or np.size(blocks) == 0:
        return True
    B = np.asarray(blocks)
    scale = np.abs(B).max()
    return bool(np.abs(B - B.transpose(0, 2, 1)).max() <= SYMMETRY_RTOL * scale)


def matrix_symmetric(K) -> bool:
    """Whether the sparse matrix K equals its transpose to SYMMETRY_RTOL."""
    K = sp.csr_matrix(K)
    if K.nnz == 0:
        return True
    diff = abs(K - K.T)
    return bool(diff.max() <= SYMMETRY_RTOL * abs(K).max())


class PardisoSystems:
    """The Newton systems of one run on PARDISO: one FixedPattern, one Handle
    per mode (SPD, unsymmetric), each analysed once.

    solve(values, symmetric, r) returns x, for the contact entries' values
    (FixedPattern.values) and whether they are symmetric, with backward error
    at most `max_error` (after one refinement step if needed), or raises
    PardisoError (a PARDISO error,
    or a solve that stays above `max_error`: the caller falls back)."""

    def __init__(self, K, pattern: FixedPattern, max_error: float, stats: dict):
        self.pattern = pattern
        # K_ff is symmetric by construction (see make_systems); a solve in
        # the SPD mode that misses the backward-error bound is redone in
        # the unsymmetric one
        self.spd_possible = True
        self.max_error = max_error
        self.stats = stats
        self.handles: dict[int, Handle] = {}
        self._norm: dict[int, float] = {}  # mtype -> infinity norm of its matrix

    def _handle(self, mtype: int) -> Handle:
        if mtype not in self.handles:
            p = self.pattern
            if mtype == MTYPE_SPD:
                self.handles[mtype] = Handle(mtype, p.indptr_upper, p.indices_upper)
            else:
                self.handles[mtype] = Handle(mtype, p.indptr, p.indices)
        return self.handles[mtype]

    def values(self, entries) -> np.ndarray:
        return self.pattern.values(entries)

    @property
    def analyses(self) -> int:
        return sum(h.analyses for h in self.handles.values())

    def release(self):
        for h in self.handles.values():
            h.release()

    def solve(self, values, symmetric: bool, r) -> np.ndarray:
        import time

        p = self.pattern
        data = p.data(values)
        A = p.matrix(data)
        modes = [UNSYMMETRIC_MTYPE]
        if self.spd_possible and symmetric:
            modes.insert(0, MTYPE_SPD)
        last: PardisoError | None = None
        for mtype in modes:
            h = self._handle(mtype)
            values = data[p.upper] if mtype == MTYPE_SPD else data
            t = time.perf_counter()
            try:
                if not h.is_factored(values):
                    analysed = h.analyses
                    h.factor(values)
                    self._norm[mtype] = float(abs(A).sum(axis=1).max())
                    self.stats["factorizations"] += 1
                    self.stats["pardiso_analyses"] += h.analyses - analysed
                    self.stats["factor_time"] += time.perf_counter() - t
                x = h.solve(r)
            except PardisoError as exc:
                last = exc
                logger.debug("PARDISO (mtype %d): %s", mtype, exc)
                continue
            err = backward_error(A, x, r, self._norm[mtype])
            if not err <= self.max_error and np.isfinite(err):
                self.stats["refinements"] += 1
                x = x + h.solve(r - A @ x)
                err = backward_error(A, x, r, self._norm[mtype])
            if err <= self.max_error:
                self.stats["pardiso_" + ("spd" if mtype == MTYPE_SPD else "unsym")] += 1
                return x
            last = PardisoError(
                33, 0, f"PARDISO (mtype {mtype}) backward error {err:.1e}"
            )
            logger.debug("%s", last)
        assert last is not None  # every mode failed, the last one said why
        raise last


# The Schur mode (SchurSystems) is used up to this many contact dofs: its
# dense Schur complement takes 8 m^2 bytes (128 MiB at 4000) and its dense
# LU 2/3 m^3 flops per new contact tangent (0.23 s at m = 1022, 2 threads).
SCHUR_MAX_DOFS = 4000


class SchurSystems:
    """The Newton systems of one run on one SPD PARDISO factorization.

    K_c only has entries among the contact dofs c (the rows and columns of
    the contact blocks), so with the other free dofs i

        A = [[K_ii, K_ic], [K_ci, K_cc + K_c]]

    and A_ii = K_ii, A_ic = K_ic never change.  K_ff is factored once for the
    run in SPD mode (Cholesky, mtype 2) with the dofs c eliminated last;
    PARDISO returns their dense Schur complement S0 = K_cc - K_ci K_ii^-1 K_ic
    (iparm[35] = 2).  Every Newton system, symmetric or not, is then

        x_c = (S0 + K_c)^-1 (b_c - K_ci K_ii^-1 b_i)   (dense LU, m x m)
        x_i = K_ii^-1 (b_i - K_ic x_c)                 (partial solves)

    so a new contact tangent costs one dense LU of size m = |c| and a solve
    one forward and one backward substitution (Handle.solve_schur).
    solve(values, symmetric, r) as PardisoSystems (`symmetric` is not
    needed: the dense LU takes either)."""

    def __init__(self, K, rows, cols, max_error: float, stats: dict):
        K = sp.csr_matrix(K)
        K.sum_duplicates()  # also sorts the indices (no-op when canonical)
        self.K = K
        n = K.shape[0]
        rows = np.asarray(rows, dtype=np.int64).ravel()
        cols = np.asarray(cols, dtype=np.int64).ravel()
        self.valid = (rows >= 0) & (cols >= 0)
        rows, cols = rows[self.valid], cols[self.valid]
        self.c = np.unique(np.concatenate([rows, cols]))
        local = np.full(n, -1, dtype=np.int64)
        local[self.c] = np.arange(self.c.size)
        m = self.c.size
        self.flat = local[rows] * m + local[cols]  # into the dense m x m block
        # per-row sums over the CSR segments rather than bincounts over a
        # row index per entry: 0.29 s instead of 0.86 s at 2.0M dofs
        row_of = np.repeat(np.arange(n, dtype=K.indices.dtype), np.diff(K.indptr))
        up = K.indices >= row_of
        del row_of
        indptr_upper = np.concatenate(([0], np.cumsum(_row_sums(up, K.indptr))))
        self.handle = Handle(MTYPE_SPD, indptr_upper, K.indices[up], schur=self.c)
        self._upper = np.ascontiguousarray(K.data[up])
        self.K_cc = K[self.c][:, self.c].toarray()
        self._row_norm = _row_sums(np.abs(K.data), K.indptr)
        # |K| row sums of the rows c outside the columns c
        self._row_out = self._row_norm[self.c] - np.abs(self.K_cc).sum(axis=1)
        self.max_error = max_error
        self.stats = stats
        # (dense LU, the contact values it is for, their dense block, norm of A)
        self._lu: tuple[tuple, np.ndarray, np.ndarray, float] | None = None

    def values(self, entries) -> np.ndarray:
        if entries is None or self.flat.size == 0:
            return np.zeros(self.flat.size)
        return np.asarray(entries, dtype=np.float64).reshape(-1)[self.valid]

    @property
    def analyses(self) -> int:
        return self.handle.analyses

    def release(self):
        self.handle.release()

    def _factor(self, values):
        import time

        import scipy.linalg as sla

        h = self.handle
        t = time.perf_counter()
        if h.factored is None:
            h.factor(self._upper)
            self.stats["factorizations"] += 1
            self.stats["pardiso_analyses"] += 1
        m = self.c.size
        Kc = np.bincount(self.flat, weights=values, minlength=m * m).reshape(m, m)
        S = h.schur_matrix + Kc
        if not np.all(np.isfinite(S)):
            raise PardisoError(22, 0)
        lu = sla.lu_factor(S, check_finite=False)
        # infinity norm of A = K + K_c: rows i as K's, rows c from their
        # part outside c and the dense block K_cc + K_c
        norm = max(
            float(np.delete(self._row_norm, self.c).max(initial=0.0)),
            float((self._row_out + np.abs(self.K_cc + Kc).sum(axis=1)).max()),
        )
        self._lu = (lu, values.copy(), Kc, norm)
        self.stats["schur_factorizations"] += 1
        self.stats["factor_time"] += time.perf_counter() - t

    def _apply(self, x):
        """A x."""
        Kc = self._lu[2]
        y = self.K @ x
        y[self.c] += Kc @ x[self.c]
        return y

    def _solve(self, b):
        import scipy.linalg as sla

        lu = self._lu[0]
        return self.handle.solve_schur(
            b, lambda rhs: sla.lu_solve(lu, rhs, check_finite=False)
        )

    def solve(self, values, symmetric: bool, r) -> np.ndarray:
        if self._lu is None or not np.array_equal(self._lu[1], values):
            self._factor(values)
        assert self._lu is not None
        norm = self._lu[3]
        x, err = refined(self._solve, self._apply, r, norm, self.max_error, self.stats)
        if err <= self.max_error:
            self.stats["pardiso_schur"] += 1
            return x
        raise PardisoError(33, 0, f"PARDISO Schur solve: backward error {err:.1e}")


def _row_sums(values, indptr) -> np.ndarray:
    """Sum of `values` over each CSR row segment (0 for an empty row)."""
    starts = indptr[:-1]
    nonempty = starts < indptr[1:]
    dtype = np.int64 if values.dtype == bool else values.dtype
    out = np.zeros(starts.size, dtype=dtype)
    if values.size:
        out[nonempty] = np.add.reduceat(values, starts[nonempty], dtype=dtype)
    return out


def make_systems(K, rows, cols, max_error: float, stats: dict):
    """SchurSystems when the contact entries touch 1 to SCHUR_MAX_DOFS dofs,
    PardisoSystems otherwise.

    K (K_ff) is symmetric by construction (element matrices B^T D B), which
    the Schur mode's Cholesky relies on; it is not checked here (a transpose
    of K: 0.3 s at 324k dofs), the backward error of every solve, against
    the whole matrix, is."""
    rows = np.asarray(rows, dtype=np.int64).ravel()
    cols = np.asarray(cols, dtype=np.int64).ravel()
    ok = (rows >= 0) & (cols >= 0)
    m = np.unique(np.concatenate([rows[ok], cols[ok]])).size
    if 0 < m <= SCHUR_MAX_DOFS:
        return SchurSystems(K, rows, cols, max_error, stats)
    return PardisoSystems(K, FixedPattern(K, rows, cols), max_error, stats)
