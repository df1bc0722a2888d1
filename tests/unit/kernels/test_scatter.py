"""kernels.block_triplets / assembly.coo_block against a dense double loop."""

import numpy as np
import pytest

from xfemslip import kernels
from xfemslip.fem.assembly import coo_block


def _padded(seed, m=40, k=10, n=30):
    rng = np.random.default_rng(seed)
    dofs = rng.integers(0, n, size=(m, k))
    dofs[rng.random((m, k)) < 0.4] = -1  # empty slots anywhere in a row
    dofs[0] = -1  # an item without any dof
    blocks = rng.standard_normal((m, k, k))
    return dofs.astype(np.int64), blocks, n


@pytest.mark.parametrize("backend", ["numba", "numpy"])
def test_triplets_are_the_masked_expansion_in_order(backend):
    dofs, blocks, _ = _padded(1)
    r, c, v = kernels.backend(backend).block_triplets(dofs, blocks)
    k = dofs.shape[1]
    rows = np.repeat(dofs, k, axis=1).ravel()
    cols = np.tile(dofs, (1, k)).ravel()
    keep = (rows >= 0) & (cols >= 0)
    np.testing.assert_array_equal(r, rows[keep])
    np.testing.assert_array_equal(c, cols[keep])
    np.testing.assert_array_equal(v, blocks.ravel()[keep])


@pytest.mark.parametrize("backend", ["numba", "numpy"])
def test_coo_block_sums_every_kept_entry(backend):
    dofs, blocks, n = _padded(2)
    dense = np.zeros((n, n))
    for e in range(dofs.shape[0]):
        for i, di in enumerate(dofs[e]):
            for j, dj in enumerate(dofs[e]):
                if di >= 0 and dj >= 0:
                    dense[di, dj] += blocks[e, i, j]
    np.testing.assert_allclose(
        coo_block(dofs, blocks, n, backend).toarray(), dense, rtol=1e-14, atol=1e-14
    )


@pytest.mark.parametrize("backend", ["numba", "numpy"])
def test_no_kept_entry_gives_an_empty_matrix(backend):
    dofs = -np.ones((3, 4), np.int64)
    K = coo_block(dofs, np.ones((3, 4, 4)), 5, backend)
    assert K.shape == (5, 5) and K.nnz == 0
