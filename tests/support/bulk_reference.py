"""Point-by-point references of the bulk kernels (NumPy, written from the
formulas, not from the kernels)."""

from __future__ import annotations

import numpy as np

# Natural coordinates of the Q4 corners
XI = np.array([-1.0, 1.0, 1.0, -1.0])
ETA = np.array([-1.0, -1.0, 1.0, 1.0])


def enriched_reference(b, xy, w, F, gradF, slot_node, slot_fnode, D):
    """K (nd, nd) and Bbar (3, nd) of one enriched cell, point by point."""
    S = slot_node.size
    nd = 8 + 2 * S
    K = np.zeros((nd, nd))
    Bsum = np.zeros((3, nd))
    hx, hy = b[1] - b[0], b[3] - b[2]
    for q in range(xy.shape[0]):
        xi = (2.0 * xy[q, 0] - b[0] - b[1]) / hx
        eta = (2.0 * xy[q, 1] - b[2] - b[3]) / hy
        N = 0.25 * (1.0 + xi * XI) * (1.0 + eta * ETA)
        dNx = 0.5 * XI * (1.0 + eta * ETA) / hx
        dNy = 0.5 * ETA * (1.0 + xi * XI) / hy
        gx = np.concatenate([dNx, np.zeros(S)])
        gy = np.concatenate([dNy, np.zeros(S)])
        for s in range(S):
            a = slot_node[s]
            if a < 0:
                continue
            # grad (N_a (F - F_a)) = grad N_a (F - F_a) + N_a grad F
            gx[4 + s] = dNx[a] * (F[q, s] - slot_fnode[s]) + N[a] * gradF[q, s, 0]
            gy[4 + s] = dNy[a] * (F[q, s] - slot_fnode[s]) + N[a] * gradF[q, s, 1]
        B = np.zeros((3, nd))
        B[0, 0::2] = gx
        B[1, 1::2] = gy
        B[2, 0::2] = gy
        B[2, 1::2] = gx
        K += B.T @ D @ B * w[q]
        Bsum += B * w[q]
    return K, Bsum / w.sum()


def compact_slots(offsets, F, gradF, slot_node):
    """The per-column layout of enrichment.EnrichedCells (column_offsets,
    column_F, column_gradF, slot_column) of padded values F (nq, S) and grad
    F (nq, S, 2) of cells whose slots are filled from 0 (slot_node (nc, S),
    -1 = empty), each used slot in a column of its own."""
    slot_node = np.asarray(slot_node)
    used = (slot_node >= 0).sum(axis=1)
    vals, grads, off = [], [], [0]
    for e in range(used.size):
        q = slice(offsets[e], offsets[e + 1])
        vals.append(F[q, : used[e]].T.ravel())
        grads.append(gradF[q, : used[e]].transpose(1, 0, 2).reshape(-1, 2))
        off.append(off[-1] + vals[-1].size)
    slot_column = np.where(slot_node >= 0, np.arange(slot_node.shape[1]), -1)
    return (
        np.array(off, np.int64),
        np.ascontiguousarray(np.concatenate(vals)),
        np.ascontiguousarray(np.concatenate(grads).reshape(-1, 2)),
        np.ascontiguousarray(slot_column, dtype=np.int64),
    )
