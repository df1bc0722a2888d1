"""The structured-grid assembly (assembly.grid_stiffness, add_to_grid)
against the plain sum of element matrices by COO (duplicates summed by
scipy) on graded meshes, per-cell matrices and cells left out."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from xfemslip.fem.assembly import add_to_grid, grid_stiffness, std_cell_dofs
from xfemslip.fem.mesh import build_mesh


def _coo_sum(dofs, blocks, n):
    rows = np.repeat(dofs, dofs.shape[1], axis=1).ravel()
    cols = np.tile(dofs, (1, dofs.shape[1])).ravel()
    return sp.coo_matrix((blocks.ravel(), (rows, cols)), shape=(n, n)).tocsr()


def _mesh(nx, ny, rng):
    x = np.concatenate([[0.0], np.cumsum(rng.uniform(0.5, 2.0, nx))])
    y = np.concatenate([[0.0], np.cumsum(rng.uniform(0.5, 2.0, ny))])
    return build_mesh(x, y)


@pytest.mark.parametrize("nx, ny", [(1, 1), (1, 4), (5, 1), (6, 3), (7, 9)])
@pytest.mark.parametrize("kinds", [1, 3])
def test_grid_matches_the_coo_sum(nx, ny, kinds):
    rng = np.random.default_rng(nx * 31 + ny + kinds)
    mesh = _mesh(nx, ny, rng)
    K_u = rng.standard_normal((kinds, 8, 8))
    keep = rng.random(mesh.n_cells) < 0.8  # some cells left out
    cells = np.nonzero(keep)[0]
    which = rng.integers(0, kinds, cells.size)
    K = grid_stiffness(mesh, cells, K_u, which)
    n = 2 * mesh.n_nodes
    ref = _coo_sum(std_cell_dofs(mesh.cells[cells]), K_u[which], n)
    assert K.shape == (n, n) and K.has_canonical_format
    assert abs(K - ref).max() <= 1e-14 * abs(ref).max()
    # the pattern is the whole grid's: every node with its neighbours inside
    counts = np.diff(K.indptr).reshape(ny + 1, nx + 1, 2)[:, :, 0] // 2
    ex = np.full(nx + 1, 3) - (np.arange(nx + 1) == 0) - (np.arange(nx + 1) == nx)
    ey = np.full(ny + 1, 3) - (np.arange(ny + 1) == 0) - (np.arange(ny + 1) == ny)
    assert np.array_equal(counts, np.outer(ey, ex))


def _grid_and_entries(rng, n_extra=12, picked=5):
    """A grid matrix of a graded 6 x 5 mesh (one zero entry stored) and the
    entries of `picked` enriched cells: their standard dofs and 4 dofs each
    among n_extra numbered after the standard ones, repeated."""
    mesh = _mesh(6, 5, rng)
    cells = np.arange(mesh.n_cells)
    K_u = rng.standard_normal((1, 8, 8))
    K_u[0, 0, 3] = K_u[0, 3, 0] = 0.0
    which = np.zeros(cells.size, np.int64)
    n_std = 2 * mesh.n_nodes
    chosen = rng.choice(mesh.n_cells, picked, replace=False)
    extra = n_std + rng.integers(0, n_extra, (picked, 4))
    dofs = np.concatenate([std_cell_dofs(mesh.cells[chosen]), extra], axis=1)
    blocks = rng.standard_normal((picked, 12, 12))
    rows = np.repeat(dofs, 12, axis=1).ravel()
    cols = np.tile(dofs, (1, 12)).ravel()
    grid = grid_stiffness(mesh, cells, K_u, which)
    ref = _coo_sum(std_cell_dofs(mesh.cells), K_u[which], n_std)
    return mesh, grid, ref, rows, cols, blocks.ravel()


@pytest.mark.parametrize("backend", ["numpy", "numba"])
@pytest.mark.parametrize("seed", [7, 8, 9])
def test_entries_added_keep_the_pattern_and_sort_the_rows(backend, seed):
    """Standard entries land in place, enriched rows and columns (numbered
    after the standard dofs) are appended to their rows; zeros of the grid
    stay stored."""
    rng = np.random.default_rng(seed)
    mesh, grid, ref, rows, cols, vals = _grid_and_entries(rng)
    n_std = 2 * mesh.n_nodes
    n = n_std + 12
    stored = grid.nnz
    entries = [rows.astype(np.int32), cols.astype(np.int32), vals]
    K = add_to_grid(grid, entries, np.arange(n), n, backend)
    assert entries == []  # emptied: the caller holds no copy
    ref.resize((n, n))
    ref = ref + sp.coo_matrix((vals, (rows, cols)), shape=(n, n)).tocsr()
    assert K.shape == (n, n) and K.has_canonical_format
    assert abs(K - ref).max() <= 1e-13 * abs(ref).max()
    new_pairs = np.unique(
        rows[(rows >= n_std) | (cols >= n_std)] * n
        + cols[(rows >= n_std) | (cols >= n_std)]
    )
    assert K.nnz == stored + new_pairs.size
    assert K.indices.dtype == grid.indices.dtype


@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_entries_renumbered_and_the_dropped_left_out(backend):
    """to_dof renumbers the candidate numbers after the standard dofs and
    drops some (-1): the sum is that of the kept entries, renumbered."""
    rng = np.random.default_rng(3)
    mesh, grid, ref, rows, cols, vals = _grid_and_entries(rng)
    n_std = 2 * mesh.n_nodes
    # candidate numbers n_std .. n_std + 11: every third dropped, the rest
    # numbered in reverse
    kept = np.array([k for k in range(12) if k % 3 != 1])
    to_dof = np.concatenate([np.arange(n_std), -np.ones(12, np.int64)])
    to_dof[n_std + kept] = n_std + np.arange(kept.size)[::-1]
    n = n_std + kept.size
    K = add_to_grid(grid, [rows, cols, vals], to_dof, n, backend)
    r, c = to_dof[rows], to_dof[cols]
    ok = (r >= 0) & (c >= 0)
    assert 0 < np.count_nonzero(ok) < ok.size
    ref.resize((n, n))
    ref = ref + sp.coo_matrix((vals[ok], (r[ok], c[ok])), shape=(n, n)).tocsr()
    assert K.has_canonical_format
    assert abs(K - ref).max() <= 1e-13 * abs(ref).max()


@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_a_standard_entry_outside_the_grid_is_refused(backend):
    rng = np.random.default_rng(5)
    mesh, grid, _, rows, cols, vals = _grid_and_entries(rng)
    n = 2 * mesh.n_nodes + 12
    rows = np.append(rows, 0)  # node 0 and the last node share no cell
    cols = np.append(cols, 2 * mesh.n_nodes - 1)
    vals = np.append(vals, 1.0)
    with pytest.raises(ValueError, match="outside one cell"):
        add_to_grid(grid, [rows, cols, vals], np.arange(n), n, backend)


def test_both_backends_sum_to_the_same_matrix():
    """The Numba kernel and its NumPy twin: the same pattern, each sum to
    round-off (SciPy sums the appended duplicates in an order of its own)."""
    out = {}
    for backend in ("numpy", "numba"):
        rng = np.random.default_rng(11)
        _, grid, _, rows, cols, vals = _grid_and_entries(rng, 40, 20)
        n = grid.shape[0] + 40
        out[backend] = add_to_grid(grid, [rows, cols, vals], np.arange(n), n, backend)
    a, b = out["numpy"], out["numba"]
    assert np.array_equal(a.indptr, b.indptr) and np.array_equal(a.indices, b.indices)
    assert np.abs(a.data - b.data).max() <= 1e-14 * np.abs(a.data).max()


@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_bulk_of_a_network_is_the_coo_sum_of_its_cell_matrices(backend, monkeypatch):
    """assemble_bulk on a crossing network (enriched cells taken in chunks of
    7, their entries gathered before the sliver rule in candidate numbering
    and renumbered) equals the COO sum of the intact cells' and the enriched
    cells' whole matrices on the kept dofs, and the same with one chunk."""
    from pathlib import Path

    from xfemslip import simulation
    from xfemslip.case import build, loads_case
    from xfemslip.fem import assembly
    from xfemslip.fem.enrichment import build_enriched_cells, find_candidates
    from xfemslip.fem.material import elasticity_matrix
    from xfemslip.fem.quadrature import interface_points

    root = Path(__file__).resolve().parents[3]
    case = build.file_case(
        root / "cases" / "fracture_network.toml", **{"mesh.elements": [30, 30]}
    )
    spec = loads_case(build.case_text(case), root / "cases" / "net.toml")
    mesh, fractures = simulation._geometry(spec)
    cand = find_candidates(mesh, fractures)
    ec = build_enriched_cells(mesh, fractures, cand)
    ip = interface_points(fractures, mesh.h_min)
    D = elasticity_matrix(spec.material.E, spec.material.nu, "plane_strain")
    out = {}
    for chunk in (7, 10**6):
        monkeypatch.setattr(assembly, "enriched_chunk", lambda S, c=chunk: c)
        out[chunk] = assembly.assemble_bulk(mesh, D, cand, ec, ip, backend=backend)
    bulk = out[7]
    assert bulk.dofmap.n_enriched_functions < cand.node.size  # some dropped
    assert (abs(bulk.K - out[10**6].K)).max() == 0.0
    K_e, _ = assembly._enriched_matrices(mesh, ec, D, None, backend="numpy")
    K_u, which = assembly._rect_stiffness_shared(
        *(np.diff(mesh.bounds[bulk.std_cells].reshape(-1, 2, 2), axis=2)[:, :, 0].T),
        D,
        None,
        "numpy",
    )
    n = bulk.dofmap.n_dofs
    ref = _coo_sum(std_cell_dofs(mesh.cells[bulk.std_cells]), K_u[which], n)
    dofs = bulk.enr_dofs
    ok = (dofs[:, :, None] >= 0) & (dofs[:, None, :] >= 0)
    rows = np.broadcast_to(dofs[:, :, None], K_e.shape)[ok]
    cols = np.broadcast_to(dofs[:, None, :], K_e.shape)[ok]
    ref = ref + sp.coo_matrix((K_e[ok], (rows, cols)), shape=(n, n)).tocsr()
    assert abs(bulk.K - ref).max() <= 1e-13 * abs(ref).max()


