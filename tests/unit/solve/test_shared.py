"""Schur factors kept between runs of one bulk matrix (xfemslip.solve.shared)
against a direct sparse solve of the whole matrix."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import spsolve

from xfemslip.solve import shared
from xfemslip.solve.linear import LinearSolver


def laplacian(n):
    """The SPD 5-point Laplacian of an n x n grid, plus the identity."""
    one = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(n, n))
    eye = sp.identity(n)
    return (sp.kron(one, eye) + sp.kron(eye, one) + sp.identity(n * n)).tocsr()


def contact(n_dofs, rng, m=12, k=4):
    """(m, k) dofs (some -1) and non-symmetric (m, k, k) blocks."""
    dofs = rng.choice(n_dofs, size=(m, k), replace=False)
    dofs[0, -1] = -1
    blocks = rng.normal(size=(m, k, k)) + 3.0 * np.eye(k)
    return dofs, blocks


def dense_contact(n, dofs, blocks):
    A = np.zeros((n, n))
    for d, b in zip(dofs, blocks, strict=True):
        for i, di in enumerate(d):
            for j, dj in enumerate(d):
                if di >= 0 and dj >= 0:
                    A[di, dj] += b[i, j]
    return sp.csr_matrix(A)


def test_shared_solves_match_a_direct_solve_and_are_kept():
    rng = np.random.default_rng(1)
    K = laplacian(20)
    n = K.shape[0]
    dofs, blocks = contact(n, rng)
    r = rng.normal(size=n)
    reference = spsolve((K + dense_contact(n, dofs, blocks)).tocsc(), r)
    shared.forget()
    with shared.sharing():
        # the first run of a matrix: its own SuperLU path, nothing formed
        alone = LinearSolver(K, "superlu", contact_dofs=dofs)
        np.testing.assert_allclose(
            alone.solve_contact(blocks, r), reference, rtol=1e-10, atol=1e-12
        )
        assert alone.stats["schur_factorizations"] == 0
        # it comes back: K_ii and S0 formed once, kept
        first = LinearSolver(K, "superlu", contact_dofs=dofs)
        x = first.solve_contact(blocks, r)
        np.testing.assert_allclose(x, reference, rtol=1e-10, atol=1e-12)
        assert first.stats["factorizations"] == 1  # K_ii and S0, once
        assert first.stats["schur_factorizations"] == 1
        # a third run of the same matrix (another object, same values)
        second = LinearSolver(K.copy(), "superlu", contact_dofs=dofs)
        blocks2 = blocks * 0.5
        x2 = second.solve_contact(blocks2, r)
        assert second.stats["factorizations"] == 0
        assert second.stats["shared_reuses"] == 1
    reference2 = spsolve((K + dense_contact(n, dofs, blocks2)).tocsc(), r)
    np.testing.assert_allclose(x2, reference2, rtol=1e-10, atol=1e-12)
    # without contact blocks: K x = r
    with shared.sharing():
        zero = LinearSolver(K, "superlu", contact_dofs=dofs)
        x0 = zero.solve_contact(None, r)
    assert zero.stats["shared_reuses"] == 1
    np.testing.assert_allclose(x0, spsolve(K.tocsc(), r), rtol=1e-10, atol=1e-12)


def test_outside_sharing_nothing_is_kept():
    rng = np.random.default_rng(2)
    K = laplacian(10)
    dofs, blocks = contact(K.shape[0], rng, m=4)
    shared.forget()
    solver = LinearSolver(K, "superlu", contact_dofs=dofs)
    solver.solve_contact(blocks, np.ones(K.shape[0]))
    assert solver.stats["schur_factorizations"] == 0
    assert not shared._kept


def test_a_changed_matrix_is_not_taken_for_the_kept_one():
    rng = np.random.default_rng(3)
    K = laplacian(10)
    n = K.shape[0]
    dofs, blocks = contact(n, rng, m=4)
    r = rng.normal(size=n)
    K2 = K.copy()
    K2.data = K2.data * 1.5  # another rock: the same pattern, other values
    shared.forget()
    with shared.sharing():
        for _ in range(2):  # K formed and kept
            LinearSolver(K, "superlu", contact_dofs=dofs).solve_contact(blocks, r)
        other = LinearSolver(K2, "superlu", contact_dofs=dofs)
        x = other.solve_contact(blocks, r)
    assert other.stats["shared_reuses"] == 0
    assert other.stats["schur_factorizations"] == 0  # met once: its own path
    expected = spsolve((K2 + dense_contact(n, dofs, blocks)).tocsc(), r)
    np.testing.assert_allclose(x, expected, rtol=1e-10, atol=1e-12)
