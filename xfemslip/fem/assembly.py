"""Bulk stiffness: assembled once per run (linear elasticity does not change
between Newton iterations or load steps; only the contact part does).

Intact cells share one 2x2-Gauss rectangle stiffness per distinct (hx, hy);
enriched cells go through the sub-cell kernel.  Global assembly is COO -> CSR
(duplicates summed by scipy).
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


def _rect_stiffness_shared(hx, hy, D, material, backend):
    """Stiffness (m, 8, 8) computed once per distinct (rectangle size, material).

    D : (3, 3), or (k, 3, 3) with ``material`` (m,) the index of each cell's D
    (None: D[0] everywhere); backend : the model's kernel backend.
    """
    D = np.asarray(D, float).reshape(-1, 3, 3)
    if material is None:
        material = np.zeros(hx.size, np.int64)
    key = np.column_stack([np.round(np.column_stack([hx, hy]), 15), material])
    uniq, inverse = np.unique(key, axis=0, return_inverse=True)
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
    """K_e, Bbar of the enriched cells ``rows`` (indices into ec.cells; None =
    all) integrated with the weights qp_w (nq,) [m^2] in place of ec.qp_w (0
    on the QPs left out; every row keeps some weight)."""
    if rows is None:
        cells, off, idx = ec.cells, ec.qp_offsets, slice(None)
        slot_node, slot_fnode = ec.slot_node, ec.slot_fnode
    else:
        counts = np.diff(ec.qp_offsets)[rows]
        off = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        idx = np.arange(off[-1]) + np.repeat(ec.qp_offsets[rows] - off[:-1], counts)
        cells, slot_node, slot_fnode = (
            ec.cells[rows],
            ec.slot_node[rows],
            ec.slot_fnode[rows],
        )
    return kernels.backend(backend).enriched_cell_matrices(
        np.ascontiguousarray(mesh.bounds[cells]),
        off,
        np.ascontiguousarray(ec.qp_xy[idx]),
        np.ascontiguousarray(qp_w[idx], dtype=np.float64),
        np.ascontiguousarray(ec.qp_F[idx]),
        np.ascontiguousarray(ec.qp_gradF[idx]),
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


def _enriched_matrices(mesh, ec, D, material, qp_material=None, *, backend):
    """K_e, Bbar of the enriched cells, each with its own material's D.

    material : (nc,) material index of each cell, or None (D[0] everywhere);
    qp_material : (nq,) material index of each QP (overrides ``material``):
    K_e = K_e(D_0) + sum_k sum_{q in k} B_q^T (D_k - D_0) B_q w_q, the second
    term on the cells holding QPs of material k only.  With several materials
    by cell every material's matrices are computed for all enriched cells and
    each cell keeps its own (the enriched cells are few).
    """
    D = np.asarray(D, float).reshape(-1, 3, 3)
    if qp_material is not None:
        K, Bbar = _part_matrices(mesh, ec, None, ec.qp_w, D[0], backend)
        cell_of_qp = np.repeat(np.arange(ec.cells.size), np.diff(ec.qp_offsets))
        for k in range(1, D.shape[0]):
            rows = np.unique(cell_of_qp[qp_material == k])
            if rows.size:
                w = np.where(qp_material == k, ec.qp_w, 0.0)
                K[rows] += _part_matrices(mesh, ec, rows, w, D[k] - D[0], backend)[0]
        return K, Bbar
    out = None
    for k in range(D.shape[0]):
        mine = np.ones(ec.cells.size, bool) if material is None else material == k
        if not mine.any():
            continue
        K_k, B_k = _part_matrices(mesh, ec, None, ec.qp_w, D[k], backend)
        if out is None:
            out = (K_k, B_k)
        else:
            out[0][mine] = K_k[mine]
    return out


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
    std_dofs = std_cell_dofs(mesh.cells[std_cells])

    if ec.cells.size:
        K_e, Bbar = _enriched_matrices(
            mesh,
            ec,
            D,
            None if cell_material is None else cell_material[ec.cells],
            qp_material,
            backend=backend,
        )
    else:
        K_e = np.zeros((0, 8, 8))
        Bbar = np.zeros((0, 3, 8))
    enr_std = std_cell_dofs(mesh.cells[ec.cells])

    n_std = 2 * mesh.n_nodes
    std_diag = np.zeros(n_std)
    np.add.at(std_diag, std_dofs, np.diagonal(K_u, axis1=1, axis2=2)[which])
    np.add.at(std_diag, enr_std, np.diagonal(K_e[:, :8, :8], axis1=1, axis2=2))
    jumps = carries_jump(mesh, cand, ip) if ip is not None else None
    dofmap = select_enrichment(mesh, cand, ec, K_e, std_diag, jumps)

    S = ec.slot_cand.shape[1]
    enr_dofs = -np.ones((ec.cells.size, 8 + 2 * S), np.int64)
    enr_dofs[:, :8] = enr_std
    for s in range(S):
        k = ec.slot_cand[:, s]
        base = np.where(k >= 0, dofmap.cand_dof[np.maximum(k, 0)], -1)
        enr_dofs[:, 8 + 2 * s] = np.where(base >= 0, base, -1)
        enr_dofs[:, 9 + 2 * s] = np.where(base >= 0, base + 1, -1)

    # standard cells (every dof >= 0), then the enriched cells' entries
    # without their empty slots (kernels.block_triplets: same order as
    # expanding the padded blocks and masking, so the same CSR to the bit)
    enr_rows, enr_cols, enr_vals = _triplets(enr_dofs, K_e, backend)
    rows = [np.repeat(std_dofs, 8, axis=1).ravel(), enr_rows]
    cols = [np.tile(std_dofs, (1, 8)).ravel(), enr_cols]
    vals = [K_u[which].ravel(), enr_vals]
    rows, cols, vals = (np.concatenate(v) for v in (rows, cols, vals))
    n = dofmap.n_dofs
    K = sp.coo_matrix((vals, (rows, cols)), shape=(n, n)).tocsr()
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


def _triplets(dofs, blocks, backend):
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
