"""Bilinear Q4 shape functions on axis-aligned rectangles (structured meshes).

Node order is counter-clockwise from the lower-left corner:
0 (x0, y0), 1 (x1, y0), 2 (x1, y1), 3 (x0, y1).  On a rectangle the
isoparametric map is affine, so N and its gradient are evaluated directly at
physical points: xi = (2x - x0 - x1) / hx, eta = (2y - y0 - y1) / hy.
"""

import numpy as np
from numba import njit

from xfemslip.kernels._config import NUMBA_CACHE

XI_A = np.array([-1.0, 1.0, 1.0, -1.0])
ETA_A = np.array([-1.0, -1.0, 1.0, 1.0])


@njit(cache=NUMBA_CACHE)
def q4_shape(x, y, x0, x1, y0, y1, out_N, out_dN):
    """Shape functions and gradients at the physical point (x, y).

    Parameters
    ----------
    x, y : float [m]; x0, x1, y0, y1 : float, rectangle bounds [m]
    out_N : (4,) float64, written; out_dN : (4, 2) float64 [1/m], written.
    """
    hx = x1 - x0
    hy = y1 - y0
    xi = (2.0 * x - x0 - x1) / hx
    eta = (2.0 * y - y0 - y1) / hy
    for a in range(4):
        xa = XI_A[a]
        ya = ETA_A[a]
        out_N[a] = 0.25 * (1.0 + xi * xa) * (1.0 + eta * ya)
        out_dN[a, 0] = 0.25 * xa * (1.0 + eta * ya) * 2.0 / hx
        out_dN[a, 1] = 0.25 * ya * (1.0 + xi * xa) * 2.0 / hy
