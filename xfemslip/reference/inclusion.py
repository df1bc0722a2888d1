"""Stress change of a uniform pore-pressure change in polygons of an infinite
plane (inclusion theory), and the displaced fault of Jansen, Singhal &
Vossepoel (2019).

Signs: tension positive, dp < 0 = depletion, alpha the Biot coefficient,
plane strain, homogeneous isotropic elasticity (Poisson's ratio nu).

**Goodier's potential.**  A pressure change dp in a region A of an infinite
plane is the displacement u = grad psi with (lambda + 2 mu) lap psi =
alpha dp chi_A (it solves the Navier equations with the Biot body force
alpha grad p), so

    psi = alpha dp / (lambda + 2 mu) Phi,
    Phi(x) = (1 / 2 pi) int_A ln|x - x'| dA',    lap Phi = chi_A,

and the total stress sigma = lambda tr(eps) I + 2 mu eps - alpha dp chi_A I
with eps = grad grad psi is

    sigma_ij = 2 mu (psi_,ij - delta_ij lap psi)
             = K (Phi_,ij - delta_ij chi_A),
    K = alpha dp (1 - 2 nu) / (1 - nu)                                   (G1)

(2 mu / (lambda + 2 mu) = (1 - 2 nu) / (1 - nu) in plane strain):
sigma_xx = -K Phi_,yy, sigma_yy = -K Phi_,xx, sigma_xy = K Phi_,xy.

**The polygon in closed form** (one sum over the edges).  With z = x + i y,
the divergence theorem turns Phi_,i into -(1/2 pi) oint ln|z - zeta| n_i ds
(n the outward normal), and 4 d^2/dz^2 Phi = Phi_,xx - Phi_,yy - 2 i Phi_,xy
into -(1/2 pi) oint conj(n) / (z - zeta) ds.  On a straight edge from P_k to
P_k+1 with unit tangent tau_k (complex), conj(n) = i conj(tau_k) and
ds = d zeta / tau_k, and the integral is a logarithm:

    Phi_,xx - Phi_,yy - 2 i Phi_,xy = -(i / 2 pi) sum_k conj(tau_k)^2 W_k,
    W_k = ln(r_k / r_k+1) + i theta_k,                                   (G2)

r_k = |z - P_k|, theta_k = arg((z - P_k) / (z - P_k+1)) in (-pi, pi] the
angle the edge subtends at z, and lap Phi = -(1 / 2 pi) sum_k theta_k (1
inside a counter-clockwise polygon, 0 outside).  For a rectangle the
imaginary part of (G2) is the corner sum of ln r behind
``closed_form_depletion.rectangles_shear`` (which calls this module).

The stress jumps across the polygon's boundary (the traction n.sigma.n,
t.sigma.n does not): at a point on an edge (within EDGE_TOL, relative)
this module returns the mean of the two one-sided limits, which
gives the traction on the edge exactly.  At a vertex the stress is
log-singular and NaN is returned.

**The displaced fault** (``displaced_fault``, ``fault_tractions``): a
reservoir of height h offset by a throw t across a fault of dip delta, each
compartment a quadrilateral with one side on the fault (Jansen, Singhal &
Vossepoel 2019, "Insights from closed-form expressions for injection- and
production-induced stresses in displaced faults", JGR Solid Earth 124; the
same geometry as the authors' published MATLAB examples, repository
Terzaghi1/InclusionTheory, example_F1_fault.m): the fault through the
reservoir's centre point (x_c, y_c) at x - x_c = (y - y_c) cot delta, the
hanging wall (the compartment above the fault plane: on the -x side for
delta < 90 degrees, on the +x side above 90) spanning
y_c - (h + t)/2 .. y_c + (h - t)/2, the footwall y_c - (h - t)/2 ..
y_c + (h + t)/2: t > 0 is a normal offset.  The four corners where the
compartments' tops and bases meet the fault are log singularities of the
traction.  Checked against that script (its two rectangles and two
triangles summed; ported to NumPy outside the project, not part of it): for
the published geometry (h = 225 m, t = 75 m, delta = 70 degrees,
nu = 0.15, alpha = 0.9, its width of 20 km: ``center = (10000, 0)``,
``width = 10000``) at 41 points along the fault, our tau equals minus its
sigma_parallel to 4e-16 relative (it takes the tangent up-dip and the normal
into the footwall, xfemslip the normal t turned +90 degrees, into the
hanging wall) and our sigma_n its sigma_perp to 6e-11 (it evaluates 1e-9 m
off the fault; the difference scales with that offset).  Its 20 km wide
reservoir differs from the laterally infinite one (``width=None``) by up to
0.6 % of the peak shear traction, the O(h / width) of its far sides.

Nothing here imports the solver.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

__all__ = [
    "EDGE_TOL",
    "DisplacedFault",
    "FaultTractions",
    "coulomb_change",
    "displaced_fault",
    "fault_tractions",
    "log_potential_hessian",
    "polygon_stress",
    "stress_factor",
]

# A point within EDGE_TOL (|z| + |v| + |z - v|) of an edge, v the edge's
# nearer end, lies on the edge: ~200 times the rounding of a point computed
# on the edge and of its distance to the edge measured from the nearer end
# (so that the far ends of a laterally infinite layer do not widen it).
EDGE_TOL = 4.0e-14
# A point closer than this (relative to the shorter edge at a vertex) to a
# vertex is at the vertex: the stress is log-singular there (NaN).
VERTEX_TOL = 1.0e-12
# The compartments of a laterally infinite reservoir end this many times
# (h + |t|) from the fault: their far sides change the stress near the fault
# by O(h / width), below round-off here.
LATERAL_INFINITY = 1.0e12


def _ccw(polygon) -> np.ndarray:
    """(m, 2) float64 vertices of a simple polygon, counter-clockwise."""
    P = np.asarray(polygon, dtype=np.float64)
    if P.ndim != 2 or P.shape[1] != 2 or P.shape[0] < 3:
        raise ValueError(f"polygon must be (m >= 3, 2), got shape {P.shape}")
    x, y = P[:, 0], P[:, 1]
    area2 = np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y)
    if area2 == 0.0:
        raise ValueError("polygon has zero area")
    return P if area2 > 0.0 else P[::-1].copy()


def _on_edge(z, a, b, za, zb) -> np.ndarray:
    """(n, m) whether point z[i] lies on edge k (a[k] to b[k]), EDGE_TOL."""
    e = b - a
    length = np.abs(e)
    along = (za * np.conj(e)).real / length  # from a, toward b
    across = np.abs((za * np.conj(e)).imag) / length
    near_a = along <= 0.5 * length
    v = np.where(near_a, a[None, :], b[None, :])
    r = np.where(near_a, np.abs(za), np.abs(zb))
    tol = EDGE_TOL * (np.abs(z)[:, None] + np.abs(v) + r)
    return (across <= tol) & (along > 0.0) & (along < length)


def log_potential_hessian(xy, polygon) -> np.ndarray:
    """Second derivatives of Phi(x) = (1/2 pi) int_A ln|x - x'| dA' of a
    simple polygon A, eq. (G2).

    Parameters
    ----------
    xy : (n, 2) float64 points [m]
    polygon : (m, 2) float64 vertices [m], either orientation, not closed
        (the last vertex joins the first)

    Returns
    -------
    (n, 4) float64: Phi_,xx, Phi_,yy, Phi_,xy [-] and lap Phi = chi_A (1
    inside, 0 outside, 1/2 on an edge); the mean of the two sides on an edge,
    NaN at a vertex.
    """
    P = _ccw(polygon)
    z = np.asarray(xy, dtype=np.float64).reshape(-1, 2) @ np.array([1.0, 1.0j])
    Pc = P @ np.array([1.0, 1.0j])
    a, b = Pc, np.roll(Pc, -1)  # edge k runs from a[k] to b[k]
    tau = (b - a) / np.abs(b - a)
    za = z[:, None] - a[None, :]  # (n, m)
    zb = z[:, None] - b[None, :]
    ra, rb = np.abs(za), np.abs(zb)
    prod = za * np.conj(zb)
    theta = np.arctan2(prod.imag, prod.real)
    theta = np.where(_on_edge(z, a, b, za, zb), 0.0, theta)  # the mean of +-pi
    with np.errstate(divide="ignore", invalid="ignore"):  # at a vertex: NaN below
        W = np.log(ra / rb) + 1j * theta
        D = (-1j / (2.0 * np.pi)) * (W * np.conj(tau)[None, :] ** 2).sum(axis=1)
    # the angles sum to -2 pi inside, -pi on an edge (its own set to 0), 0 outside
    lap = np.rint(-theta.sum(axis=1) / np.pi) / 2.0
    out = np.column_stack([0.5 * (lap + D.real), 0.5 * (lap - D.real), -0.5 * D.imag])
    length = np.abs(b - a)
    near = VERTEX_TOL * np.minimum(length, np.roll(length, 1))  # per vertex a[k]
    at_vertex = np.any(ra <= near[None, :], axis=1)
    out[at_vertex] = np.nan
    return np.column_stack([out, np.where(at_vertex, np.nan, lap)])


def stress_factor(dp: float, nu: float, biot: float = 1.0) -> float:
    """K = alpha dp (1 - 2 nu) / (1 - nu) [Pa] of eq. (G1)."""
    return biot * dp * (1.0 - 2.0 * nu) / (1.0 - nu)


def polygon_stress(xy, polygon, dp: float, nu: float, biot: float = 1.0) -> np.ndarray:
    """Total stress change [Pa] of a uniform pore-pressure change dp inside a
    polygon of an infinite homogeneous plane (plane strain), eq. (G1).

    Parameters
    ----------
    xy : (n, 2) float64 points [m]
    polygon : (m, 2) float64 vertices of a simple polygon [m]
    dp : pressure change in the polygon [Pa], < 0 = depletion
    nu : Poisson's ratio [-]; biot : Biot coefficient alpha [-]

    Returns
    -------
    (n, 3) float64 [sxx, syy, sxy] [Pa], tension positive; the mean of the
    two sides on an edge (the traction on the edge is that of either side),
    NaN at a vertex.  Several polygons (compartments with their own dp) add.
    """
    hxx, hyy, hxy, lap = log_potential_hessian(xy, polygon).T
    K = stress_factor(dp, nu, biot)
    return K * np.column_stack([hxx - lap, hyy - lap, hxy])


class DisplacedFault(NamedTuple):
    """A reservoir offset by a fault (see the module docstring).

    hanging_wall, footwall : (4, 2) float64 compartment polygons [m],
        counter-clockwise, one side of each on the fault
    point : (2,) float64 the reservoir's centre on the fault [m]
    tangent : (2,) float64 unit fault tangent, up-dip
    normal : (2,) float64 unit normal, the tangent turned +90 degrees (the
        xfemslip fracture frame; into the hanging wall for dip < 90 degrees)
    corners : (4,) float64 elevations y [m] of the four corners where the
        compartments' tops and bases meet the fault, increasing
    """

    hanging_wall: np.ndarray
    footwall: np.ndarray
    point: np.ndarray
    tangent: np.ndarray
    normal: np.ndarray
    corners: np.ndarray


def displaced_fault(
    height: float,
    throw: float,
    dip: float,
    width: float | None = None,
    center=(0.0, 0.0),
) -> DisplacedFault:
    """Compartments of a reservoir of ``height`` [m] offset by ``throw`` [m]
    (> 0: normal, the hanging wall down) across a fault of ``dip`` [deg]
    (0 < dip < 180; over 90 the fault leans the other way), through the
    reservoir's centre point ``center`` = (x_c, y_c) [m]; each compartment
    ends at a vertical side x = x_c -+ ``width`` [m] (None: laterally
    infinite, width LATERAL_INFINITY (h + |t|)).  The width must exceed
    the fault's horizontal reach (h + |t|) |cot dip| / 2."""
    if not (height > 0.0 and 0.0 < dip < 180.0):
        raise ValueError(f"need height > 0 and 0 < dip < 180, got {height}, {dip}")
    if width is None:
        width = LATERAL_INFINITY * (height + abs(throw))
    th = math.radians(dip)
    cot = math.cos(th) / math.sin(th)
    if not width > 0.5 * (height + abs(throw)) * abs(cot):
        raise ValueError(f"width {width} does not reach past the fault")
    xc, yc = (float(c) for c in center)

    def on_fault(y):
        return xc + (y - yc) * cot

    hw0, hw1 = yc - 0.5 * (height + throw), yc + 0.5 * (height - throw)
    fw0, fw1 = yc - 0.5 * (height - throw), yc + 0.5 * (height + throw)
    # the hanging wall lies above the fault plane: on the -x side when the
    # fault rises toward +x (dip < 90), on the +x side when it leans over
    side = -1.0 if dip <= 90.0 else 1.0

    def block(y0, y1, toward):
        far = xc + toward * width
        return _ccw([[on_fault(y0), y0], [far, y0], [far, y1], [on_fault(y1), y1]])

    hanging, foot = block(hw0, hw1, side), block(fw0, fw1, -side)
    tangent = np.array([math.cos(th), math.sin(th)])
    return DisplacedFault(
        hanging_wall=hanging,
        footwall=foot,
        point=np.array([xc, yc]),
        tangent=tangent,
        normal=np.array([-tangent[1], tangent[0]]),
        corners=np.sort([hw0, hw1, fw0, fw1]),
    )


