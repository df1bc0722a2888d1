"""Hydraulic aperture of a fracture from its slip and normal stress, the cubic
law, and the equivalent permeability of a block (Oda's crack tensor).

A post-process of the mechanical solution (one-way coupling): the aperture
follows the slip and the effective normal stress of each contact point, and
does not act back on the contact law.  Units SI; stresses tension positive,
so a compressed fracture has sigma_n' < 0.

Aperture at a contact point (m):

    a = a0 + dilation(|s|) - [closure(sigma_n') - closure(sigma_n0')] + max(g_n, 0)

- ``a0`` the hydraulic aperture in the initial (in-situ) state;
- shear dilation with a constant dilation angle psi that stops at a slip
  s_max (Barton, Bandis & Bakhtar 1985, "Strength, deformation and
  conductivity coupling of rock joints", IJRMMS 22(3), the mobilised
  dilation; the capped linear form of Willis-Richards, Watanabe & Takahashi
  1996, JGR 101(B8), eq. 5, without its normal-stress factor):
  dilation = min(|s|, s_max) tan(psi);
- hyperbolic normal closure (Bandis, Lumsden & Barton 1983, "Fundamentals of
  rock joint deformation", IJRMMS 20(6)): closure(sigma') = V_m sigma_c /
  (K_ni V_m + sigma_c) with sigma_c = max(0, -sigma_n') the compression,
  V_m the maximum closure and K_ni the initial normal stiffness; only the
  change from the in-situ state counts;
- the mechanical opening g_n of an open fracture.

The hydraulic aperture is taken equal to the mechanical one (smooth parallel
plates); with V_m <= a0 it stays positive.  Cubic law (Witherspoon et al.
1980, WRR 16(6)): the transmissivity per unit out-of-plane length is
T = a^3 / 12 [m^3], so the flow along the fracture is q = -(T / mu) dp/ds.

Equivalent permeability of a block of area A (Oda 1985, "Permeability tensor
for discontinuous rock masses", Geotechnique 35(4)) in 2D, with Oda's
connectivity factor lambda = 1 (every fracture conducting across the block:
an upper bound; isolated fractures conduct less):

    k_ij = k_m delta_ij + (1 / A) sum_f int_f a^3 / 12 t_i t_j ds   [m^2]

(in 2D, delta_ij - n_i n_j = t_i t_j).  A straight fracture of uniform
aperture a and length L at angle theta gives k_xx = a^3 L cos^2 theta / (12 A).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class ApertureLaw:
    """Hydraulic aperture law of one fracture (module doc)."""

    initial_aperture: float  # a0 [m] > 0
    dilation_angle: float = 0.0  # psi [deg], 0 <= psi < 90
    dilation_slip: float = math.inf  # s_max [m]: slip at which dilation stops
    max_closure: float = 0.0  # V_m [m], 0 <= V_m <= a0 (0: no closure)
    normal_stiffness: float = math.inf  # K_ni [Pa/m] > 0

    def dilation(self, slip) -> np.ndarray:
        """min(|s|, s_max) tan(psi) [m]."""
        s = np.minimum(np.abs(np.asarray(slip, float)), self.dilation_slip)
        return s * math.tan(math.radians(self.dilation_angle))

    def closure(self, sigma_n_eff) -> np.ndarray:
        """V_m sigma_c / (K_ni V_m + sigma_c), sigma_c = max(0, -sigma_n') [m]."""
        sc = np.maximum(0.0, -np.asarray(sigma_n_eff, float))
        if self.max_closure == 0.0:
            return np.zeros_like(sc)
        if math.isinf(self.normal_stiffness):
            return np.zeros_like(sc)
        vm = self.max_closure
        return vm * sc / (self.normal_stiffness * vm + sc)

    def aperture(self, slip, sigma_n_eff, sigma_n0_eff, opening=0.0) -> np.ndarray:
        """Hydraulic aperture [m] at contact points (module doc)."""
        return (
            self.initial_aperture
            + self.dilation(slip)
            - (self.closure(sigma_n_eff) - self.closure(sigma_n0_eff))
            + np.maximum(np.asarray(opening, float), 0.0)
        )


def transmissivity(aperture) -> np.ndarray:
    """Cubic law a^3 / 12 [m^3] (per unit out-of-plane length)."""
    a = np.asarray(aperture, float)
    return a**3 / 12.0


def oda_tensor(fractures, area: float, matrix_permeability: float = 0.0):
    """Equivalent permeability tensor (2, 2) [m^2] of a block (module doc).

    fractures : iterable of (stretches (K,) [m], tangents (K, 2), apertures
    (K,) [m]): the length each contact point stands for
    (:func:`xfemslip.post.metrics.point_stretches`), the unit tangent there,
    and the hydraulic aperture.
    """
    k = matrix_permeability * np.eye(2)
    for w, t, a in fractures:
        t = np.asarray(t, float)
        c = np.asarray(w, float) * transmissivity(a)
        k = k + np.einsum("k,ki,kj->ij", c, t, t) / area
    return 0.5 * (k + k.T)  # symmetric to the last bit (einsum's order is not)