@settings(max_examples=40, deadline=None)
@given(
    nx=st.integers(1, 5),
    ny=st.integers(1, 5),
    extra=st.integers(0, 6),
    picked=st.integers(0, 6),
    drop=st.floats(0.0, 0.6),
    seed=st.integers(0, 2**31 - 1),
)
def test_generated_entries_sum_like_coo_on_both_backends(
    nx, ny, extra, picked, drop, seed
):
    """Generated grids (cells of any size, 1-row and 1-column meshes),
    enriched cells (none to several, repeated dofs) and dropped candidates:
    both backends give the COO sum of the kept entries, in canonical CSR
    with the grid's pattern kept."""
    rng = np.random.default_rng(seed)
    mesh = _mesh(nx, ny, rng)
    n_std = 2 * mesh.n_nodes
    cells = np.arange(mesh.n_cells)
    K_u = rng.standard_normal((1, 8, 8))
    which = np.zeros(cells.size, np.int64)
    chosen = rng.integers(0, mesh.n_cells, picked)
    cand = n_std + rng.integers(0, max(extra, 1), (picked, 4))
    dofs = np.concatenate([std_cell_dofs(mesh.cells[chosen]), cand], axis=1)
    k = dofs.shape[1]
    rows = np.repeat(dofs, k, axis=1).ravel()
    cols = np.tile(dofs, (1, k)).ravel()
    vals = rng.standard_normal(rows.size)
    kept = rng.random(max(extra, 1)) >= drop
    to_dof = np.concatenate([np.arange(n_std), -np.ones(max(extra, 1), np.int64)])
    to_dof[n_std + np.nonzero(kept)[0]] = n_std + np.arange(np.count_nonzero(kept))
    n = n_std + int(np.count_nonzero(kept))
    r, c = to_dof[rows], to_dof[cols]
    ok = (r >= 0) & (c >= 0)
    ref = _coo_sum(std_cell_dofs(mesh.cells), K_u[which], n_std)
    ref.resize((n, n))
    ref = ref + sp.coo_matrix((vals[ok], (r[ok], c[ok])), shape=(n, n)).tocsr()
    for backend in ("numpy", "numba"):
        grid = grid_stiffness(mesh, cells, K_u, which)
        stored = grid.nnz
        K = add_to_grid(grid, [rows, cols, vals], to_dof, n, backend)
        assert K.shape == (n, n) and K.has_canonical_format
        assert abs(K - ref).max() <= 1e-13 * max(abs(ref).max(), 1.0)
        appended = (r >= n_std) | (c >= n_std)
        pairs = np.unique(r[ok & appended] * n + c[ok & appended])
        assert K.nnz == stored + pairs.size