class FaultTractions(NamedTuple):
    """Stress changes along the fault of a ``DisplacedFault``.

    xy : (n, 2) float64 the points on the fault [m]
    stress : (n, 3) float64 [sxx, syy, sxy] [Pa], the mean of the two sides
    sigma_n : (n,) float64 n.sigma.n [Pa], tension positive
    tau : (n,) float64 t.sigma.n [Pa]
    pressure_plus, pressure_minus : (n,) float64 the pressure change [Pa] on
        the + face (the side the normal points to) and on the - face: the
        compartment's dp where that face touches it, else 0
    """

    xy: np.ndarray
    stress: np.ndarray
    sigma_n: np.ndarray
    tau: np.ndarray
    pressure_plus: np.ndarray
    pressure_minus: np.ndarray


def _touches(y, polygon) -> np.ndarray:
    """Whether elevations y lie within the y-range of a compartment (closed)."""
    return (y >= polygon[:, 1].min()) & (y <= polygon[:, 1].max())


def fault_tractions(
    fault: DisplacedFault,
    y,
    dp_hanging: float,
    dp_foot: float,
    nu: float,
    biot: float = 1.0,
) -> FaultTractions:
    """Normal and shear traction changes along the fault at elevations ``y``
    [m] (n,), for pressure changes ``dp_hanging`` and ``dp_foot`` [Pa] in the
    two compartments (Poisson's ratio nu, Biot coefficient alpha = biot).

    The fault frame is xfemslip's: t = ``fault.tangent`` (up-dip), n =
    ``fault.normal``, sigma_n = n.sigma.n, tau = t.sigma.n.  NaN at the four
    corners (``fault.corners``), where the tractions are log-singular.
    """
    y = np.asarray(y, dtype=np.float64).reshape(-1)
    s = (y - fault.point[1]) / fault.tangent[1]
    xy = fault.point[None, :] + s[:, None] * fault.tangent[None, :]
    stress = polygon_stress(xy, fault.hanging_wall, dp_hanging, nu, biot)
    stress = stress + polygon_stress(xy, fault.footwall, dp_foot, nu, biot)
    n, t = fault.normal, fault.tangent
    sxx, syy, sxy = stress.T
    sigma_n = sxx * n[0] ** 2 + 2.0 * sxy * n[0] * n[1] + syy * n[1] ** 2
    tau = sxx * t[0] * n[0] + sxy * (t[0] * n[1] + t[1] * n[0]) + syy * t[1] * n[1]
    inward = fault.hanging_wall.mean(axis=0) - fault.point
    hanging_is_plus = float(np.dot(inward, n)) > 0.0
    p_hw = np.where(_touches(y, fault.hanging_wall), dp_hanging, 0.0)
    p_fw = np.where(_touches(y, fault.footwall), dp_foot, 0.0)
    plus, minus = (p_hw, p_fw) if hanging_is_plus else (p_fw, p_hw)
    return FaultTractions(xy, stress, sigma_n, tau, plus, minus)


