"""Factorizations kept between runs that share a bulk matrix (studies).

The samples of an uncertainty study, and the members of a sweep that vary
loads, pore pressures or friction only, solve Newton systems

    A = K_ff + K_c

with the same bulk matrix K_ff on the same free dofs: only the contact
tangent K_c, on the contact dofs c, changes between Newton iterations, load
steps and samples.  With the other free dofs i,

    A = [[K_ii, K_ic], [K_ci, K_cc + K_c]],

K_ii is factored once (SuperLU) and the dense Schur complement
S0 = K_cc - K_ci K_ii^-1 K_ic formed once (m back-solves, m = |c|); every
Newton system of every run is then

    x_c = (S0 + K_c)^-1 (b_c - K_ci K_ii^-1 b_i)   (dense LU, m x m)
    x_i = K_ii^-1 (b_i - K_ic x_c)

so a new contact tangent costs a dense LU of size m, a solve one back-solve
and a dense product (W = K_ii^-1 K_ic kept; two back-solves where W would
be large), and no sparse factorization is repeated.  Every solve is checked by its
backward error against the whole A (as every linear solve of the project);
a solve that fails it returns None and the run's own solver takes it.

This is the SuperLU counterpart of ``pardiso.SchurSystems`` (which forms S0
inside PARDISO's factorization).  For one run the kept SuperLU factorization
of ``linear`` is the better choice (the m back-solves cost more than the
few refactorizations of one run on the meshes SuperLU is chosen for);
across runs, S0 is formed once for all of them.  It is used only inside
:func:`sharing` (``xfemslip.studies`` enters it in every worker), formed
when a bulk matrix comes back for a second run and kept per process for at
most MAX_KEPT bulk matrices, recognised by their content
(:func:`matrix_key`).
"""

from __future__ import annotations

import contextlib
import hashlib
import time
from collections import OrderedDict
from collections.abc import Iterator

import numpy as np
import scipy.sparse as sp

from xfemslip.solve.backward import refined

# The dense Schur complement of m contact dofs takes 8 m^2 bytes and its LU
# 2/3 m^3 flops per contact tangent; forming it takes m back-solves with
# K_ii, kept to MAX_WORK = n_free * m (4e8: 3.2 GB of right-hand sides
# would be too much, so they go in chunks of CHUNK columns).
MAX_CONTACT_DOFS = 2000
MAX_WORK = 4.0e8
CHUNK = 256
# ... and each chunk is back-solved SOLVE_COLUMNS columns at a time: with
# more right-hand sides SuperLU's triangular solves go to BLAS-3 calls that
# OpenBLAS runs on several threads, which on a loaded machine (a study on
# every core) made forming S0 of 134 contact dofs take 0.6-1.8 s in place of
# 0.12-0.16 s (5,975 dofs; 4 columns a call: 0.09-0.16 s, one: 0.16-0.35 s)
SOLVE_COLUMNS = 4
# W = K_ii^-1 K_ic is kept up to this many entries (80 MB)
MAX_KEPT_W = 10_000_000
# bulk matrices whose factors a process keeps (a study has one; a sweep
# over a few meshes alternates between a few)
MAX_KEPT = 2

_state = {"depth": 0}
_kept: OrderedDict = OrderedDict()
_values: OrderedDict = OrderedDict()  # kept_value's
_seen: OrderedDict = OrderedDict()  # keys of the bulk matrices met once
MAX_SEEN = 64


@contextlib.contextmanager
def sharing() -> Iterator[None]:
    """Within it, LinearSolver keeps the Schur factors of its bulk matrix
    for the next run with the same matrix (in this process)."""
    _state["depth"] += 1
    try:
        yield
    finally:
        _state["depth"] -= 1


def active() -> bool:
    """Whether :func:`sharing` is entered."""
    return _state["depth"] > 0


def forget() -> None:
    """Drop the kept factors and values (tests; memory)."""
    _kept.clear()
    _values.clear()
    _seen.clear()


