"""The pore-pressure change at which a plane first slips or opens.

One law, used by ``xfemslip screen`` (:mod:`xfemslip.reference.screen`), the
uniaxial-strain closed form (:mod:`xfemslip.reference.closed_form_depletion`)
and the uncertainty screen (:mod:`xfemslip.studies.slip_screen`).

Signs as everywhere in xfemslip: SI, tension positive, dp < 0 a depletion.
Along a stress path the plane's effective normal stress and shear stress
change linearly with the pore-pressure change dp:

    sigma_n'(dp) = A0 + A1 dp,    tau(dp) = B0 + B1 dp.

The contact law of the solver (:mod:`xfemslip.kernels.contact`) keeps a
closed plane stuck while |tau| <= c - f sigma_n' and opens it once
sigma_n' > 0, where it carries no shear at all.  The plane therefore reaches
its limit at the first dp, in the direction of the change, at which one of
three linear functions of dp reaches zero from below:

    opening                 sigma_n'                 >= 0,
    Coulomb, tau > 0        tau + f sigma_n' - c     >= 0,
    Coulomb, tau < 0        -tau + f sigma_n' - c    >= 0.

Their maximum is convex in dp, so the set where the plane is still stuck is
one interval about dp = 0 and the first crossing is the smallest of the
three roots that lie ahead (a function that does not grow in the direction
of the change never crosses).  Edge rules, all from that statement:

- **Already at or beyond the limit** (any of the three >= 0 at dp = 0,
  including a plane in tension or exactly at sigma_n' = 0): dp = 0.
- **Both branches of |tau|**: tau may change sign along the path; the
  branch whose sign tau takes when it reaches the bound is the one found.
- **f = 0**: the bound is the cohesion alone, |tau| = c (no root if tau does
  not change along the path); opening still applies.
- **Cohesion**: the Coulomb line reaches into tension up to sigma_n' = c / f,
  but an open plane carries no shear, so opening at sigma_n' = 0 comes first
  wherever the line crosses in tension.
- **Vertical and horizontal planes** are no special case of the law; their
  coefficients must be exact (:func:`plane_directions` gives exact zeros at
  multiples of 90 degrees, so no 1e-17 rate makes a far root of nothing).
- **Physically possible range**: the pore pressure cannot fall below zero,
  so under depletion only -p0 <= dp <= 0 counts (dp = -p0 included); under
  injection the range is unbounded.  NaN where the plane never reaches its
  limit within the range.

The in-situ Coulomb margin and the slip tendency stay in
:mod:`xfemslip.reference.screen`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

DEPLETION = -1.0
INJECTION = 1.0


class Onset(NamedTuple):
    """The first limit along the path, per plane (arrays of one shape)."""

    change: np.ndarray  # dp [Pa]: 0 at or beyond the limit in situ, NaN never
    opens: np.ndarray  # bool: the limit is opening (sigma_n' = 0), not Coulomb


def plane_directions(theta_deg) -> tuple[np.ndarray, np.ndarray]:
    """(cos theta, sin theta) of planes at theta [deg], exact at multiples of
    90 degrees (cos(pi / 2) is 6e-17 in floating point, not 0)."""
    theta = np.asarray(theta_deg, dtype=float)
    c, s = np.cos(np.radians(theta)), np.sin(np.radians(theta))
    quarter = np.mod(theta, 90.0) == 0.0
    return np.where(quarter, np.round(c), c), np.where(quarter, np.round(s), s)


def plane_tractions(stress, cos_t, sin_t) -> tuple[np.ndarray, np.ndarray]:
    """(sigma_n, tau) [Pa] on planes of tangent t = (cos, sin), normal
    n = (-sin, cos): sigma_n = n.S.n, tau = t.S.n.

    stress : (..., 3) (xx, yy, xy) [Pa], broadcast against cos_t, sin_t.
    """
    S = np.asarray(stress, dtype=float)
    xx, yy, xy = S[..., 0], S[..., 1], S[..., 2]
    c, s = np.asarray(cos_t, dtype=float), np.asarray(sin_t, dtype=float)
    sigma_n = xx * s * s + yy * c * c - 2.0 * xy * s * c
    tau = (yy - xx) * s * c + xy * (c * c - s * s)
    return sigma_n + 0.0, tau + 0.0  # + 0.0: no -0.0 in a printout


def onset(normal, shear, friction, cohesion, direction, initial_pressure) -> Onset:
    """The first pore-pressure change at which planes slip or open.

    normal : (A0 [Pa], A1 [-]) of sigma_n'(dp) = A0 + A1 dp;
    shear : (B0 [Pa], B1 [-]) of tau(dp) = B0 + B1 dp;
    friction f [-] >= 0, cohesion c [Pa] >= 0; direction : DEPLETION (-1) or
    INJECTION (+1); initial_pressure p0 [Pa]: under depletion dp >= -p0
    (not read under injection; None there).  Every array broadcasts to one
    shape; a NaN coefficient gives NaN.  The rules: the module docstring.
    """
    if direction not in (DEPLETION, INJECTION):
        raise ValueError(f"direction must be -1 or +1, got {direction!r}")
    reach = np.inf if direction == INJECTION else initial_pressure
    A0, A1, B0, B1, f, c, reach = np.broadcast_arrays(
        *(
            np.asarray(v, dtype=float)
            for v in (*normal, *shear, friction, cohesion, reach)
        )
    )
    limits = (  # (value at dp = 0, slope in dp) of each limit function
        (A0, A1),
        (B0 + f * A0 - c, B1 + f * A1),
        (-B0 + f * A0 - c, -B1 + f * A1),
    )
    at_start = np.zeros(A0.shape, bool)
    ahead = []  # |dp| to each root that lies in the direction of the change
    for value, slope in limits:
        at_start |= value >= 0.0
        rate = direction * slope
        with np.errstate(divide="ignore", invalid="ignore"):
            ahead.append(np.where((value < 0.0) & (rate > 0.0), -value / rate, np.inf))
    first = np.minimum(ahead[0], np.minimum(ahead[1], ahead[2]))
    reached = np.isfinite(first) & (first <= reach)
    known = ~np.isnan(A0 + A1 + B0 + B1 + f + c + reach)
    change = np.where(at_start, 0.0, np.where(reached, direction * first, np.nan))
    opens = np.where(at_start, A0 >= 0.0, reached & (ahead[0] <= first))
    return Onset(np.where(known, change, np.nan) + 0.0, opens & known)


def critical_change(
    normal, shear, friction, cohesion, direction, initial_pressure
) -> np.ndarray:
    """dp [Pa] of :func:`onset` alone (0 at or beyond the limit, NaN never)."""
    return onset(normal, shear, friction, cohesion, direction, initial_pressure).change
