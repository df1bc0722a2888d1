"""Size of a slip event on a fracture: seismic moment, stress drop, magnitude.

- Seismic moment per unit out-of-plane length (2D): M0' = int mu(s) |d(s)| ds
  [N m / m], mu the shear modulus at each point of the fracture and d the slip
  that slid there (Aki & Richards 2002, M0 = mu A <d>; with mu inside the
  integral a fault between two rocks weighs each stretch with its own).
- Moment magnitude for an out-of-plane extent W: M0 = M0' W [N m] and
  Mw = (2/3) (log10 M0 - 9.1), M0 in N m: the IASPEI standard form (IASPEI
  Working Group on Magnitude Measurements 2013; Bormann, Wendt & Di Giacomo
  2013, NMSOP-2 ch. 3), the constant rounded from Hanks & Kanamori (1979,
  JGR 84(B5)), whose Mw = (2/3) log10 M0 - 10.7 with M0 in dyne cm is
  (2/3) (log10 M0 - 9.05) in N m: 0.033 higher.  The extent is an assumption
  of the user's (a 2D model has none): it is reported next to every
  magnitude.
- Static stress drop of a crack model: a straight crack of half-length a
  slipping under a uniform stress drop dtau opens the elliptical profile
  d(x) = (kappa + 1) / (2 mu) dtau sqrt(a^2 - x^2) (Westergaard, mode II),
  whose integral is (kappa + 1) pi a^2 dtau / (4 mu); so
  dtau = 4 M0' / ((kappa + 1) pi a^2), with a half the slipping length (the
  2D counterpart of the circular-crack estimate of seismology).  With the
  elastic constants varying along the fracture, the same inversion point by
  point: dtau = 4 / (pi a^2) int mu |d| / (kappa + 1) ds.  It is the uniform
  drop that would give the moment, whatever the shear did on the slipping
  points (under depletion it may rise there).
"""

from __future__ import annotations

import math

import numpy as np

from xfemslip.fem.material import shear_modulus
from xfemslip.reference.closed_form import kolosov

__all__ = ["moment_magnitude", "moment_per_length", "shear_modulus", "stress_drop"]


def moment_per_length(mu, stretch, slip) -> float:
    """M0' = int mu |d| ds [N m / m]: ``mu`` [Pa] one value or (K,) per
    contact point, ``stretch`` (K,) the length [m] each contact point stands
    for (:func:`xfemslip.post.metrics.point_stretches`), ``slip`` (K,) the slip
    that slid [m]."""
    weight = np.asarray(mu, float) * np.asarray(stretch, float)
    return float(np.sum(weight * np.abs(slip)))


def moment_magnitude(moment: float) -> float:
    """Mw of a seismic moment M0 [N m] (IASPEI 2013); -inf for no moment."""
    if moment <= 0.0:
        return -math.inf
    return (2.0 / 3.0) * (math.log10(moment) - 9.1)


def stress_drop(mu, nu, model, stretch, slip, slipping_length: float) -> float:
    """Crack-model static stress drop [Pa] (module doc): 4 / (pi a^2) int mu
    |d| / (kappa + 1) ds, a = slipping_length / 2; ``mu`` [Pa] and ``nu``
    one value or (K,) per contact point.  NaN without slipping length or
    slip."""
    if slipping_length <= 0.0:
        return math.nan
    kappa = kolosov(np.asarray(nu, float), model)
    weighted = moment_per_length(np.asarray(mu, float) / (kappa + 1.0), stretch, slip)
    if weighted <= 0.0:
        return math.nan
    a = 0.5 * slipping_length
    return 4.0 * weighted / (math.pi * a * a)
