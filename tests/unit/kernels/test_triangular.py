"""The sparse triangular substitutions (kernels/triangular.py) against dense
solves: whole and partial, on CSC factors with unsorted row indices and the
diagonal anywhere in a column (SuperLU keeps it last in U and first in L;
the kernels must not depend on it)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp

from xfemslip.kernels.triangular import lower_unit_forward, upper_backward


def _csc(dense, rng, shuffle: bool) -> sp.csc_matrix:
    A = sp.csc_matrix(dense)
    if shuffle:  # each column's entries in a random order
        for j in range(A.shape[1]):
            a, b = A.indptr[j], A.indptr[j + 1]
            p = a + rng.permutation(b - a)
            A.indices[a:b], A.data[a:b] = A.indices[p].copy(), A.data[p].copy()
        A.has_sorted_indices = False
    return A


def _factors(n: int, seed: int, density: float = 0.2):
    rng = np.random.default_rng(seed)
    mask = rng.random((n, n)) < density
    Lw = np.tril(np.where(mask, rng.standard_normal((n, n)), 0.0), -1)
    Uw = np.triu(np.where(mask.T, rng.standard_normal((n, n)), 0.0), 1)
    Uw += np.diag(rng.uniform(1.0, 2.0, n) * rng.choice([-1.0, 1.0], n))
    return rng, Lw, Uw


@pytest.mark.parametrize("shuffle", [False, True], ids=["sorted", "unsorted"])
@pytest.mark.parametrize("seed", range(3))
def test_whole_substitutions_are_dense_triangular_solves(shuffle, seed):
    n = 60
    rng, Lw, Uw = _factors(n, seed)
    # L stored with its unit diagonal (as SciPy returns SuperLU's L): the
    # kernel must take it as 1, whatever the stored value
    Ls = Lw + np.diag(np.full(n, 7.0))
    L, U = _csc(Ls, rng, shuffle), _csc(Uw, rng, shuffle)
    b = rng.standard_normal(n)
    y = b.copy()
    lower_unit_forward(L.indptr, L.indices, L.data, y, n)
    ref = sla.solve_triangular(Lw + np.eye(n), b, lower=True, unit_diagonal=True)
    np.testing.assert_allclose(y, ref, rtol=1e-12, atol=1e-12 * abs(ref).max())
    x = b.copy()
    upper_backward(U.indptr, U.indices, U.data, x, n)
    ref = sla.solve_triangular(Uw, b, lower=False)
    np.testing.assert_allclose(x, ref, rtol=1e-12, atol=1e-12 * abs(ref).max())


@pytest.mark.parametrize("shuffle", [False, True], ids=["sorted", "unsorted"])
@pytest.mark.parametrize("k", [0, 1, 17, 40])
def test_partial_substitutions_hold_the_trailing_block(shuffle, k):
    """Forward over the first n - k columns leaves b2 - L21 a on the last k
    rows; backward with the last k entries given solves U11 p = a - U12 q."""
    n = 40 + k
    m = n - k
    rng, Lw, Uw = _factors(n, 10 + k)
    L, U = _csc(Lw + np.eye(n), rng, shuffle), _csc(Uw, rng, shuffle)
    b = rng.standard_normal(n)
    y = b.copy()
    lower_unit_forward(L.indptr, L.indices, L.data, y, m)
    a = sla.solve_triangular(
        Lw[:m, :m] + np.eye(m), b[:m], lower=True, unit_diagonal=True
    )
    np.testing.assert_allclose(y[:m], a, rtol=1e-12, atol=1e-12 * abs(a).max())
    np.testing.assert_allclose(y[m:], b[m:] - Lw[m:, :m] @ a, rtol=1e-11, atol=1e-11)
    q = rng.standard_normal(k)
    x = np.concatenate([a, q])
    upper_backward(U.indptr, U.indices, U.data, x, m)
    p = sla.solve_triangular(Uw[:m, :m], a - Uw[:m, m:] @ q, lower=False)
    np.testing.assert_allclose(x[:m], p, rtol=1e-11, atol=1e-11 * abs(p).max())
    assert np.array_equal(x[m:], q)  # the given entries are left alone


def test_zero_pivot_is_not_finite():
    """A zero on U's diagonal gives inf/nan (the caller's backward-error
    check refuses the solve), not a silent number."""
    U = sp.csc_matrix(np.array([[1.0, 2.0], [0.0, 0.0]]))
    U.eliminate_zeros()
    x = np.array([1.0, 1.0])
    upper_backward(U.indptr, U.indices, U.data, x, 2)
    assert not np.all(np.isfinite(x))
