"""Closed forms for depletion: uniaxial strain and the offset-reservoir fault.

Signs: tension positive, dp < 0 = depletion, alpha the Biot coefficient,
plane strain, homogeneous isotropic elasticity (shear modulus mu, Poisson nu).

1. Uniaxial strain (laterally infinite layer, constant overburden):
   Delta sigma_xx = -alpha dp (1 - 2 nu) / (1 - nu), Delta sigma_yy = 0,
   Delta sigma'_yy = alpha dp, Delta sigma'_xx = nu / (1 - nu) alpha dp
   (derivation in xfemslip.fem.poro).

2. Vertical fault x = 0 through a reservoir offset across it (Jansen,
   Singhal & Vossepoel 2019, Jansen & Meulenbroek 2022, "Induced aseismic slip
   and the onset of seismicity in displaced faults", Neth. J. Geosci. 101; the
   set-up of GEOS's "stableVerticalFault" / "slippedVerticalFault"): the
   reservoir is a < y < b left of the fault (x < 0) and c < y < d right of it
   (x > 0), both extending to infinity sideways, in an infinite homogeneous
   plane; the pressure changes by dp in the reservoir only.

   Stuck fault (no slip, it is not there mechanically).  Goodier's
   displacement potential u = grad psi with (lambda + 2 mu) lap psi =
   alpha dp chi_reservoir solves the Navier equations with the Biot body
   force, so psi = alpha dp / (lambda + 2 mu) * (1 / 2 pi) int_A ln r dA and
   sigma_xy = 2 mu d2psi/dxdy (xfemslip.reference.inclusion: the whole stress
   of any polygon).  For a rectangle, d2/dxdy int int ln r dA is a
   signed sum of ln r over its four corners; on x = 0 the corners at
   infinity drop out and

       sigma_xy(0, y) = C ln( |y - b| |y - c| / (|y - a| |y - d|) ),
       C = alpha dp (1 - 2 nu) / (2 pi (1 - nu))                     (J1)

   log-singular at the four reservoir corners.  The same potential gives the
   uniaxial-strain state of 1 inside a laterally infinite layer (check).

   Frictionless fault.  The slip delta(y) = u_y(x = 0-) - u_y(x = 0+)
   (left minus right) cancels (J1) on the whole line.  With the shear stress
   of a continuous distribution of glide dislocations,
   sigma_xy^slip(y) = -mu / (2 pi (1 - nu)) PV int delta'(s) / (s - y) ds
   (constant and sign fixed by the Griffith shear crack: under a remote
   sigma_xy = S > 0 the right side moves up, delta = -2 (1 - nu) S / mu
   sqrt(a^2 - y^2), and its stress is -S on the crack), and the Hilbert pair
   PV int sgn(s - k) / (y - s) ds = 2 ln|y - k| + const, the solution is
   piecewise linear:

       delta(y) = -alpha dp (1 - 2 nu) / (2 mu)
                  * (|y - b| + |y - c| - |y - a| - |y - d|)              (J2)

   compact (zero outside [min, max] of a, b, c, d) when both sides have the
   same thickness, b - a = d - c.  Under depletion in the throw's overlap
   (c < y < b for a < c < b < d) |delta| = alpha |dp| (1 - 2 nu) (c - a) / mu,
   and the side whose reservoir lies lower moves down relative to the other
   (delta < 0 there when the left reservoir is the lower one).
   (J1) and (J2) were derived here independently; they agree to round-off
   with the analytical solution GEOS's validations use (GEOS-DEV/GEOS,
   .../faultMechanics/slippedVerticalFault/generate_analytical.py; Frigo,
   Castelletto, Cusini et al., J. Comput. Phys. 2026, Sec. 5.1.2, eqs.
   48-51, for equal thickness b - a = d - c): tested in
   tests/unit/reference/test_closed_form_depletion.py.
   The released elastic energy -1/2 int sigma_xy delta dy is positive
   (checked in tests/unit/reference/test_closed_form_depletion.py with a numerical
   Cauchy principal value of the slip's stress).  The fault must stay closed
   (compressive effective normal stress), which the in-situ stress provides.
"""

from __future__ import annotations

import numpy as np

from xfemslip.geometry.box import Box
from xfemslip.reference.inclusion import polygon_stress
from xfemslip.reference.onset import critical_change, plane_directions, plane_tractions


def uniaxial_strain_change(dp: float, nu: float, biot: float = 1.0) -> dict:
    """Stress changes [Pa] of the uniaxial-strain path for a pressure change dp."""
    return {
        "xx": -biot * dp * (1.0 - 2.0 * nu) / (1.0 - nu),
        "yy": 0.0,
        "xx_eff": nu / (1.0 - nu) * biot * dp,
        "yy_eff": biot * dp,
    }


