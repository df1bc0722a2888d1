"""Bulk stiffness: assembled once per run (linear elasticity does not change
between Newton iterations or load steps; only the contact part does).

Intact cells share one 2x2-Gauss rectangle stiffness per distinct (hx, hy);
enriched cells go through the sub-cell kernel.  The intact cells are summed
straight into the CSR data of the structured grid (grid_stiffness: node (i, j)
couples to its 3 x 3 neighbourhood, so every row's columns are known without
forming and sorting (row, column, value) triplets); the enriched cells'
entries are added to it in place or appended to their rows (add_to_grid),
which keeps the grid's pattern.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from xfemslip import kernels
from xfemslip.fem.enrichment import (
    Candidates,
    DofMap,
    EnrichedCells,
    carries_jump,
    select_enrichment,
)
from xfemslip.kernels.threads import map_kernels

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class BulkSystem:
    K: sp.csr_matrix  # (n_dofs, n_dofs) [N/m]
    dofmap: DofMap
    enr_dofs: np.ndarray  # (nc, 8+2S) int64 global dofs of enriched cells, -1 = none
    enr_Bbar: np.ndarray  # (nc, 3, 8+2S) cell-average strain operator [1/m]
    std_cells: np.ndarray  # (ns,) int64 intact cells
    enriched_cells: np.ndarray  # (nc,) int64, same order as enr_dofs


def std_cell_dofs(cells: np.ndarray) -> np.ndarray:
    """(m, 8) standard dofs 2*node + c of cells (m, 4)."""
    return np.stack([2 * cells, 2 * cells + 1], axis=2).reshape(cells.shape[0], 8)


# local node p of a cell sits at (dx, dy) from its lower-left node
_CELL_OFFSETS = ((0, 0), (1, 0), (1, 1), (0, 1))


def _neighbours_inside(ix, iy, nx, ny) -> np.ndarray:
    """(..., 9) bool: whether neighbour k = 3 (dy + 1) + (dx + 1) of the node
    (ix, iy) (broadcast together) lies inside the (nx + 1) x (ny + 1) grid."""
    d = np.array([-1, 0, 1])
    x = np.asarray(ix)[..., None] + d
    y = np.asarray(iy)[..., None] + d
    in_x, in_y = (x >= 0) & (x <= nx), (y >= 0) & (y <= ny)
    inside = in_y[..., :, None] & in_x[..., None, :]
    return inside.reshape(*inside.shape[:-2], 9)


def grid_stiffness(mesh, cells, K_u, which) -> sp.csr_matrix:
    """The sum of the element matrices K_u[which] (m, 8, 8) of the listed
    cells (m,) as (2 n_nodes, 2 n_nodes) CSR, with canonical (sorted,
    duplicate-free) indices, on the pattern of the whole grid.

    Row 2 i + a of node i = (ix, iy) has the columns 2 j + b of its
    neighbours j = i + dy (nx + 1) + dx, dx, dy in -1..1 inside the grid, in
    increasing order.  The values are summed in planes (9, 2, 2, ny + 1,
    nx + 1): for each pair of local nodes (p, q) and components (a, b), one
    whole-grid slice add; then the planes are read out row by row, without
    the neighbours outside the grid.  About 36 values per node, where
    triplets took 64 (row, column, value) per cell and a sort (1.5 GB and
    2-4 s at 2.0M dofs)."""
    nx, ny = mesh.nx, mesh.ny
    N = mesh.n_nodes
    K_u = np.asarray(K_u, dtype=np.float64)
    which = np.asarray(which, dtype=np.int64)
    listed = np.zeros(mesh.n_cells, bool)
    listed[cells] = True
    listed = listed.reshape(ny, nx)
    uniform = which.size == 0 or bool((which == which[0]).all())
    if not uniform:
        index = np.zeros(mesh.n_cells, dtype=np.int64)
        index[cells] = which
        index = index.reshape(ny, nx)
    weight = listed.astype(np.float64)
    planes = np.zeros((9, 2, 2, ny + 1, nx + 1))
    work = np.empty((ny, nx))
    # each local node pair (p, q) and component pair (a, b): the cells'
    # entries land on node p's row, neighbour k of it (where q sits)
    pairs = [
        (p, q, a, b) for p in range(4) for q in range(4) for a in (0, 1) for b in (0, 1)
    ]
    for p, q, a, b in pairs if which.size else []:
        (px, py), (qx, qy) = _CELL_OFFSETS[p], _CELL_OFFSETS[q]
        k = (qy - py + 1) * 3 + (qx - px + 1)
        if uniform:
            np.multiply(weight, K_u[which[0], 2 * p + a, 2 * q + b], out=work)
        else:
            np.take(K_u[:, 2 * p + a, 2 * q + b], index, out=work)
            work *= weight
        planes[k, a, b, py : py + ny, px : px + nx] += work
    inside = _neighbours_inside(
        np.arange(nx + 1)[None, :], np.arange(ny + 1)[:, None], nx, ny
    )
    keep = np.broadcast_to(inside[:, :, None, :, None], (ny + 1, nx + 1, 2, 9, 2))
    values = planes.transpose(3, 4, 1, 0, 2)[keep]
    del planes
    index_type = np.int32 if 2 * N + 2 < 2**31 and values.size < 2**31 else np.int64
    d = (-1, 0, 1)
    step = np.array([dy * (nx + 1) + dx for dy in d for dx in d], dtype=index_type)
    node = np.arange(N, dtype=index_type).reshape(ny + 1, nx + 1)
    col = 2 * (node[:, :, None, None, None] + step[None, None, None, :, None])
    col = col + np.arange(2, dtype=index_type)
    indices = np.broadcast_to(col, keep.shape)[keep]
    per_row = np.repeat(2 * inside.sum(axis=2, dtype=index_type).reshape(-1), 2)
    indptr = np.zeros(2 * N + 1, dtype=index_type)
    np.cumsum(per_row, out=indptr[1:])
    # entries that sum to exactly zero (on a uniform mesh, u_x of a node with
    # u_y of its neighbour across an edge shared by two cells) stay in the
    # pattern: pyamg's strength of connection (theta = 0) counts them, and
    # without them its aggregates took 14 -> 22 GMRES iterations on the
    # depleting reservoir
    return sp.csr_matrix((values, indices, indptr), shape=(2 * N, 2 * N), copy=False)


def add_to_grid(K_grid, entries, to_dof, n, backend) -> sp.csr_matrix:
    """K_grid (grid_stiffness) plus the entries [rows, cols, vals] (the list
    is emptied: the caller keeps no reference) renumbered by to_dof (an entry
    with a -1 left out), as (n, n) CSR, n >= 2 n_nodes, keeping K_grid's
    pattern (its zeros too; scipy's sum drops them).  K_grid's data are
    added to in place.

    An entry between two standard dofs lies in the grid's pattern (both
    nodes belong to one cell) and is added where it is; the others (a row or
    column of an enriched dof, numbered after the standard ones) are summed
    and appended to their rows after the grid's entries, which keeps every
    row's columns increasing (kernel csr_add_entries of ``backend``)."""
    rows, cols, vals = entries
    entries.clear()
    if vals.size == 0 and n == K_grid.shape[0]:
        return K_grid
    indptr, indices, data, bad = kernels.backend(backend).csr_add_entries(
        K_grid.indptr,
        K_grid.indices,
        K_grid.data,
        rows,
        cols,
        np.ascontiguousarray(vals, dtype=np.float64),
        np.ascontiguousarray(to_dof, dtype=np.int64),
        n,
    )
    if bad >= 0:
        raise ValueError(
            f"an entry between standard dofs outside one cell: "
            f"({to_dof[rows[bad]]}, {to_dof[cols[bad]]})"
        )
    return sp.csr_matrix((data, indices, indptr), shape=(n, n), copy=False)


