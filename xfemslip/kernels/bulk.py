"""Bulk element matrices: intact rectangles and enriched (cut / blending) cells.

Intact rectangles are Q4 with condensed incompatible modes (rectangle_stiffness);
enriched cells are plain Q4 plus their enrichment slots.

Local dof order of a cell: standard ``2*a + c`` (a = 0..3 local node, c = 0 x,
1 y), then enriched slot s: ``8 + 2*s + c``.  A slot is one (node, fracture)
enrichment with the shifted function (paper eq. 11)

    Phi_s(x) = N_a(x) * (F(x) - F(x_a)),   F = H(phi) * R,

H = +/-1 the side of the fracture and R the tip ramp (see enrichment.py), so
grad Phi_s = grad N_a * (F - F_a) + N_a * grad F.  Strain B (3 x ndof) uses the
Voigt order [exx, eyy, gxy] (paper eq. 16); K_e = sum_qp B^T D B w (eq. 22).
"""

import numpy as np
from numba import njit

from xfemslip.kernels._config import NUMBA_CACHE
from xfemslip.kernels.shape import q4_shape

_GAUSS2 = np.array([-1.0 / np.sqrt(3.0), 1.0 / np.sqrt(3.0)])


@njit(cache=NUMBA_CACHE)
def rectangle_stiffness(hx, hy, D):
    """Stiffness of intact rectangles: Q4 with Wilson's incompatible modes.

    The bilinear field is enriched inside each cell with the two bubble modes
    P1 = 1 - xi^2, P2 = 1 - eta^2 per displacement component (Wilson, Taylor,
    Doherty & Ghaboussi 1973; Taylor, Beresford & Wilson 1976, QM6), which are
    condensed out, so the cell keeps its 8 nodal dofs.  On a rectangle the
    derivatives of P1, P2 integrate to zero over the cell: a uniform strain
    leaves the bubbles at rest (patch test), the cell-average strain is that
    of the nodal field alone, and the cell is exact in pure bending, where the
    plain Q4 is too stiff by parasitic shear.  That stiffness grows with
    (cell length / length scale of the field)^2, which is what the coarse,
    elongated cells of a graded far field see; it made the slip of a crack
    converge to a floor (docs/performance.md, "Slip convergence on the
    OpenGeoSys peer problem").  Enriched cells stay plain Q4 (the bubbles are
    internal to each cell, so the two kinds of cells are conforming).
    2x2 Gauss is exact for every term (at most quadratic in xi or eta).

    Parameters
    ----------
    hx, hy : (m,) float64, rectangle sizes [m]
    D : (3, 3) float64, elasticity matrix [Pa] (eqs. 24-25)

    Returns
    -------
    K : (m, 8, 8) float64 [N/m per unit thickness]
    """
    m = hx.shape[0]
    K = np.zeros((m, 8, 8))
    N = np.empty(4)
    dN = np.empty((4, 2))
    B = np.zeros((3, 12))
    Kf = np.zeros((12, 12))
    for e in range(m):
        Kf[:, :] = 0.0
        for gi in range(2):
            for gj in range(2):
                x = 0.5 * hx[e] * (1.0 + _GAUSS2[gi])
                y = 0.5 * hy[e] * (1.0 + _GAUSS2[gj])
                q4_shape(x, y, 0.0, hx[e], 0.0, hy[e], N, dN)
                B[:, :] = 0.0
                for a in range(4):
                    B[0, 2 * a] = dN[a, 0]
                    B[1, 2 * a + 1] = dN[a, 1]
                    B[2, 2 * a] = dN[a, 1]
                    B[2, 2 * a + 1] = dN[a, 0]
                # bubbles: d(1 - xi^2)/dx = -4 xi / hx, d(1 - eta^2)/dy = -4 eta / hy
                p1x = -4.0 * _GAUSS2[gi] / hx[e]
                p2y = -4.0 * _GAUSS2[gj] / hy[e]
                B[0, 8] = p1x  # P1 on ux
                B[2, 9] = p1x  # P1 on uy
                B[1, 11] = p2y  # P2 on uy
                B[2, 10] = p2y  # P2 on ux
                w = 0.25 * hx[e] * hy[e]
                Kf += (B.T @ D @ B) * w
        # static condensation of the four bubble dofs
        Kaa = np.ascontiguousarray(Kf[8:, 8:])
        Kau = np.ascontiguousarray(Kf[8:, :8])
        X = np.linalg.solve(Kaa, Kau)
        K[e] = Kf[:8, :8] - Kau.T @ X
        for i in range(8):  # exact symmetry (the solve leaves round-off)
            for j in range(i + 1, 8):
                v = 0.5 * (K[e, i, j] + K[e, j, i])
                K[e, i, j] = v
                K[e, j, i] = v
    return K