def kept_value(key: tuple, make):
    """``make()``, kept for the next call with an equal ``key`` while
    :func:`sharing` is entered (the MAX_KEPT last keys), made anew outside
    it.  What the model build of a study keeps between its samples: the
    mesh, the fractures' geometry, the enriched cells and the bulk stiffness
    (``xfemslip.simulation``)."""
    if not active():
        return make()
    found = _values.get(key)
    if found is not None:
        _values.move_to_end(key)
        return found
    made = make()
    _values[key] = made
    while len(_values) > MAX_KEPT:
        _values.popitem(last=False)
    return made


def digest(*arrays) -> str:
    """A digest of the bytes of ``arrays`` (equal digests: equal arrays)."""
    h = hashlib.blake2b(digest_size=20)
    for a in arrays:
        a = np.ascontiguousarray(a)
        h.update(str((a.dtype.str, a.shape)).encode())
        h.update(a.tobytes())
    return h.hexdigest()


def matrix_key(K: sp.csr_matrix, c: np.ndarray) -> tuple:
    """What identifies a bulk matrix and its contact dofs: shape, and a
    digest of the pattern, the values and c (equal digests: the same
    matrix, to the bit)."""
    return (K.shape, K.nnz, c.size, digest(K.indptr, K.indices, K.data, c))


class SchurLU:
    """K_ii factored by SuperLU and the dense S0 on the contact dofs c."""

    def __init__(self, K: sp.csr_matrix, c: np.ndarray, lu_settings: dict):
        from scipy.sparse.linalg import splu

        n = K.shape[0]
        self.K = K
        self.c = c
        inner = np.ones(n, dtype=bool)
        inner[c] = False
        self.i = np.nonzero(inner)[0]
        self.K_c = K[c]  # rows c; K symmetric: K_ic = K_c[:, i]^T
        K_ci = self.K_c[:, self.i].tocsr()
        self.K_ci = K_ci
        self.K_ic = K_ci.T.tocsc()
        self.lu = splu(sp.csc_matrix(K[self.i][:, self.i]), **lu_settings)
        m = c.size
        S = self.K_c[:, c].toarray()
        # W = K_ii^-1 K_ic, kept when small: x_i = y - W x_c is then a dense
        # product in place of a second back-solve per solve
        keep = self.i.size * m <= MAX_KEPT_W
        self.W = np.empty((self.i.size, m)) if keep else None
        for start in range(0, m, CHUNK):
            cols = self.K_ic[:, start : start + CHUNK].toarray()
            W = np.empty_like(cols)
            for j in range(0, cols.shape[1], SOLVE_COLUMNS):
                W[:, j : j + SOLVE_COLUMNS] = self.lu.solve(
                    cols[:, j : j + SOLVE_COLUMNS]
                )
            S[:, start : start + CHUNK] -= K_ci @ W
            if self.W is not None:
                self.W[:, start : start + CHUNK] = W
        self.S0 = S
        self.row_norm = np.asarray(abs(K).sum(axis=1)).ravel()
        self.K_cc = self.K_c[:, c].toarray()
        self.row_out = self.row_norm[c] - np.abs(self.K_cc).sum(axis=1)


def kept_schur(K: sp.csr_matrix, c: np.ndarray, lu_settings: dict, stats: dict):
    """The SchurLU of (K, c), kept from an earlier run or made (and kept)
    when (K, c) comes for the second time; None the first time, and when
    it would be too large (MAX_CONTACT_DOFS, MAX_WORK)."""
    m = c.size
    if not 0 < m <= MAX_CONTACT_DOFS or K.shape[0] * m > MAX_WORK:
        return None
    key = matrix_key(K, c)
    found = _kept.get(key)
    if found is not None:
        _kept.move_to_end(key)
        stats["shared_reuses"] = stats.get("shared_reuses", 0) + 1
        return found
    if key not in _seen:
        # the first run of a matrix takes the run's own solver: forming S0
        # pays only for a matrix that comes back (a sweep over geometries
        # never sees one twice)
        _seen[key] = None
        while len(_seen) > MAX_SEEN:
            _seen.popitem(last=False)
        return None
    t = time.perf_counter()
    made = SchurLU(K, c, lu_settings)
    stats["factorizations"] += 1
    stats["factor_time"] += time.perf_counter() - t
    _kept[key] = made
    while len(_kept) > MAX_KEPT:
        _kept.popitem(last=False)
    return made