def _rect_stiffness_shared(hx, hy, D, material, backend):
    """Stiffness (m, 8, 8) computed once per distinct (rectangle size, material).

    D : (3, 3), or (k, 3, 3) with ``material`` (m,) the index of each cell's D
    (None: D[0] everywhere); backend : the model's kernel backend.
    """
    D = np.asarray(D, float).reshape(-1, 3, 3)
    if material is None:
        material = np.zeros(hx.size, np.int64)
    # distinct (hx, hy, material) as one integer code per cell: three 1-D
    # uniques (a structured mesh has few sizes) instead of a row-wise unique
    # of (m, 3), which sorts m rows (1 s at 1M cells)
    hx_u, hx_i = np.unique(np.round(hx, 15), return_inverse=True)
    hy_u, hy_i = np.unique(np.round(hy, 15), return_inverse=True)
    material = np.asarray(material, dtype=np.int64)
    code = (hx_i.ravel() * hy_u.size + hy_i.ravel()) * D.shape[0] + material
    codes, inverse = np.unique(code, return_inverse=True)
    material_u = codes % D.shape[0]
    pair = codes // D.shape[0]
    uniq = np.column_stack(
        [hx_u[pair // hy_u.size], hy_u[pair % hy_u.size], material_u]
    )
    K_u = np.zeros((uniq.shape[0], 8, 8))
    for k in range(D.shape[0]):
        rows = np.nonzero(uniq[:, 2] == k)[0]
        if rows.size:
            K_u[rows] = kernels.backend(backend).rectangle_stiffness(
                np.ascontiguousarray(uniq[rows, 0]),
                np.ascontiguousarray(uniq[rows, 1]),
                np.ascontiguousarray(D[k]),
            )
    return K_u, inverse.ravel()


def _part_matrices(mesh, ec, rows, qp_w, D, backend):
    """K_e, Bbar of the enriched cells ``rows`` (indices into ec.cells or a
    slice of them; None = all) integrated with the weights qp_w (nq,) [m^2]
    in place of ec.qp_w (0 on the QPs left out; every row keeps some
    weight)."""
    if rows is None:
        rows = slice(0, ec.cells.size)
    off, idx, v_off, column_F, column_gradF = ec.part(rows)
    cells, slot_column, slot_node, slot_fnode = (
        ec.cells[rows],
        ec.slot_column[rows],
        ec.slot_node[rows],
        ec.slot_fnode[rows],
    )
    return kernels.backend(backend).enriched_cell_matrices(
        np.ascontiguousarray(mesh.bounds[cells]),
        off,
        np.ascontiguousarray(ec.qp_xy[idx]),
        np.ascontiguousarray(qp_w[idx], dtype=np.float64),
        v_off,
        np.ascontiguousarray(column_F),
        np.ascontiguousarray(column_gradF),
        np.ascontiguousarray(slot_column),
        np.ascontiguousarray(slot_node),
        np.ascontiguousarray(slot_fnode),
        np.ascontiguousarray(D, dtype=np.float64),
    )


def enriched_part_bbar(mesh, ec, rows, qp_w, backend) -> np.ndarray:
    """(len(rows), 3, 8+2S) average strain operator [1/m] of the enriched cells
    ``rows`` over the QPs with weight qp_w > 0 (xfemslip.fem.poro's Biot load)."""
    if len(rows) == 0:
        return np.zeros((0, 3, 8 + 2 * ec.slot_node.shape[1]))
    return _part_matrices(mesh, ec, rows, qp_w, np.eye(3), backend)[1]


def _enriched_matrices(mesh, ec, D, material, qp_material=None, *, backend, rows=None):
    """K_e, Bbar of the enriched cells ``rows`` (indices into ec.cells or a
    slice of them; None: all), each with its own material's D.

    material : (nc,) material index of each enriched cell, or None (D[0]
    everywhere); qp_material : (nq,) material index of each QP (overrides
    ``material``): K_e = K_e(D_0) + sum_k sum_{q in k} B_q^T (D_k - D_0) B_q
    w_q, the second term on the cells holding QPs of material k only.  With
    several materials by cell every material's matrices are computed for all
    the cells and each cell keeps its own (the enriched cells are few).
    """
    D = np.asarray(D, float).reshape(-1, 3, 3)
    if rows is None:
        rows = slice(0, ec.cells.size)
    index = np.arange(ec.cells.size)[rows]  # the rows as indices
    if qp_material is not None:
        K, Bbar = _part_matrices(mesh, ec, rows, ec.qp_w, D[0], backend)
        _, q_idx, *_ = ec.part(rows)
        cell_of_qp = np.repeat(np.arange(index.size), np.diff(ec.qp_offsets)[index])
        for k in range(1, D.shape[0]):
            sub = np.unique(cell_of_qp[qp_material[q_idx] == k])
            if sub.size:
                w = np.where(qp_material == k, ec.qp_w, 0.0)
                K_k = _part_matrices(mesh, ec, index[sub], w, D[k] - D[0], backend)
                K[sub] += K_k[0]
        return K, Bbar
    out = None
    for k in range(D.shape[0]):
        mine = np.ones(index.size, bool) if material is None else material[index] == k
        if not mine.any():
            continue
        K_k, B_k = _part_matrices(mesh, ec, rows, ec.qp_w, D[k], backend)
        if out is None:
            out = (K_k, B_k)
        else:
            out[0][mine] = K_k[mine]
    return out


# Bytes of the padded element matrices ((8 + 2S)^2 doubles a cell) of one call
# of the cell kernel, which are reduced to their diagonal and entries chunk
# by chunk (all at once: 1.1 GB on a 100-fracture network of 13k enriched
# cells with S = 48).  Below the allocator's mmap threshold
# (memory.MMAP_THRESHOLD) a chunk reuses the heap memory of the last one,
# already in the cache, instead of mapping and faulting in fresh pages: the
# network's entries took 1.85-2.03 s in chunks of 2048 cells (177 MB),
# 0.83-1.05 s in chunks of 8 to 46 cells.
ENRICHED_CHUNK_BYTES = 2 << 20


def enriched_chunk(S: int) -> int:
    """Enriched cells per call of the cell kernel with S slots a cell."""
    return max(1, ENRICHED_CHUNK_BYTES // (8 * (8 + 2 * S) ** 2))


def _candidate_dofs(mesh, ec):
    """(nc, 8+2S) dofs of the enriched cells with each slot numbered by its
    candidate, n_std + 2 k + c (-1 for an empty slot): the entries can be
    gathered before the sliver rule has chosen the kept enrichments."""
    n_std = 2 * mesh.n_nodes
    S = ec.slot_cand.shape[1]
    out = -np.ones((ec.cells.size, 8 + 2 * S), np.int64)
    out[:, :8] = std_cell_dofs(mesh.cells[ec.cells])
    k = ec.slot_cand
    out[:, 8::2] = np.where(k >= 0, n_std + 2 * k, -1)
    out[:, 9::2] = np.where(k >= 0, n_std + 2 * k + 1, -1)
    return out


def _enriched_entries(mesh, ec, D, material, qp_material, backend):
    """Chunk by chunk (enriched_chunk cells): the diagonal (nc, 8+2S) and
    Bbar (nc, 3, 8+2S) of the enriched-cell matrices and their entries (rows,
    cols, values) in candidate numbering (_candidate_dofs; int32 where the
    numbers fit), in the order of kernels.block_triplets over all the cells."""
    nc = ec.cells.size
    nd = 8 + 2 * ec.slot_cand.shape[1]
    diag = np.zeros((nc, nd))
    Bbar = np.zeros((nc, 3, nd))
    dofs = _candidate_dofs(mesh, ec)
    live = np.count_nonzero(dofs >= 0, axis=1).astype(np.int64)
    start = np.zeros(nc + 1, np.int64)  # each cell's first entry
    np.cumsum(live**2, out=start[1:])
    total = int(start[-1])
    index_type = np.int32 if dofs.max(initial=0) < 2**31 - 1 else np.int64
    rows = np.empty(total, index_type)
    cols = np.empty(total, index_type)
    vals = np.empty(total)
    chunk = enriched_chunk(ec.slot_cand.shape[1])

    def entries(lo: int) -> int:
        part = slice(lo, min(lo + chunk, nc))
        K_e, Bbar[part] = _enriched_matrices(
            mesh, ec, D, material, qp_material, backend=backend, rows=part
        )
        diag[part] = np.diagonal(K_e, axis1=1, axis2=2)
        r, c, v = _triplets(dofs[part], K_e, backend)
        del K_e
        p = start[lo]
        rows[p : p + r.size] = r
        cols[p : p + r.size] = c
        vals[p : p + r.size] = v
        return r.size

    # with the compiled kernels, the chunks on every core
    p = sum(map_kernels(backend, entries, range(0, nc, chunk)))
    assert p == total
    return diag, Bbar, [rows, cols, vals]


def assemble_bulk(
    mesh,
    D,
    cand: Candidates,
    ec: EnrichedCells,
    ip=None,
    cell_material=None,
    qp_material=None,
    *,
    backend: str,
) -> BulkSystem:
    """Assemble the bulk stiffness and choose the kept enrichments (sliver rule).

    D : (3, 3) [Pa] for one material, or (k, 3, 3) with ``cell_material``
    (n_cells,) int64 the material index of every cell (xfemslip.fem.poro) and,
    optionally, ``qp_material`` (nq,) int64 that of every enriched-cell QP.
    backend : the model's kernel backend ("numba" | "numpy", kernels.choose).
    """
    is_enr = np.zeros(mesh.n_cells, bool)
    is_enr[ec.cells] = True
    std_cells = np.nonzero(~is_enr)[0]
    b = mesh.bounds[std_cells]
    mat_std = None if cell_material is None else cell_material[std_cells]
    K_u, which = _rect_stiffness_shared(
        b[:, 1] - b[:, 0], b[:, 3] - b[:, 2], D, mat_std, backend
    )

    diag_e, Bbar, entries = _enriched_entries(
        mesh,
        ec,
        D,
        None if cell_material is None else cell_material[ec.cells],
        qp_material,
        backend,
    )
    enr_std = std_cell_dofs(mesh.cells[ec.cells])

    n_std = 2 * mesh.n_nodes
    K_grid = grid_stiffness(mesh, std_cells, K_u, which)
    std_diag = K_grid.diagonal()
    np.add.at(std_diag, enr_std, diag_e[:, :8])
    jumps = carries_jump(mesh, cand, ip) if ip is not None else None
    dofmap = select_enrichment(mesh, cand, ec, diag_e, std_diag, jumps)

    S = ec.slot_cand.shape[1]
    enr_dofs = -np.ones((ec.cells.size, 8 + 2 * S), np.int64)
    enr_dofs[:, :8] = enr_std
    for s in range(S):
        k = ec.slot_cand[:, s]
        base = np.where(k >= 0, dofmap.cand_dof[np.maximum(k, 0)], -1)
        enr_dofs[:, 8 + 2 * s] = np.where(base >= 0, base, -1)
        enr_dofs[:, 9 + 2 * s] = np.where(base >= 0, base + 1, -1)

    # the enriched cells' entries on the kept enrichments (candidate numbers
    # to dofs, the dropped candidates' entries left out, the order kept: the
    # entries block_triplets gives on enr_dofs), added to the grid's (rows of
    # the enriched dofs appended, empty); no name here keeps the entries, so
    # add_to_grid frees them once it has summed them
    n = dofmap.n_dofs
    to_dof = np.concatenate(
        [
            np.arange(n_std),
            np.where(
                dofmap.cand_dof[:, None] >= 0,
                dofmap.cand_dof[:, None] + np.arange(2),
                -1,
            ).ravel(),
        ]
    )
    K = add_to_grid(K_grid, entries, to_dof, n, backend)
    logger.info(
        "bulk: %d cells (%d enriched), %d dofs (%d enriched)",
        mesh.n_cells,
        ec.cells.size,
        n,
        n - n_std,
    )
    return BulkSystem(
        K=K,
        dofmap=dofmap,
        enr_dofs=enr_dofs,
        enr_Bbar=Bbar,
        std_cells=std_cells,
        enriched_cells=ec.cells,
    )


def _triplets(dofs, blocks, backend) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rows, columns and values of the entries of per-item blocks (m, k, k)
    whose dofs (m, k) are both >= 0 (kernels.block_triplets)."""
    return kernels.backend(backend).block_triplets(
        np.ascontiguousarray(dofs, dtype=np.int64),
        np.ascontiguousarray(blocks, dtype=np.float64),
    )


def coo_block(
    dofs: np.ndarray, blocks: np.ndarray, n: int, backend: str
) -> sp.csr_matrix:
    """Sum of per-item blocks (m, k, k) on dofs (m, k) (-1 ignored) as CSR (n, n),
    gathered by the kernel ``backend``."""
    r, c, v = _triplets(dofs, blocks, backend)
    return sp.coo_matrix((v, (r, c)), shape=(n, n)).tocsr()


def scatter_vector(dofs: np.ndarray, values: np.ndarray, n: int) -> np.ndarray:
    """Sum of per-item vectors (m, k) on dofs (m, k) (-1 ignored) into (n,)."""
    out = np.zeros(n)
    keep = dofs >= 0
    np.add.at(out, dofs[keep], values[keep])
    return out
