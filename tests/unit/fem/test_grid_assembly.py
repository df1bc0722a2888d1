"""The structured-grid assembly (assembly.grid_stiffness, add_to_grid)
against the plain sum of element matrices by COO (duplicates summed by
scipy) on graded meshes, per-cell matrices and cells left out."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

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


def test_entries_added_keep_the_pattern_and_sort_the_rows():
    """Standard entries land in place, enriched rows and columns (numbered
    after the standard dofs) are appended to their rows; zeros of the grid
    stay stored."""
    rng = np.random.default_rng(7)
    mesh = _mesh(6, 5, rng)
    cells = np.arange(mesh.n_cells)
    K_u = rng.standard_normal((1, 8, 8))
    K_u[0, 0, 3] = K_u[0, 3, 0] = 0.0
    which = np.zeros(cells.size, np.int64)
    n_std = 2 * mesh.n_nodes
    n = n_std + 12
    # enriched cells: their standard dofs and 4 extra dofs each, repeated
    picked = rng.choice(mesh.n_cells, 5, replace=False)
    extra = n_std + rng.integers(0, 12, (5, 4))
    dofs = np.concatenate([std_cell_dofs(mesh.cells[picked]), extra], axis=1)
    blocks = rng.standard_normal((5, 12, 12))
    rows = np.repeat(dofs, 12, axis=1).ravel()
    cols = np.tile(dofs, (1, 12)).ravel()
    grid = grid_stiffness(mesh, cells, K_u, which)
    stored = grid.nnz
    K = add_to_grid(mesh, grid, rows, cols, blocks.ravel(), n)
    ref = _coo_sum(std_cell_dofs(mesh.cells), K_u[which], n_std)
    ref.resize((n, n))
    ref = ref + sp.coo_matrix((blocks.ravel(), (rows, cols)), shape=(n, n)).tocsr()
    assert K.shape == (n, n) and K.has_canonical_format
    assert abs(K - ref).max() <= 1e-13 * abs(ref).max()
    new_pairs = np.unique(
        rows[(rows >= n_std) | (cols >= n_std)] * n
        + cols[(rows >= n_std) | (cols >= n_std)]
    )
    assert K.nnz == stored + new_pairs.size


def test_bulk_of_a_network_is_the_coo_sum_of_its_cell_matrices(monkeypatch):
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
        monkeypatch.setattr(assembly, "ENRICHED_CHUNK", chunk)
        out[chunk] = assembly.assemble_bulk(mesh, D, cand, ec, ip, backend="numpy")
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