def rectangles_shear(x, y, rects, dp, nu, biot=1.0) -> np.ndarray:
    """sigma_xy(x, y) [Pa] of a pressure change dp in rectangles, no fault.

    rects : (k, 4) [x0, y0, x1, y1] [m].  Each rectangle is a polygon of
    ``inclusion.polygon_stress``, whose sigma_xy is here the corner sum
    behind (J1): sigma_xy = C [g(x - x0, y - y0) - g(x - x0, y - y1)
    - g(x - x1, y - y0) + g(x - x1, y - y1)], g = ln r, summed over the
    rectangles; valid at any point off the corners (inside, outside or on
    an edge of the rectangles), NaN at a corner.
    """
    x, y = np.broadcast_arrays(np.asarray(x, float), np.asarray(y, float))
    xy = np.column_stack([x.ravel(), y.ravel()])
    out = np.zeros(x.size)
    for corners in np.asarray(rects, float).reshape(-1, 4):
        box = Box.from_corners(*corners).vertices()
        out += polygon_stress(xy, box, dp, nu, biot)[:, 2]
    return out.reshape(x.shape)


def offset_fault_shear(y, a, b, c, d, dp, nu, biot=1.0) -> np.ndarray:
    """sigma_xy(0, y) [Pa] on the stuck fault, eq. (J1).

    y : (n,) depths along the fault [m]; a < b the reservoir left of the fault,
    c < d right of it [m]; dp [Pa]; nu [-].  Infinite at the corners.
    """
    y = np.asarray(y, float)
    C = biot * dp * (1.0 - 2.0 * nu) / (2.0 * np.pi * (1.0 - nu))
    with np.errstate(divide="ignore"):
        return C * (
            np.log(np.abs(y - b))
            + np.log(np.abs(y - c))
            - np.log(np.abs(y - a))
            - np.log(np.abs(y - d))
        )


def offset_fault_slip(y, a, b, c, d, dp, nu, shear_modulus, biot=1.0) -> np.ndarray:
    """Slip u_y(left) - u_y(right) [m] of the frictionless fault, eq. (J2).

    Requires b - a == d - c (same thickness on both sides; otherwise the
    infinite-fault slip is not compact and (J2) does not apply).
    """
    if not np.isclose(b - a, d - c, rtol=1e-12, atol=0.0):
        raise ValueError("offset_fault_slip needs b - a == d - c")
    y = np.asarray(y, float)
    k = biot * dp * (1.0 - 2.0 * nu) / (2.0 * shear_modulus)
    return -k * (np.abs(y - b) + np.abs(y - c) - np.abs(y - a) - np.abs(y - d))


def dislocation_shear(y, s, slip, nu, shear_modulus) -> np.ndarray:
    """sigma_xy(0, y) [Pa] of a piecewise-linear slip (s, slip) on x = 0.

    sigma = -mu / (2 pi (1 - nu)) PV int delta'(s) / (s - y) ds, delta =
    u_y(left) - u_y(right), with delta' constant on each piece, integrated
    exactly: int_{s0}^{s1} ds / (s - y) = ln|s1 - y| - ln|s0 - y| (the
    principal value at y inside a piece).  The
    independent check of (J2): it must cancel (J1).
    """
    y = np.asarray(y, float)
    s = np.asarray(s, float)
    g = np.diff(slip) / np.diff(s)  # delta' on each piece
    with np.errstate(divide="ignore"):
        terms = g[None, :] * (
            np.log(np.abs(s[None, 1:] - y[:, None]))
            - np.log(np.abs(s[None, :-1] - y[:, None]))
        )
    return -shear_modulus / (2.0 * np.pi * (1.0 - nu)) * terms.sum(axis=1)


def critical_change_uniaxial(
    initial_stress, p0, nu, angle_deg, friction, cohesion=0.0, biot=1.0, sign=-1.0
) -> float:
    """Pore-pressure change [Pa] at which a plane first slips or opens on the
    uniaxial-strain path (:func:`xfemslip.reference.onset.onset`).

    initial_stress : (xx, yy, xy) total [Pa]; p0 [Pa]; the plane's tangent at
    ``angle_deg`` from +x, normal n = (-sin, cos).  Along the path
    sigma_xx = sigma0_xx - alpha (1 - 2 nu) / (1 - nu) dp, sigma_yy, sigma_xy
    constant (Biot in the bulk), and the fracture sees sigma_n' = sigma_n + p
    (Terzaghi): sigma_n' = A0 + A1 dp, tau = B0 + B1 dp.  ``sign`` = -1
    looks for the first limit under depletion (dp >= -p0), +1 under
    injection; 0 at or beyond the limit in situ, NaN if never.
    """
    c, s = plane_directions(angle_deg)
    rate = (-biot * (1.0 - 2.0 * nu) / (1.0 - nu), 0.0, 0.0)
    A0, B0 = plane_tractions(initial_stress, c, s)
    A1, B1 = plane_tractions(rate, c, s)
    return float(
        critical_change((A0 + p0, A1 + 1.0), (B0, B1), friction, cohesion, sign, p0)
    )