@njit(cache=NUMBA_CACHE)
def _gram_to_stiffness(G, nf, D, K):
    """K (2 nf, 2 nf) of functions whose strain columns are (g_x, 0, g_y) and
    (0, g_y, g_x), from the weighted Gram matrix G of [g_x | g_y] (2 nf, 2 nf):
    each 2 x 2 block is a combination of XX, XY, YX, YY with D's entries
    (a third of the products of sum_qp B^T D B w)."""
    for i in range(nf):
        for j in range(nf):
            XX = G[i, j]
            XY = G[i, nf + j]
            YX = G[nf + i, j]
            YY = G[nf + i, nf + j]
            K[2 * i, 2 * j] = D[0, 0] * XX + D[0, 2] * XY + D[2, 0] * YX + D[2, 2] * YY
            K[2 * i, 2 * j + 1] = (
                D[0, 1] * XY + D[0, 2] * XX + D[2, 1] * YY + D[2, 2] * YX
            )
            K[2 * i + 1, 2 * j] = (
                D[1, 0] * YX + D[1, 2] * YY + D[2, 0] * XX + D[2, 2] * XY
            )
            K[2 * i + 1, 2 * j + 1] = (
                D[1, 1] * YY + D[1, 2] * YX + D[2, 1] * XY + D[2, 2] * XX
            )


@njit(cache=NUMBA_CACHE, nogil=True)
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
    """Stiffness and area-averaged strain operator of enriched cells.

    Parameters
    ----------
    bounds : (nc, 4) float64, [x0, x1, y0, y1] of each cell [m]
    qp_offsets : (nc + 1,) int64, qp range of each cell in the flat arrays
    qp_xy : (nq, 2) float64 [m]; qp_w : (nq,) float64 [m^2] (sub-cell rules)
    column_offsets : (nc + 1,) int64; column_F : (nv,) float64 [-];
        column_gradF : (nv, 2) float64 [1/m]: the enrichment functions of
        each cell at its points, column c of cell e at point q at
        column_offsets[e] + c * nq_e + (q - qp_offsets[e])
        (enrichment.EnrichedCells)
    slot_column : (nc, S) int64, the column of each slot's function, -1 =
        empty
    slot_node : (nc, S) int64, local node (0..3) of each slot, -1 = empty
        (slots are filled from 0)
    slot_fnode : (nc, S) float64, F at the slot's node (the shift of eq. 11)
    D : (3, 3) float64 [Pa]

    Returns
    -------
    K : (nc, 8 + 2S, 8 + 2S) float64, sum_qp B^T D B w
    Bbar : (nc, 3, 8 + 2S) float64, (1/A) sum_qp B w (cell-average strain)
    """
    nc = bounds.shape[0]
    S = slot_node.shape[1]
    nd = 8 + 2 * S
    K = np.zeros((nc, nd, nd))
    Bbar = np.zeros((nc, 3, nd))
    N = np.empty(4)
    dN = np.empty((4, 2))
    for e in range(nc):
        x0, x1, y0, y1 = bounds[e, 0], bounds[e, 1], bounds[e, 2], bounds[e, 3]
        q0 = qp_offsets[e]
        nq = qp_offsets[e + 1] - q0
        # functions in use: the four nodes' and the slots up to the last
        # occupied one (slots are filled from 0; networks pad most cells far
        # below S)
        n_used = 0
        for s in range(S):
            if slot_node[e, s] >= 0:
                n_used = s + 1
        nf = 4 + n_used
        # G_x | G_y: the gradient of every scalar function at every point
        P = np.empty((nq, 2 * nf))
        Pw = np.empty((nq, 2 * nf))
        area = 0.0
        for k in range(nq):
            q = q0 + k
            q4_shape(qp_xy[q, 0], qp_xy[q, 1], x0, x1, y0, y1, N, dN)
            for a in range(4):
                P[k, a] = dN[a, 0]
                P[k, nf + a] = dN[a, 1]
            for s in range(n_used):
                a = slot_node[e, s]
                if a < 0:
                    P[k, 4 + s] = 0.0
                    P[k, nf + 4 + s] = 0.0
                    continue
                v = column_offsets[e] + slot_column[e, s] * nq + k
                shift = column_F[v] - slot_fnode[e, s]
                P[k, 4 + s] = dN[a, 0] * shift + N[a] * column_gradF[v, 0]
                P[k, nf + 4 + s] = dN[a, 1] * shift + N[a] * column_gradF[v, 1]
            w = qp_w[q]
            for i in range(2 * nf):
                Pw[k, i] = w * P[k, i]
            area += w
        G = np.dot(P.T, Pw)
        _gram_to_stiffness(G, nf, D, K[e])
        for i in range(nf):
            sx = 0.0
            sy = 0.0
            for k in range(nq):
                sx += Pw[k, i]
                sy += Pw[k, nf + i]
            Bbar[e, 0, 2 * i] = sx / area
            Bbar[e, 1, 2 * i + 1] = sy / area
            Bbar[e, 2, 2 * i] = sy / area
            Bbar[e, 2, 2 * i + 1] = sx / area
    return K, Bbar