def coulomb_change(
    tau, sigma_n, fault_pressure, friction: float, sense: float = -1.0
) -> np.ndarray:
    """Coulomb stress change [Pa] on a fault: positive = toward slip.

    dCFS = sense * d tau + friction * (d sigma_n + d p_f), with the effective
    normal traction sigma_n' = sigma_n + p_f (Terzaghi, as xfemslip's contact
    law; tension positive, so a less compressive sigma_n' is toward slip) and
    ``sense`` = +-1 the sign of the in-situ shear traction tau (the direction
    the fault is loaded in: -1 for a normal fault under normal-faulting
    stress in the frame of ``displaced_fault``, dip < 90 degrees).

    tau, sigma_n, fault_pressure : (n,) float64 changes [Pa]; fault_pressure
    is the fluid pressure change on the fault (the mean of
    ``FaultTractions.pressure_plus`` and ``pressure_minus``, their maximum or
    minimum, or a sealed fault's own value: the choice is the user's; Jansen
    et al. 2019 take alpha dp wherever the fault touches the reservoir on
    either side).
    """
    if sense not in (1.0, -1.0):
        raise ValueError(f"sense must be +1 or -1, got {sense}")
    tau, sigma_n, p = (
        np.asarray(v, dtype=np.float64) for v in (tau, sigma_n, fault_pressure)
    )
    return sense * tau + friction * (sigma_n + p)
