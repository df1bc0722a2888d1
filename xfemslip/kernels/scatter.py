"""COO triplets of per-cell blocks, without the padding (block_triplets),
and their sum into the grid's CSR matrix (csr_add_entries).

Enriched cells carry up to S slots, most far fewer (networks: S in the tens,
a typical cell a few), so the padded (m, k, k) blocks are mostly dofs -1.
Expanding every (i, j) pair and masking afterwards allocated and copied the
whole padded array three times (rows, columns, values) and concatenated it
with the standard cells (measured: 2.7 of 10 s of the model build of a
30-fracture network with branch tips, 100 x 100 cells).  Here the kept pairs
are counted and written directly, in the same order as the masked expansion
(cell by cell, row-major), so scipy's COO -> CSR sums duplicates in the same
order and the matrix is bitwise the same.
"""

import numpy as np
from numba import njit

from xfemslip.kernels._config import NUMBA_CACHE


@njit(cache=NUMBA_CACHE, nogil=True)
def block_triplets(dofs, blocks):
    """(rows, cols, vals) of every entry (i, j) of blocks (m, k, k) whose dofs
    (m, k) int64 are both >= 0, cell by cell and row-major within a cell."""
    m, k = dofs.shape
    count = 0
    for e in range(m):
        used = 0
        for i in range(k):
            if dofs[e, i] >= 0:
                used += 1
        count += used * used
    rows = np.empty(count, np.int64)
    cols = np.empty(count, np.int64)
    vals = np.empty(count, np.float64)
    p = 0
    for e in range(m):
        for i in range(k):
            r = dofs[e, i]
            if r < 0:
                continue
            for j in range(k):
                c = dofs[e, j]
                if c < 0:
                    continue
                rows[p] = r
                cols[p] = c
                vals[p] = blocks[e, i, j]
                p += 1
    return rows, cols, vals


@njit(cache=NUMBA_CACHE)
def csr_add_entries(indptr, indices, data, rows, cols, vals, to_dof, n):
    """The (n, n) CSR sum of a matrix on the first rows (indptr, indices,
    data: n_std = indptr.size - 1 rows, columns increasing in each row) and
    the entries (rows, cols, vals), renumbered by to_dof (an entry with a -1
    is left out).  An entry whose row and column are both below n_std must
    lie in the matrix's pattern and is added to ``data`` in place; the
    others are summed by (row, column), in the order given, and appended to
    their rows after the matrix's entries (every such column is at least
    n_std or its row is), which keeps each row's columns increasing.

    Returns (indptr, indices, data, bad): the sum (indices of indices' type)
    and -1, or the index of the first entry outside the pattern (then the
    rest is not meaningful)."""
    n_std = indptr.size - 1
    count = np.zeros(n + 1, np.int64)  # appended entries per row, per column
    by_col = np.zeros(n + 1, np.int64)
    for p in range(vals.size):
        r = to_dof[rows[p]]
        c = to_dof[cols[p]]
        if r < 0 or c < 0:
            continue
        if r < n_std and c < n_std:
            lo = indptr[r]
            hi = indptr[r + 1]
            while lo < hi:  # the first column >= c
                mid = (lo + hi) // 2
                if indices[mid] < c:
                    lo = mid + 1
                else:
                    hi = mid
            if lo == indptr[r + 1] or indices[lo] != c:
                return indptr, indices, data, p
            data[lo] += vals[p]
        else:
            count[r + 1] += 1
            by_col[c + 1] += 1
    for r in range(n):
        count[r + 1] += count[r]
    # the appended entries bucketed by column (in the order given), then
    # column by column into their rows: each row's entries come out sorted
    # by column, the duplicates of a (row, column) next to each other in the
    # order given (linear passes: a sort of each row took 0.8 s for the
    # 13M entries of a 100-fracture network)
    for c in range(n):
        by_col[c + 1] += by_col[c]
    col_row = np.empty(by_col[n], np.int32)
    col_val = np.empty(by_col[n])
    fill = by_col[:n].copy()
    for p in range(vals.size):
        r = to_dof[rows[p]]
        c = to_dof[cols[p]]
        if r < 0 or c < 0 or (r < n_std and c < n_std):
            continue
        col_row[fill[c]] = r
        col_val[fill[c]] = vals[p]
        fill[c] += 1
    tail_col = np.empty(count[n], np.int32)
    tail_val = np.empty(count[n])
    fill = count[:n].copy()
    for c in range(n):
        for q in range(by_col[c], by_col[c + 1]):
            r = col_row[q]
            tail_col[fill[r]] = c
            tail_val[fill[r]] = col_val[q]
            fill[r] += 1
    # each row's duplicates summed, written back to the front of its bucket
    unique = np.zeros(n, np.int64)
    for r in range(n):
        lo = count[r]
        hi = count[r + 1]
        if hi == lo:
            continue
        w = lo
        for k in range(lo + 1, hi):
            if tail_col[k] == tail_col[w]:
                tail_val[w] += tail_val[k]
            else:
                w += 1
                tail_col[w] = tail_col[k]
                tail_val[w] = tail_val[k]
        unique[r] = w + 1 - lo
    out_ptr = np.zeros(n + 1, np.int64)
    for r in range(n):
        own = indptr[r + 1] - indptr[r] if r < n_std else 0
        out_ptr[r + 1] = out_ptr[r] + own + unique[r]
    out_idx = np.empty(out_ptr[n], indices.dtype)
    out_val = np.empty(out_ptr[n])
    for r in range(n):
        w = out_ptr[r]
        if r < n_std:
            for q in range(indptr[r], indptr[r + 1]):
                out_idx[w] = indices[q]
                out_val[w] = data[q]
                w += 1
        for q in range(count[r], count[r] + unique[r]):
            out_idx[w] = tail_col[q]
            out_val[w] = tail_val[q]
            w += 1
    return out_ptr.astype(indptr.dtype), out_idx, out_val, -1


@njit(cache=NUMBA_CACHE, nogil=True)
def scatter_column_values(
    F,
    gF,
    Fv,
    Fq,
    gq,
    Fvert,
    col_cell,
    col,
    func,
    group_cell,
    col_off,
    qp_count,
    group_qp,
    tri_off,
    tri_count,
    group_tri,
):
    """The values of one enrichment group, evaluated on the points of the
    cells it reaches, copied to each of its columns (enrichment.
    EnrichedCells): for column ``col[i]`` of cell ``col_cell[i]`` (row
    ``group_cell[i]`` of the group's cells) taking the group's function
    ``func[i]``,

        F[col_off[e] + c nq_e + q] = Fq[group_qp[g] + q, j]   (q < nq_e)
        gF[...] likewise from gq (., ., 2),
        Fv[tri_off[e] + t, :, c] = Fvert[group_tri[g] + t, :, j]   (t < nt_e)

    with e, c, g, j those of column i, nq_e = qp_count[e], nt_e =
    tri_count[e].  F, gF and Fv are written in place."""
    for i in range(col_cell.size):
        e = col_cell[i]
        c = col[i]
        g = group_cell[i]
        j = func[i]
        nq = qp_count[e]
        dst = col_off[e] + c * nq
        src = group_qp[g]
        for q in range(nq):
            F[dst + q] = Fq[src + q, j]
            gF[dst + q, 0] = gq[src + q, j, 0]
            gF[dst + q, 1] = gq[src + q, j, 1]
        dst = tri_off[e]
        src = group_tri[g]
        for t in range(tri_count[e]):
            for v in range(3):
                Fv[dst + t, v, c] = Fvert[src + t, v, j]
