"""Size of a slip event on a fracture: seismic moment, stress drop, magnitude.

- Seismic moment per unit out-of-plane length (2D): M0' = mu int |s| ds
  [N m / m], mu the shear modulus of the rock around the fracture and s the
  slip along it (Aki & Richards 2002, M0 = mu A <s>).
- Moment magnitude for an out-of-plane extent W: M0 = M0' W [N m] and
  Mw = (2/3) (log10 M0 - 9.1) (Hanks & Kanamori 1979, JGR 84(B5), with M0 in
  N m).  The extent is an assumption of the user's (a 2D model has none):
  it is reported next to every magnitude.
- Static stress drop of a crack model: a straight crack of half-length a
  slipping under a uniform stress drop dtau opens the elliptical profile
  s(x) = (kappa + 1) / (2 mu) dtau sqrt(a^2 - x^2) (Westergaard, mode II),
  whose integral is (kappa + 1) pi a^2 dtau / (4 mu); so
  dtau = 4 M0' / ((kappa + 1) pi a^2), with a half the slipping length (the
  2D counterpart of the circular-crack estimate of seismology).
"""

from __future__ import annotations

import math

import numpy as np

from xfemslip.reference.closed_form import kolosov


def shear_modulus(E: float, nu: float) -> float:
    """mu = E / (2 (1 + nu)) [Pa]."""
    return E / (2.0 * (1.0 + nu))


def moment_per_length(mu: float, stretch, slip) -> float:
    """M0' = mu int |s| ds [N m / m]; ``stretch`` (K,) is the length [m] each
    contact point stands for (:func:`xfemslip.post.metrics.point_stretches`)."""
    return mu * float(np.sum(np.asarray(stretch, float) * np.abs(slip)))


def moment_magnitude(moment: float) -> float:
    """Mw of a seismic moment M0 [N m]; -inf for no moment."""
    if moment <= 0.0:
        return -math.inf
    return (2.0 / 3.0) * (math.log10(moment) - 9.1)


def stress_drop(moment_per_len: float, slipping_length: float, mu, nu, model) -> float:
    """Crack-model static stress drop [Pa] (module doc); NaN without slip."""
    if slipping_length <= 0.0 or moment_per_len <= 0.0:
        return math.nan
    a = 0.5 * slipping_length
    return 4.0 * moment_per_len / ((kolosov(nu, model) + 1.0) * math.pi * a * a)