class SharedSchurSystems:
    """The Newton systems of one run on a kept SchurLU: per contact tangent
    a dense LU of S0 + K_c, per solve two back-solves with K_ii."""

    def __init__(self, schur: SchurLU, dofs: np.ndarray, max_error: float, stats):
        self.s = schur
        dofs = np.asarray(dofs, dtype=np.int64)
        k = dofs.shape[1] if dofs.ndim == 2 else 0
        rows = np.broadcast_to(dofs[:, :, None], (dofs.shape[0], k, k)).ravel()
        cols = np.broadcast_to(dofs[:, None, :], (dofs.shape[0], k, k)).ravel()
        self.valid = (rows >= 0) & (cols >= 0)
        local = np.full(schur.K.shape[0], -1, dtype=np.int64)
        local[schur.c] = np.arange(schur.c.size)
        m = schur.c.size
        self.flat = local[rows[self.valid]] * m + local[cols[self.valid]]
        self.max_error = max_error
        self.stats = stats
        self._lu: tuple | None = None  # (dense LU, values, K_c block, norm of A)

    def _factor(self, values) -> None:
        import scipy.linalg as sla

        s = self.s
        t = time.perf_counter()
        m = s.c.size
        Kc = np.bincount(self.flat, weights=values, minlength=m * m).reshape(m, m)
        lu = sla.lu_factor(s.S0 + Kc, check_finite=False)
        norm = max(
            float(np.delete(s.row_norm, s.c).max(initial=0.0)),
            float((s.row_out + np.abs(s.K_cc + Kc).sum(axis=1)).max()),
        )
        self._lu = (lu, values.copy(), Kc, norm)
        self.stats["schur_factorizations"] += 1
        self.stats["factor_time"] += time.perf_counter() - t

    def _apply(self, x) -> np.ndarray:
        """A x."""
        assert self._lu is not None
        y = self.s.K @ x
        y[self.s.c] += self._lu[2] @ x[self.s.c]
        return y

    def _solve(self, b) -> np.ndarray:
        import scipy.linalg as sla

        assert self._lu is not None
        s = self.s
        y = s.lu.solve(b[s.i])
        xc = sla.lu_solve(self._lu[0], b[s.c] - s.K_ci @ y, check_finite=False)
        x = np.empty_like(b)
        # einsum, not W @ xc: a threaded BLAS product of this size costs 10-20
        # times more than one thread's on a loaded machine (its threads
        # wait for cores)
        x[s.i] = y - (
            np.einsum("ij,j->i", s.W, xc)
            if s.W is not None
            else s.lu.solve(s.K_ic @ xc)
        )
        x[s.c] = xc
        return x

    def solve(self, blocks, r) -> np.ndarray | None:
        """x with (K_ff + blocks) x = r, or None when its backward error
        stays above max_error after one refinement."""
        values = (
            np.zeros(self.flat.size)
            if blocks is None or not np.size(blocks)
            else np.asarray(blocks, dtype=np.float64).reshape(-1)[self.valid]
        )
        if self._lu is None or not np.array_equal(self._lu[1], values):
            self._factor(values)
        assert self._lu is not None
        norm = self._lu[3]
        x, err = refined(self._solve, self._apply, r, norm, self.max_error, self.stats)
        return x if err <= self.max_error else None
