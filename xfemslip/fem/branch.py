"""Near-tip (branch) enrichment functions of linear elastic fracture mechanics.

In the tip frame (x_l along the outward tip direction d, y_l along
n_d = (-d_y, d_x); r, theta polar, theta in (-pi, pi], the fracture behind the
tip at theta = +/-pi) the four functions spanning the asymptotic crack-tip
displacement field are (Moes, Dolbow & Belytschko 1999; Belytschko & Black 1999)

    B1 = sqrt(r) sin(theta/2)            B2 = sqrt(r) cos(theta/2)
    B3 = sqrt(r) sin(theta/2) sin(theta) B4 = sqrt(r) cos(theta/2) sin(theta)

Only B1 is discontinuous across the fracture: [[B1]] = 2 sqrt(r) (n_d . n),
with n the fracture normal (+ side minus - side), so the modelled slip has the
exact sqrt(r) shape at the tip and ends exactly there.  The functions are
scaled by 1/sqrt(h_tip) (h_tip: size of the tip cell) to be dimensionless and
O(1), which keeps the enriched stiffness comparable with the standard one
(conditioning, and the sliver rule of enrichment.py).
"""

from __future__ import annotations

import numpy as np


def tip_frame(tip, pts, side=None, tol=0.0):
    """Local coordinates (x_l, y_l) and polar (r, theta) of points (n, 2).

    side : optional (n,) +1/-1, the fracture side of each point (the sub-cell
    it belongs to); it decides theta = +/-pi for points lying on the fracture
    behind the tip, where the angle alone is ambiguous.
    """
    d = tip.direction
    nd = np.array([-d[1], d[0]])
    rel = np.atleast_2d(pts) - tip.point
    xl = rel @ d
    yl = rel @ nd
    theta = np.arctan2(yl, xl)
    if side is not None:
        on = (np.abs(yl) <= tol) & (xl < 0.0)
        theta = np.where(on, np.pi * np.asarray(side) * tip.sign, theta)
    r = np.hypot(xl, yl)
    return xl, yl, r, theta


def branch_functions(tip, pts, side=None, tol=0.0):
    """Values (n, 4) and gradients (n, 4, 2) [1/m] of the scaled B1..B4."""
    _, _, r, th = tip_frame(tip, pts, side, tol)
    scale = 1.0 / np.sqrt(tip.cell_size)
    sr = np.sqrt(r)
    s2, c2 = np.sin(th / 2.0), np.cos(th / 2.0)
    # sin, cos of theta and 3 theta / 2 from those of theta / 2
    s1 = 2.0 * s2 * c2
    c1 = (c2 - s2) * (c2 + s2)
    s32 = s1 * c2 + c1 * s2
    c32 = c1 * c2 - s1 * s2
    F = np.empty((r.size, 4))
    F[:, 0] = sr * s2
    F[:, 1] = sr * c2
    F[:, 2] = F[:, 0] * s1
    F[:, 3] = F[:, 1] * s1
    F *= scale
    with np.errstate(divide="ignore", invalid="ignore"):
        k = np.where(r > 0.0, 0.5 * scale / sr, 0.0)
    # derivatives in the local frame (x_l, y_l), turned to (x, y)
    gx = np.stack([-s2, c2, -s32 * s1, -c32 * s1], axis=1)
    gy = np.stack([c2, s2, s2 + s32 * c1, c2 + c32 * c1], axis=1)
    gx *= k[:, None]
    gy *= k[:, None]
    d = tip.direction
    grad = np.empty((r.size, 4, 2))
    grad[:, :, 0] = gx * d[0] - gy * d[1]
    grad[:, :, 1] = gx * d[1] + gy * d[0]
    return F, grad
