"""The kernels as NumPy array code: the same functions, signatures and results
(to round-off) as the Numba kernels of bulk.py, contact.py, scatter.py and
subcells.py, without importing Numba.

Why two implementations: a warm ``xfemslip run`` of a small case paid about
0.2 s to import Numba and 0.3 s for its target set-up at the first cached
dispatch (docs/performance.md, *Start-up*), against a few milliseconds of
kernel work on a 50 x 50 mesh; a first run after install paid about 9 s of
compilation.  Every kernel here is a loop over independent cells or points,
which NumPy does as whole-array operations: the intact cells share one
stiffness per distinct size (a handful of rows), the contact law is
elementwise, and the enriched cells are one small matrix product each.  The
backend is chosen per model (``xfemslip.kernels.choose``); these functions are
also the NumPy reference the Numba kernels are tested against (house style,
kernels rule 8).

Formulas and argument conventions: see the Numba kernel of the same name.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from xfemslip.conventions import OPEN, SLIP, STICK, TANGENT_SECANT
from xfemslip.kernels._config import SECANT_MIN_INCREMENT

_XI_A = np.array([-1.0, 1.0, 1.0, -1.0])
_ETA_A = np.array([-1.0, -1.0, 1.0, 1.0])
_GAUSS2 = np.array([-1.0 / np.sqrt(3.0), 1.0 / np.sqrt(3.0)])


def q4_shape(x, y, x0, x1, y0, y1):
    """N (..., 4) and dN (..., 4, 2) [1/m] of Q4 rectangles at points (x, y)
    (arrays of one shape; kernels/shape.py for the node order)."""
    hx = x1 - x0
    hy = y1 - y0
    xi = ((2.0 * x - x0 - x1) / hx)[..., None]
    eta = ((2.0 * y - y0 - y1) / hy)[..., None]
    N = 0.25 * (1.0 + xi * _XI_A) * (1.0 + eta * _ETA_A)
    dN = np.empty(N.shape + (2,))
    dN[..., 0] = 0.25 * _XI_A * (1.0 + eta * _ETA_A) * 2.0 / hx[..., None]
    dN[..., 1] = 0.25 * _ETA_A * (1.0 + xi * _XI_A) * 2.0 / hy[..., None]
    return N, dN


def rectangle_stiffness(hx, hy, D):
    """Stiffness (m, 8, 8) of intact rectangles: Q4 with Wilson's condensed
    incompatible modes, 2x2 Gauss (bulk.rectangle_stiffness)."""
    m = hx.shape[0]
    Kf = np.zeros((m, 12, 12))
    zero = np.zeros(m)
    for gi in range(2):
        for gj in range(2):
            x = 0.5 * hx * (1.0 + _GAUSS2[gi])
            y = 0.5 * hy * (1.0 + _GAUSS2[gj])
            _, dN = q4_shape(x, y, zero, hx, zero, hy)
            B = np.zeros((m, 3, 12))
            B[:, 0, 0:8:2] = dN[..., 0]
            B[:, 1, 1:8:2] = dN[..., 1]
            B[:, 2, 0:8:2] = dN[..., 1]
            B[:, 2, 1:8:2] = dN[..., 0]
            # bubbles: d(1 - xi^2)/dx = -4 xi / hx, d(1 - eta^2)/dy = -4 eta / hy
            p1x = -4.0 * _GAUSS2[gi] / hx
            p2y = -4.0 * _GAUSS2[gj] / hy
            B[:, 0, 8] = p1x  # P1 on ux
            B[:, 2, 9] = p1x  # P1 on uy
            B[:, 2, 10] = p2y  # P2 on ux
            B[:, 1, 11] = p2y  # P2 on uy
            w = 0.25 * hx * hy
            Kf += np.einsum("mki,kl,mlj->mij", B, D, B) * w[:, None, None]
    # static condensation of the four bubble dofs
    Kau = Kf[:, 8:, :8]
    X = np.linalg.solve(Kf[:, 8:, 8:], Kau)
    K = Kf[:, :8, :8] - np.einsum("mai,maj->mij", Kau, X)
    return 0.5 * (K + K.transpose(0, 2, 1))  # exact symmetry


def function_gradients(xy, bounds, slot_node, slot_fnode, F, gradF):
    """d/dx and d/dy (g, n, 4 + S) of the shape functions of g cells at n
    points each: the four Q4 functions N_a, then the shifted enrichment
    Phi_s = N_a (F - F(x_a)) of each slot (paper eq. 11; 0 for an empty
    slot).  xy (g, n, 2) [m]; bounds (g, 4), slot_node (g, S), slot_fnode
    (g, S) of each cell; F (g, n, S), gradF (g, n, S, 2) the slots' values
    at the points (0 in empty slots).  Local dof 2 f + c is function f,
    component c, as in bulk._enriched_B."""
    N, dN = q4_shape(
        xy[..., 0],
        xy[..., 1],
        bounds[:, 0, None],
        bounds[:, 1, None],
        bounds[:, 2, None],
        bounds[:, 3, None],
    )
    # N_a, dN_a/dx, dN_a/dy of each slot's node a: a product with the
    # slots' 0/1 node matrix (g, 4, S), exact, and a third of the time of
    # three gathers
    pick = _one_hot(slot_node, 4)[:, None]
    Na, dxa, dya = np.matmul(np.stack([N, dN[..., 0], dN[..., 1]], 1), pick).transpose(
        1, 0, 2, 3
    )
    shift = F - slot_fnode[:, None, :]
    gx = dxa * shift + Na * gradF[..., 0]
    gy = dya * shift + Na * gradF[..., 1]
    return np.concatenate([dN[..., 0], gx], 2), np.concatenate([dN[..., 1], gy], 2)


def _one_hot(index, n):
    """(g, n, S) with 1 at [i, index[i, s], s] where index >= 0, else 0."""
    g, S = index.shape
    out = np.zeros((g, n, S))
    i, s = np.nonzero(index >= 0)
    out[i, index[i, s], s] = 1.0
    return out


def slot_values(group, count, column_offsets, column_F, column_gradF, slot_column):
    """F (g, count, S) and grad F (g, count, S, 2) of the cells ``group``,
    each with ``count`` points, each slot in its column (0 in empty slots),
    from the per-column layout of enrichment.EnrichedCells: the cells'
    columns gathered, then given to their slots by a product with the 0/1
    column matrix (exact)."""
    col = slot_column[group]  # (g, S)
    C = int(col.max(initial=-1)) + 1  # the most columns of a cell
    # a cell's C first columns; past its own, whatever is stored there (the
    # 0/1 product drops it), within the array
    at = np.minimum(
        column_offsets[group][:, None, None]
        + np.arange(C)[None, None, :] * count
        + np.arange(count)[None, :, None],
        column_F.size - 1,
    )  # (g, count, C)
    values = np.stack(
        [column_F[at], column_gradF[at, 0], column_gradF[at, 1]], 1
    )  # (g, 3, count, C)
    F, gx, gy = np.matmul(values, _one_hot(col, C)[:, None]).transpose(1, 0, 2, 3)
    return F, np.stack([gx, gy], 3)


# the largest batch of enriched_cell_matrices (cells, points): a batch's
# arrays (points x functions) stay in the cache and below the allocator's
# mmap threshold (memory.MMAP_THRESHOLD), so batches reuse the same memory
BATCH_CELLS = 256
BATCH_POINTS = 4096


def enriched_cell_matrices(
    bounds,
    qp_offsets,
    qp_xy,
    qp_w,
    column_offsets,
    column_F,
    column_gradF,
    slot_column,
    slot_node,
    slot_fnode,
    D,
):
    """K (nc, 8 + 2S, 8 + 2S) = sum_qp B^T D B w and Bbar (nc, 3, 8 + 2S) =
    (1/A) sum_qp B w of enriched cells (bulk.enriched_cell_matrices).

    With B's Voigt rows [exx, eyy, gxy] = [bx u_x, by u_y, by u_x + bx u_y]
    (paper eq. 16), each (x|y, x|y) block of K_e is a combination of the four
    gradient products sum_qp w b_f b_g: four small products per cell instead
    of one over the 3 x (8 + 2S) B.  Cells with the same number of points (a
    handful of rules: uncut, cut, tip) are taken together, in batches of at
    most BATCH_CELLS cells and BATCH_POINTS points, each evaluating its own
    functions.
    """
    nc = bounds.shape[0]
    S = slot_node.shape[1]
    nf = 4 + S
    K = np.zeros((nc, 2 * nf, 2 * nf))
    Bbar = np.zeros((nc, 3, 2 * nf))
    counts = np.diff(qp_offsets)
    if nc == 0 or counts.sum() == 0:
        return K, Bbar
    blocks = K.reshape(nc, nf, 2, nf, 2)
    bar = Bbar.reshape(nc, 3, nf, 2)

    def add_batch(group, count):
        """K's blocks and Bbar of the cells ``group``, each with ``count``
        points: sum_q w b_f b_g for the four (x|y, x|y) gradient pairs,
        combined with D, and (1/A) sum_q w b_f."""
        at = qp_offsets[group][:, None] + np.arange(count)  # (g, count)
        bx, by = function_gradients(
            qp_xy[at],
            bounds[group],
            slot_node[group],
            slot_fnode[group],
            *slot_values(
                group, count, column_offsets, column_F, column_gradF, slot_column
            ),
        )  # (g, count, nf)
        w = qp_w[at][..., None]
        wx, wy = bx * w, by * w
        xx = np.matmul(wx.transpose(0, 2, 1), bx)  # (g, nf, nf)
        xy = np.matmul(wx.transpose(0, 2, 1), by)
        yx = np.matmul(wy.transpose(0, 2, 1), bx)
        yy = np.matmul(wy.transpose(0, 2, 1), by)
        blocks[group, :, 0, :, 0] = (
            D[0, 0] * xx + D[0, 2] * xy + D[2, 0] * yx + D[2, 2] * yy
        )
        blocks[group, :, 0, :, 1] = (
            D[0, 1] * xy + D[0, 2] * xx + D[2, 1] * yy + D[2, 2] * yx
        )
        blocks[group, :, 1, :, 0] = (
            D[1, 0] * yx + D[1, 2] * yy + D[2, 0] * xx + D[2, 2] * xy
        )
        blocks[group, :, 1, :, 1] = (
            D[1, 1] * yy + D[1, 2] * yx + D[2, 1] * xy + D[2, 2] * xx
        )
        # sums in point order (reduceat adds in sequence), as the Numba kernel
        starts = np.arange(0, group.size * count, count)
        sx = np.add.reduceat(wx.reshape(-1, nf), starts)  # (g, nf)
        sy = np.add.reduceat(wy.reshape(-1, nf), starts)
        area = np.add.reduceat(w.ravel(), starts)[:, None]
        bar[group, 0, :, 0] = sx / area
        bar[group, 1, :, 1] = sy / area
        bar[group, 2, :, 0] = sy / area
        bar[group, 2, :, 1] = sx / area

    for count in np.unique(counts[counts > 0]):
        same = np.nonzero(counts == count)[0]
        step = max(1, min(BATCH_CELLS, BATCH_POINTS // count))
        for lo in range(0, same.size, step):
            add_batch(same[lo : lo + step], int(count))
    return K, Bbar


def weakened(static, dynamic, accumulated, slip_distance):
    """contact.weakened on arrays: the linearly slip-weakened strength
    parameter, ``static`` itself where the two values are equal."""
    with np.errstate(divide="ignore", invalid="ignore"):
        ramp = static - (static - dynamic) * (accumulated / slip_distance)
    return np.where(
        (static == dynamic) | (accumulated <= 0.0),
        static,
        np.where(accumulated >= slip_distance, dynamic, ramp),
    )


def weakening_rate(static, dynamic, slip_distance):
    """contact.weakening_rate on arrays: (static - dynamic) / slip_distance,
    exactly 0 where the values are equal."""
    with np.errstate(invalid="ignore"):
        return np.where(static == dynamic, 0.0, (static - dynamic) / slip_distance)


def coulomb_return_map(
    gn,
    gt,
    slip_old,
    accumulated_old,
    pn0,
    kn,
    kt,
    friction,
    cohesion,
    friction_dynamic,
    cohesion_dynamic,
    slip_distance,
):
    """The return map of contact.coulomb_return_map on arrays of points:
    (pn, pt, state, slip_new, accumulated_new, d_nn, d_nt, d_tn, d_tt),
    each (n,)."""
    pn = kn * gn + pn0
    is_open = pn > 0.0
    pt_trial = kt * (gt - slip_old)
    f = weakened(friction, friction_dynamic, accumulated_old, slip_distance)
    c = weakened(cohesion, cohesion_dynamic, accumulated_old, slip_distance)
    bound = c - f * pn
    stick = ~is_open & (np.abs(pt_trial) <= bound)
    slip = ~is_open & ~stick
    sgn = np.where(pt_trial > 0.0, 1.0, -1.0)
    trial = np.abs(pt_trial)
    rate_f = weakening_rate(friction, friction_dynamic, slip_distance)
    rate_c = weakening_rate(cohesion, cohesion_dynamic, slip_distance)
    H = rate_c - rate_f * pn  # softening of the bound per unit slip [Pa/m]
    weakens = (
        slip & (accumulated_old < slip_distance) & ((rate_f != 0.0) | (rate_c != 0.0))
    )
    bound_d = cohesion_dynamic - friction_dynamic * pn
    with np.errstate(divide="ignore", invalid="ignore"):  # kt = 0 never slips
        dl = (trial - bound) / (kt - H)
        on_branch = weakens & (kt > H) & (dl <= slip_distance - accumulated_old)
        past = weakens & ~on_branch
        f_new = f - rate_f * dl
        pt_slip = np.where(
            on_branch,
            sgn * (c - rate_c * dl - f_new * pn),
            np.where(past, sgn * bound_d, sgn * bound),
        )
        pt = np.where(slip, pt_slip, pt_trial)
        slip_new = np.where(is_open, gt, np.where(stick, slip_old, gt - pt / kt))
        acc_new = np.where(
            on_branch,
            accumulated_old + dl,
            np.where(
                past,
                accumulated_old + (trial - bound_d) / kt,
                np.where(slip, accumulated_old + (trial - bound) / kt, accumulated_old),
            ),
        )
        scale = kt / (kt - H)
    state = np.where(is_open, OPEN, np.where(stick, STICK, SLIP)).astype(np.int8)
    pn = np.where(is_open, 0.0, pn)
    pt = np.where(is_open, 0.0, pt)
    d_nn = np.where(is_open, 0.0, kn)
    d_nt = np.zeros_like(pn)
    d_tn = np.where(
        on_branch,
        -sgn * f_new * kn * scale,
        np.where(
            past,
            -sgn * friction_dynamic * kn,
            np.where(slip, -sgn * f * kn, 0.0),
        ),
    )
    d_tt = np.where(stick, kt, np.where(on_branch, -H * scale, 0.0))
    return pn, pt, state, slip_new, acc_new, d_nn, d_nt, d_tn, d_tt


def contact_response(
    u,
    ip_dofs,
    ip_coef,
    ip_normal,
    ip_tangent,
    ip_weight,
    pn0,
    slip_old,
    accumulated_old,
    kn,
    kt,
    friction,
    cohesion,
    friction_dynamic,
    cohesion_dynamic,
    slip_distance,
    tangent_mode,
    pt_prev,
    gt_prev,
    out_f,
    out_K,
    out_gn,
    out_gt,
    out_pn,
    out_pt,
    out_state,
    out_slip,
    out_accumulated,
):
    """Contact forces and tangent of every interface point
    (contact.contact_response)."""
    n0, n1 = ip_normal[:, 0], ip_normal[:, 1]
    t0, t1 = ip_tangent[:, 0], ip_tangent[:, 1]
    dx, dy = ip_dofs[:, 0::2], ip_dofs[:, 1::2]
    ux = np.where(dx >= 0, u[np.maximum(dx, 0)], 0.0)
    uy = np.where(dy >= 0, u[np.maximum(dy, 0)], 0.0)
    j0 = (ip_coef * ux).sum(axis=1)  # paper eq. 14
    j1 = (ip_coef * uy).sum(axis=1)
    gn = j0 * n0 + j1 * n1
    gt = j0 * t0 + j1 * t1
    pn, pt, state, slip, acc, dnn, dnt, dtn, dtt = coulomb_return_map(
        gn,
        gt,
        slip_old,
        accumulated_old,
        pn0,
        kn,
        kt,
        friction,
        cohesion,
        friction_dynamic,
        cohesion_dynamic,
        slip_distance,
    )
    if tangent_mode == TANGENT_SECANT:  # paper eq. 28, no n-t coupling
        dg = np.abs(gt - gt_prev)
        with np.errstate(divide="ignore", invalid="ignore"):
            sec = np.where(dg <= SECANT_MIN_INCREMENT, kt, np.abs(pt - pt_prev) / dg)
        # a point on a weakening branch keeps its consistent tangent
        sliding = (state == SLIP) & (dtt == 0.0)
        dtt = np.where(sliding, np.minimum(sec, kt), dtt)
        dtn = np.where(sliding, 0.0, dtn)
    out_gn[:] = gn
    out_gt[:] = gt
    out_pn[:] = pn
    out_pt[:] = pt
    out_state[:] = state
    out_slip[:] = slip
    out_accumulated[:] = acc
    T = np.column_stack([pn * n0 + pt * t0, pn * n1 + pt * t1])
    # C = n (dnn n + dnt t)^T + t (dtn n + dtt t)^T
    a = dnn[:, None] * ip_normal + dnt[:, None] * ip_tangent
    b = dtn[:, None] * ip_normal + dtt[:, None] * ip_tangent
    C = ip_normal[:, :, None] * a[:, None, :] + ip_tangent[:, :, None] * b[:, None, :]
    ck = ip_weight[:, None] * ip_coef  # (n, J)
    J = ip_coef.shape[1]
    n = ip_coef.shape[0]
    out_f[:] = (ck[:, :, None] * T[:, None, :]).reshape(n, 2 * J)
    ckm = ck[:, :, None] * ip_coef[:, None, :]  # (n, J, J)
    out_K[:] = (ckm[:, :, None, :, None] * C[:, None, :, None, :]).reshape(
        n, 2 * J, 2 * J
    )


def block_triplets(dofs, blocks):
    """(rows, cols, vals) of the entries of blocks (m, k, k) whose dofs (m, k)
    are both >= 0, cell by cell and row-major (scatter.block_triplets: the
    same arrays, to the bit)."""
    keep = dofs >= 0
    pair = keep[:, :, None] & keep[:, None, :]
    k = dofs.shape[1]
    rows = np.broadcast_to(dofs[:, :, None], (dofs.shape[0], k, k))[pair]
    cols = np.broadcast_to(dofs[:, None, :], (dofs.shape[0], k, k))[pair]
    return rows.astype(np.int64), cols.astype(np.int64), blocks[pair]


def csr_add_entries(indptr, indices, data, rows, cols, vals, to_dof, n):
    """scatter.csr_add_entries: the (n, n) CSR sum of the matrix (indptr,
    indices, data) on the first rows and the entries renumbered by to_dof,
    as (indptr, indices, data, bad) (the same matrix, each sum to round-off:
    SciPy sums the appended duplicates in an order of its own)."""
    n_std = indptr.size - 1
    r, c = to_dof[rows], to_dof[cols]
    keep = (r >= 0) & (c >= 0)
    r, c, vals = r[keep], c[keep], vals[keep]
    std = (r < n_std) & (c < n_std)
    # each entry on the first rows found among its row's columns (at most
    # a few tens: one pass per place in the row)
    rs, cs = r[std], c[std]
    start = indptr[rs].astype(np.int64)
    length = indptr[rs + 1] - start
    pos = np.full(rs.size, -1, np.int64)
    last = max(indices.size - 1, 0)
    for k in range(int(length.max(initial=0))):
        hit = (k < length) & (indices[np.minimum(start + k, last)] == cs)
        pos[hit] = start[hit] + k
    if np.any(pos < 0):  # the first entry outside the pattern, as given
        given = np.nonzero(keep)[0][std]
        return indptr, indices, data, int(given[np.argmax(pos < 0)])
    if pos.size > data.size // 16:  # many entries: one pass
        data += np.bincount(pos, weights=vals[std], minlength=data.size)
    else:
        np.add.at(data, pos, vals[std])
    tail = sp.coo_matrix((vals[~std], (r[~std], c[~std])), shape=(n, n)).tocsr()
    tail.sum_duplicates()
    del r, c, vals, std, rs, cs, start, length, pos
    grid_ptr = np.full(n + 1, indptr[-1], dtype=np.int64)
    grid_ptr[: n_std + 1] = indptr
    # the tail's entries of row r go after the matrix's, at grid_ptr[r + 1]:
    # the matrix's arrays are copied run by run between those points, one
    # run per distinct point (the rows past n_std all at the end); np.insert
    # took twice as long: it indexes every entry
    ends = np.cumsum(np.diff(tail.indptr))
    row_points = grid_ptr[1:]
    distinct = np.nonzero(np.r_[row_points[1:] != row_points[:-1], True])[0]
    counts = np.diff(np.r_[0, ends[distinct]])
    points = row_points[distinct]
    counts, points = counts[counts > 0], points[counts > 0]
    out_ptr = (grid_ptr + tail.indptr).astype(indptr.dtype)
    out_val = np.empty(int(out_ptr[-1]))
    out_idx = np.empty(int(out_ptr[-1]), dtype=indices.dtype)
    src = dst = t = 0
    for point, count in zip(points.tolist(), counts.tolist(), strict=True):
        run = point - src
        out_val[dst : dst + run] = data[src:point]
        out_idx[dst : dst + run] = indices[src:point]
        dst += run
        out_val[dst : dst + count] = tail.data[t : t + count]
        out_idx[dst : dst + count] = tail.indices[t : t + count]
        dst, src, t = dst + count, point, t + count
    out_val[dst:] = data[src:]
    out_idx[dst:] = indices[src:]
    return out_ptr, out_idx, out_val, -1


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
    """scatter.scatter_column_values: one enrichment group's values copied to
    its columns (F, gF, Fv written in place, the same values)."""
    nq_c = qp_count[col_cell]
    rows_v = ranges(col_off[col_cell] + col * nq_c, nq_c)
    rows_g = ranges(group_qp[group_cell], nq_c)
    # one flat index into the group's (points, functions) arrays
    flat = rows_g * Fq.shape[1] + np.repeat(func, nq_c)
    F[rows_v] = Fq.ravel()[flat]
    # the (x, y) pairs moved as one complex number each: a fancy index over
    # the rows of an (n, 2) array took three times as long
    gF_pairs = gF.view(np.complex128)[:, 0]
    gF_pairs[rows_v] = np.ascontiguousarray(gq).view(np.complex128).ravel()[flat]
    nt_c = tri_count[col_cell]
    rows_t = ranges(tri_off[col_cell], nt_c)
    rows_gt = ranges(group_tri[group_cell], nt_c)
    Fv[rows_t, :, np.repeat(col, nt_c)] = Fvert[rows_gt, :, np.repeat(func, nt_c)]


def ranges(starts, counts):
    """Concatenation of arange(s, s + n) for each (s, n), int64."""
    starts = np.asarray(starts, np.int64)
    counts = np.asarray(counts, np.int64)
    total = int(counts.sum())
    if total == 0:
        return np.zeros(0, np.int64)
    first = np.cumsum(counts) - counts
    return np.repeat(starts - first, counts) + np.arange(total, dtype=np.int64)


# ----------------------------------------------------------- sub-cells
def split_polygon(poly: np.ndarray, point: np.ndarray, normal: np.ndarray, tol: float):
    """Split a convex polygon (k, 2) by a line; returns a list of 1 or 2 polygons.

    Vertices within tol of the line count as on it, so a line through a vertex
    or along an edge never makes a sliver.
    """
    # the two products written out, as in the Numba kernel (bit for bit)
    d = (poly[:, 0] - point[0]) * normal[0] + (poly[:, 1] - point[1]) * normal[1]
    d[np.abs(d) <= tol] = 0.0
    if np.all(d >= 0.0) or np.all(d <= 0.0):
        return [poly]
    pos, neg = [], []
    k = poly.shape[0]
    for i in range(k):
        p, q = poly[i], poly[(i + 1) % k]
        dp, dq = d[i], d[(i + 1) % k]
        if dp >= 0.0:
            pos.append(p)
        if dp <= 0.0:
            neg.append(p)
        if dp * dq < 0.0:
            x = p + dp / (dp - dq) * (q - p)
            pos.append(x)
            neg.append(x)
    # a line within tol of a corner can leave a degenerate piece (3 coincident
    # points): keep only pieces with area
    pieces = [np.array(v) for v in (pos, neg) if len(v) >= 3]
    pieces = [v for v in pieces if polygon_area(v) > tol * tol]
    return pieces or [poly]


def polygon_area(poly: np.ndarray) -> float:
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def fan_triangles(poly: np.ndarray, min_area: float) -> np.ndarray:
    """Triangles (t, 3, 2) of a convex polygon, dropping degenerate ones."""
    tris = np.array(
        [[poly[0], poly[i], poly[i + 1]] for i in range(1, poly.shape[0] - 1)]
    )
    if tris.size == 0:
        return np.zeros((0, 3, 2))
    e1 = tris[:, 1] - tris[:, 0]
    e2 = tris[:, 2] - tris[:, 0]
    area = 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    return tris[area > min_area]


def cell_subtriangles(
    bounds, line_offsets, line_point, line_normal, apex_offsets, apex_xy, tol
):
    """Sub-triangles of rectangles cut along their lines
    (subcells.cell_subtriangles): (tri_offsets (nc + 1,), tris (nt, 3, 2))."""
    nc = bounds.shape[0]
    out = []
    offsets = np.zeros(nc + 1, np.int64)
    min_area = (tol * tol) * 1e-3
    for e in range(nc):
        x0, x1, y0, y1 = bounds[e]
        polys = [np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])]
        for li in range(line_offsets[e], line_offsets[e + 1]):
            point, normal = line_point[li], line_normal[li]
            polys = [
                piece
                for poly in polys
                for piece in split_polygon(poly, point, normal, tol)
            ]
        apexes = apex_xy[apex_offsets[e] : apex_offsets[e + 1]]
        for i, poly in enumerate(polys):
            for apex in apexes:
                dist = np.linalg.norm(poly - apex, axis=1)
                j = int(np.argmin(dist))
                if dist[j] <= tol:
                    polys[i] = np.roll(poly, -j, axis=0)
                    break
        tris = [fan_triangles(p, min_area) for p in polys]
        out.extend(tris)
        offsets[e + 1] = offsets[e] + sum(t.shape[0] for t in tris)
    tris = np.concatenate(out, axis=0) if out else np.zeros((0, 3, 2))
    return offsets, tris
