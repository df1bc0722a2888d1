"""Closed-form references: the frictional straight crack and the slip window.

Pure numpy, independent of the XFEM code (nothing here imports the solver), so
that ``xfemslip verify``, the screening tools and the tests can compare the
simulator against it.  Sources:

- straight crack of half-length a in an infinite elastic plane under a uniform
  remote stress, Coulomb friction f and cohesion c on its faces: the slip is
  the mode-II Westergaard solution driven by the excess shear
  Delta tau = sign(t_T) (|t_T| - c - f max(0, -t_N))
  (Phan, Napier, Gray & Kaplan 2003, "Symmetric-Galerkin BEM simulation of
  fracture with frictional contact", IJNME 57; Westergaard 1939 stress
  function for mode II, Z = Delta tau (z / sqrt(z^2 - a^2) - 1));
- the Mohr-Coulomb slip window: the range of angles beta between a plane and
  sigma_1 on which |tau| > c + f sigma_n (Jaeger, Cook & Zimmerman,
  "Fundamentals of rock mechanics", 4th ed., section 4.7);
- Hooke's law of a homogeneous plane-strain / plane-stress state.

Units SI, stresses tension positive (as in xfemslip).  Frame of a crack at
angle psi: t = (cos psi, sin psi), n = (-sin psi, cos psi); the + side is the
side n points to; jump = u(+) - u(-).
"""

from __future__ import annotations

import math
from typing import TypeVar

import numpy as np

# a number, or an array of them per point
Value = TypeVar("Value", float, np.ndarray)


def kolosov(nu: Value, plane: str) -> Value:
    """Kolosov constant: 3 - 4 nu (plane strain), (3 - nu)/(1 + nu) (plane stress)."""
    return 3.0 - 4.0 * nu if plane == "plane_strain" else (3.0 - nu) / (1.0 + nu)


def stress_matrix(stress) -> np.ndarray:
    """(xx, yy, xy) -> 2x2 symmetric tensor [Pa]."""
    sxx, syy, sxy = stress
    return np.array([[sxx, sxy], [sxy, syy]], dtype=float)


def strain(stress, E: float, nu: float, plane: str) -> np.ndarray:
    """In-plane strain tensor (2, 2) of a homogeneous stress state (Hooke's law).

    Plane strain: eps_zz = 0, so eps = ((1 - nu^2) s - nu (1 + nu) s_other) / E;
    plane stress: sigma_zz = 0, eps = (s - nu s_other) / E.
    """
    sxx, syy, sxy = stress
    G = E / (2.0 * (1.0 + nu))
    if plane == "plane_strain":
        exx = ((1 - nu**2) * sxx - nu * (1 + nu) * syy) / E
        eyy = ((1 - nu**2) * syy - nu * (1 + nu) * sxx) / E
    else:
        exx = (sxx - nu * syy) / E
        eyy = (syy - nu * sxx) / E
    exy = sxy / (2.0 * G)
    return np.array([[exx, exy], [exy, eyy]])


def homogeneous_displacement(points, stress, E, nu, plane, origin=(0.0, 0.0)):
    """u = eps . (x - origin) (N, 2) [m]: the uncracked solution, no rotation."""
    pts = np.asarray(points, dtype=float) - np.asarray(origin, dtype=float)
    return pts @ strain(stress, E, nu, plane).T


def crack_tractions(stress, psi_deg):
    """Normal and shear traction (t_N, t_T) = (n.s.n, t.s.n) on a plane at psi [deg]."""
    p = math.radians(psi_deg)
    t = np.array([math.cos(p), math.sin(p)])
    n = np.array([-math.sin(p), math.cos(p)])
    s = stress_matrix(stress)
    return float(n @ s @ n), float(t @ s @ n)


def driving_shear(stress, psi_deg, friction, cohesion=0.0):
    """Signed excess shear sign(t_T)(|t_T| - c - f max(0, -t_N)); 0 if it sticks."""
    t_n, t_t = crack_tractions(stress, psi_deg)
    excess = abs(t_t) - cohesion - friction * max(0.0, -t_n)
    return math.copysign(excess, t_t) if excess > 0.0 else 0.0


def slip_profile(s, a, E, nu, plane, stress, psi_deg, friction, cohesion=0.0):
    """Slip [[u]].t at arc length s in [0, 2a] from the first tip (Phan et al. 2003).

    [[u_t]](x) = 4 (1 - nu^2) / E * Delta tau * sqrt(a^2 - x^2) (plane strain),
    4 / E * Delta tau * sqrt(a^2 - x^2) (plane stress), x = s - a.
    """
    x = np.asarray(s, dtype=float) - a
    factor = 4.0 * (1.0 - nu**2) / E if plane == "plane_strain" else 4.0 / E
    dtau = driving_shear(stress, psi_deg, friction, cohesion)
    return factor * dtau * np.sqrt(np.clip(a * a - x * x, 0.0, None))


def displacement(
    points, center, a, E, nu, plane, stress, psi_deg, friction, cohesion=0.0
):
    """Exact displacement (N, 2) of the cracked infinite plane at points (N, 2).

    Uniform remote strain (no rotation about ``center``) plus the Westergaard
    mode-II perturbation of the slipping crack.  Points exactly on the crack
    faces are ambiguous; boundary points never are.
    """
    pts = np.asarray(points, dtype=float) - np.asarray(center, dtype=float)
    u = pts @ strain(stress, E, nu, plane).T
    dtau = driving_shear(stress, psi_deg, friction, cohesion)
    if dtau == 0.0:
        return u
    G = E / (2.0 * (1.0 + nu))
    p = math.radians(psi_deg)
    t = np.array([math.cos(p), math.sin(p)])
    n = np.array([-math.sin(p), math.cos(p)])
    xl = pts @ t
    yl = pts @ n
    z = xl + 1j * yl
    root = np.sqrt(z - a) * np.sqrt(z + a)
    Z = dtau * (z / root - 1.0)
    Zhat = dtau * (root - z)
    kappa = kolosov(nu, plane)
    ux_l = ((kappa + 1.0) / 2.0 * Zhat.imag + yl * Z.real) / (2.0 * G)
    uy_l = (-(kappa - 1.0) / 2.0 * Zhat.real - yl * Z.imag) / (2.0 * G)
    return u + np.outer(ux_l, t) + np.outer(uy_l, n)


def _local_frame(points, center, psi_deg):
    """Crack-frame coordinates (x_l, y_l) and the unit vectors t, n."""
    pts = np.asarray(points, dtype=float) - np.asarray(center, dtype=float)
    p = math.radians(psi_deg)
    t = np.array([math.cos(p), math.sin(p)])
    n = np.array([-math.sin(p), math.cos(p)])
    return pts @ t, pts @ n, t, n


def stress_field(points, center, a, stress, psi_deg, friction, cohesion=0.0):
    """Exact stress (N, 3) [sxx, syy, sxy] [Pa] of the cracked infinite plane.

    Remote stress plus the Westergaard mode-II perturbation of the slipping
    crack, Z = Delta tau (z / sqrt(z^2 - a^2) - 1), Z' = -Delta tau a^2 /
    (z^2 - a^2)^(3/2), in the crack frame (Westergaard 1939; Anderson,
    "Fracture mechanics", 3rd ed., appendix 2.3):

        s_xx = 2 Im Z + y Re Z',  s_yy = -y Re Z',  s_xy = Re Z - y Im Z'.

    The same in plane strain and plane stress (the in-plane stresses of a
    traction problem do not depend on the elastic constants).  On the faces
    (y = 0, |x| < a) the shear is t_T - Delta tau, the friction bound.
    """
    xl, yl, t, n = _local_frame(points, center, psi_deg)
    base = stress_matrix(stress)
    out = np.tile(np.array([base[0, 0], base[1, 1], base[0, 1]]), (xl.size, 1))
    dtau = driving_shear(stress, psi_deg, friction, cohesion)
    if dtau == 0.0:
        return out
    z = xl + 1j * yl
    root = np.sqrt(z - a) * np.sqrt(z + a)
    Z = dtau * (z / root - 1.0)
    dZ = -dtau * a * a / root**3
    sxx = 2.0 * Z.imag + yl * dZ.real
    syy = -yl * dZ.real
    sxy = Z.real - yl * dZ.imag
    # rotate the crack-frame perturbation to x, y: s = R^T s_l R, R rows (t, n)
    R = np.array([t, n])
    local = np.empty((xl.size, 2, 2))
    local[:, 0, 0], local[:, 1, 1] = sxx, syy
    local[:, 0, 1] = local[:, 1, 0] = sxy
    glob = np.einsum("ki,nkl,lj->nij", R, local, R)
    out[:, 0] += glob[:, 0, 0]
    out[:, 1] += glob[:, 1, 1]
    out[:, 2] += glob[:, 0, 1]
    return out


def k_ii(stress, psi_deg, a, friction, cohesion=0.0):
    """Mode-II stress intensity factor K_II = Delta tau sqrt(pi a) [Pa sqrt(m)].

    Signed like Delta tau (positive when the + face moves along +t).  The same
    at both tips of the straight crack (Phan et al. 2003; Tada, Paris & Irwin,
    "The stress analysis of cracks handbook", 3rd ed., section 5.1).
    """
    return driving_shear(stress, psi_deg, friction, cohesion) * math.sqrt(math.pi * a)


def principal(stress):
    """(sigma1, sigma3, dir1_deg): compressive magnitudes (sigma1 >= sigma3, compression
    positive) and the direction of sigma1 in [0, 180) deg from +x."""
    vals, vecs = np.linalg.eigh(
        stress_matrix(stress)
    )  # ascending: most compressive first
    dir1 = math.degrees(math.atan2(vecs[1, 0], vecs[0, 0])) % 180.0
    return -vals[0], -vals[1], dir1


def slip_window(sigma1, sigma3, friction, cohesion=0.0):
    """Angles beta (deg) between a fracture plane and sigma1 for which it slips.

    sigma1 >= sigma3 are compressive magnitudes (compression positive here).
    With phi = atan f and S = (2 c cos phi + (s1 + s3) sin phi) / (s1 - s3),
    the plane slips for (asin S - phi)/2 < beta < (pi - phi - asin S)/2
    (Jaeger et al. 2007, eq. 4.7.5 rearranged).  Returns (beta_min, beta_max)
    or None when no orientation slips.
    """
    phi = math.atan(friction)
    if sigma1 <= sigma3:
        return None
    S = (2 * cohesion * math.cos(phi) + (sigma1 + sigma3) * math.sin(phi)) / (
        sigma1 - sigma3
    )
    if S > 1.0:
        return None
    lo = (math.asin(S) - phi) / 2.0
    hi = (math.pi - phi - math.asin(S)) / 2.0
    return math.degrees(lo), math.degrees(hi)


def angle_to_sigma1(theta_deg, dir1_deg):
    """Acute angle beta in [0, 90] deg between a plane at theta and sigma1."""
    return abs(((theta_deg - dir1_deg) + 90.0) % 180.0 - 90.0)


def relative_l2(s, numeric, exact):
    """Relative L2 norm of numeric - exact along arc length s (trapezoid rule)."""
    order = np.argsort(s)
    s, numeric, exact = (np.asarray(v, dtype=float)[order] for v in (s, numeric, exact))
    err = np.trapezoid((numeric - exact) ** 2, s)
    ref = np.trapezoid(exact**2, s)
    return math.sqrt(err / ref)
