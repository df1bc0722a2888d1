"""Closed-form screening of fracture orientations before simulating.

For a 2D stress state and a pore pressure, every plane orientation gets its
effective normal stress, shear stress, slip tendency and Coulomb failure
margin; the band of orientations that slip follows in closed form, and for a
given fracture the pore-pressure change at which it would slip.

Conventions (as everywhere in xfemslip): SI units, **tension positive**.  The
pore pressure p is positive when the fluid pushes, so the effective stress is
sigma' = sigma + p I (Terzaghi, Biot coefficient 1) and a rising p makes the
effective normal stress sigma_n' = sigma_n + p less compressive.  A plane at
angle theta (degrees, counter-clockwise from +x, like ``angle`` in a case
file) has t = (cos theta, sin theta), n = (-sin theta, cos theta),
sigma_n = n.sigma.n, tau = t.sigma.n.

- slip tendency T_s = |tau| / (-sigma_n') (Morris, Ferrill & Henderson 1996,
  "Slip-tendency analysis and fault reactivation", Geology 24); the plane
  slips without cohesion when T_s >= f; infinite for a plane in tension;
- Coulomb failure margin m = c + f max(0, -sigma_n') - |tau| [Pa]
  (the contact law of xfemslip: positive = stable, <= 0 = slips; Jaeger, Cook
  & Zimmerman 2007, section 4.7);
- pore-pressure change to slip dp_slip = m / f [Pa] (from m(p + dp) = 0:
  dm/dp = -f while the plane is in compression); the plane opens at
  dp_open = -sigma_n', and an open plane carries no shear, so it slips at
  min(dp_slip, dp_open);
- the band of angles beta to sigma_1 that slip: :func:`closed_form.slip_window`
  on the effective principal stresses.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from xfemslip.reference.closed_form import angle_to_sigma1, principal, slip_window


def effective_stress(stress, pore_pressure: float) -> tuple[float, float, float]:
    """sigma' = sigma + p I: (xx, yy, xy) [Pa], tension positive."""
    xx, yy, xy = (float(v) for v in stress)
    return xx + pore_pressure, yy + pore_pressure, xy


def plane_stresses(stress, theta_deg) -> tuple[np.ndarray, np.ndarray]:
    """(sigma_n, tau) [Pa] on planes at theta [deg] (arrays; see module doc)."""
    xx, yy, xy = (float(v) for v in stress)
    theta = np.asarray(theta_deg, dtype=float)
    c, s = np.cos(np.radians(theta)), np.sin(np.radians(theta))
    quarter = np.mod(theta, 90.0) == 0.0  # cos(pi/2) is 6e-17, not 0
    c, s = np.where(quarter, np.round(c), c), np.where(quarter, np.round(s), s)
    sigma_n = xx * s * s + yy * c * c - 2.0 * xy * s * c
    tau = (yy - xx) * s * c + xy * (c * c - s * s)
    return sigma_n + 0.0, tau + 0.0  # + 0.0: no -0.0 in the printout


def slip_tendency(sigma_n_eff, tau) -> np.ndarray:
    """|tau| / (-sigma_n'); inf where sigma_n' >= 0 and tau != 0, 0 where tau = 0."""
    sn = np.asarray(sigma_n_eff, dtype=float)
    ab = np.abs(np.asarray(tau, dtype=float))
    with np.errstate(divide="ignore", invalid="ignore"):
        ts = np.where(sn < 0.0, ab / -sn, np.where(ab > 0.0, np.inf, 0.0))
    return ts


def coulomb_margin(sigma_n_eff, tau, friction: float, cohesion: float = 0.0):
    """c + f max(0, -sigma_n') - |tau| [Pa]; <= 0 means the plane slips."""
    sn = np.asarray(sigma_n_eff, dtype=float)
    return cohesion + friction * np.maximum(0.0, -sn) - np.abs(np.asarray(tau, float))


def pressure_to_slip(sigma_n_eff, tau, friction, cohesion=0.0):
    """(dp_slip, dp_open, dp_critical) [Pa]: the pore-pressure changes at which
    the Coulomb margin reaches zero, the plane opens, and the first of the two.

    With f = 0 the margin does not depend on p: dp_slip is +inf (stable) or
    -inf (already slipping).  A negative dp means the plane slips already; a
    drop of |dp| would stop it.
    """
    sn = float(sigma_n_eff)
    margin = float(coulomb_margin(sn, tau, friction, cohesion))
    if friction > 0.0:
        dp_slip = margin / friction
    else:
        dp_slip = math.inf if margin > 0.0 else -math.inf
    dp_open = -sn
    return dp_slip, dp_open, min(dp_slip, dp_open) if margin > 0.0 else dp_slip


@dataclass(frozen=True)
class Band:
    """Orientations that slip: beta to sigma_1 and theta from +x [deg]."""

    sigma1: float  # effective, compressive magnitude [Pa]
    sigma3: float
    dir1: float  # direction of sigma_1 [deg from +x, in [0, 180)]
    beta: tuple[float, float] | None  # (beta_min, beta_max) or None: none slips
    theta: tuple[tuple[float, float], ...]  # intervals of theta in [0, 180)


def _wrap_interval(lo: float, hi: float) -> list[tuple[float, float]]:
    """(lo, hi) mod 180 as one or two intervals inside [0, 180]."""
    lo_m = lo % 180.0
    hi_m = lo_m + (hi - lo)
    if hi_m <= 180.0:
        return [(lo_m, hi_m)]
    return [(lo_m, 180.0), (0.0, hi_m - 180.0)]


def slip_band(stress_eff, friction: float, cohesion: float = 0.0) -> Band:
    """The band of plane orientations that slip under ``stress_eff``."""
    s1, s3, dir1 = principal(stress_eff)
    beta = slip_window(s1, s3, friction, cohesion)
    intervals: list[tuple[float, float]] = []
    if beta is not None:
        lo, hi = beta
        intervals += _wrap_interval(dir1 + lo, dir1 + hi)
        intervals += _wrap_interval(dir1 - hi, dir1 - lo)
    return Band(s1, s3, dir1, beta, tuple(sorted(intervals)))


def orientation_table(stress, pore_pressure, friction, cohesion, theta_deg):
    """Per plane orientation: a dict of arrays theta, beta, sigma_n_eff, tau,
    slip_tendency, margin, slips (bool)."""
    eff = effective_stress(stress, pore_pressure)
    theta = np.asarray(theta_deg, dtype=float)
    sn, tau = plane_stresses(eff, theta)
    dir1 = principal(eff)[2]
    margin = coulomb_margin(sn, tau, friction, cohesion)
    return {
        "theta_deg": theta,
        "beta_deg": np.array([angle_to_sigma1(t, dir1) for t in theta]),
        "sigma_n_eff_Pa": sn,
        "tau_Pa": tau,
        "slip_tendency": slip_tendency(sn, tau),
        "margin_Pa": margin,
        "slips": margin <= 0.0,
    }


@dataclass(frozen=True)
class FractureScreen:
    """The screening numbers of one fracture (or polyline segment)."""

    label: str
    theta: float  # [deg]
    beta: float  # [deg] to sigma_1
    friction: float
    cohesion: float  # [Pa]
    sigma_n_eff: float  # [Pa]
    tau: float  # [Pa]
    slip_tendency: float
    margin: float  # [Pa]
    dp_slip: float  # [Pa]
    dp_open: float  # [Pa]
    dp_critical: float  # [Pa]


def screen_fracture(label, theta, stress, pore_pressure, friction, cohesion=0.0):
    """Screen one plane at ``theta`` [deg]."""
    eff = effective_stress(stress, pore_pressure)
    sn, tau = (float(v) for v in plane_stresses(eff, theta))
    dp_slip, dp_open, dp_crit = pressure_to_slip(sn, tau, friction, cohesion)
    return FractureScreen(
        label=label,
        theta=float(theta),
        beta=angle_to_sigma1(theta, principal(eff)[2]),
        friction=float(friction),
        cohesion=float(cohesion),
        sigma_n_eff=sn,
        tau=tau,
        slip_tendency=float(slip_tendency(sn, tau)),
        margin=float(coulomb_margin(sn, tau, friction, cohesion)),
        dp_slip=dp_slip,
        dp_open=dp_open,
        dp_critical=dp_crit,
    )


def case_fractures(spec):
    """(label, theta [deg], friction, cohesion) of every straight segment of
    every fracture of a case."""
    out = []
    for fracture in spec.fractures:
        pts = np.asarray(fracture.points, dtype=float)
        d = np.diff(pts, axis=0)
        for k, (dx, dy) in enumerate(d):
            label = f"fractures[{fracture.index}]"
            if len(d) > 1:
                label += f" segment {k}"
            theta = math.degrees(math.atan2(dy, dx)) % 180.0
            out.append((label, theta, fracture.friction, fracture.cohesion))
    return out


def format_report(stress, pore_pressure, friction, cohesion, step, fractures) -> str:
    """The text report of ``xfemslip screen``: state, band, table, fractures."""
    eff = effective_stress(stress, pore_pressure)
    band = slip_band(eff, friction, cohesion)
    phi = math.degrees(math.atan(friction))
    lines = [
        "Stresses in Pa, tension positive; effective stress sigma' = sigma + p I.",
        f"total stress xx = {stress[0]:.6g}, yy = {stress[1]:.6g}, "
        f"xy = {stress[2]:.6g}; pore pressure p = {pore_pressure:.6g}",
        f"effective principal stresses (compression): sigma1' = {band.sigma1:.6g} "
        f"at {band.dir1:.2f} deg from +x, sigma3' = {band.sigma3:.6g}",
        f"friction f = {friction:g} (phi = {phi:.2f} deg), cohesion c = {cohesion:g}",
        "stress path: the total stress stays as given while the pore pressure "
        "changes (the dp to slip below); the stress a depleting reservoir "
        "transfers is not included (xfemslip deplete solves it)",
    ]
    if band.beta is None:
        lines.append("slip band: no orientation slips")
    else:
        thetas = ", ".join(f"{a:.2f}..{b:.2f}" for a, b in band.theta)
        lines.append(
            f"slip band: beta = {band.beta[0]:.2f}..{band.beta[1]:.2f} deg from "
            f"sigma1, i.e. theta = {thetas} deg from +x; most critical at beta = "
            f"{45.0 - phi / 2:.2f} deg"
        )
    table = orientation_table(
        stress, pore_pressure, friction, cohesion, np.arange(0.0, 180.0, step)
    )
    lines += ["", _orientation_text(table)]
    if fractures:
        lines += ["", _fracture_text(fractures)]
    return "\n".join(lines)


def _orientation_text(table) -> str:
    """The per-orientation table as aligned text."""
    header = (
        "theta[deg]  beta[deg]  sigma_n'[Pa]  tau[Pa]     T_s      margin[Pa]  slips"
    )
    rows = [
        f"{table['theta_deg'][i]:10.2f}  {table['beta_deg'][i]:9.2f}  "
        f"{table['sigma_n_eff_Pa'][i]:12.4g}  {table['tau_Pa'][i]:10.4g}  "
        f"{table['slip_tendency'][i]:7.4f}  {table['margin_Pa'][i]:11.4g}  "
        f"{'yes' if table['slips'][i] else 'no'}"
        for i in range(table["theta_deg"].size)
    ]
    return "\n".join([header, *rows])


def _fracture_text(fractures: list[FractureScreen]) -> str:
    """The per-fracture lines, with the pore-pressure change to slip."""
    lines = []
    for fs in fractures:
        if fs.margin <= 0.0:
            change = (
                f"SLIPS already; a pore-pressure drop of {-fs.dp_slip:.6g} Pa "
                "would stop it"
                if math.isfinite(fs.dp_slip)
                else "SLIPS at any pore pressure (f = 0)"
            )
        else:
            change = (
                f"stable; slips at a pore-pressure change dp = "
                f"{fs.dp_critical:.6g} Pa (Coulomb {fs.dp_slip:.6g}, opening "
                f"{fs.dp_open:.6g})"
            )
        lines.append(
            f"{fs.label}: theta = {fs.theta:.2f} deg (beta = {fs.beta:.2f} deg), "
            f"f = {fs.friction:g}, c = {fs.cohesion:g}: sigma_n' = "
            f"{fs.sigma_n_eff:.6g}, tau = {fs.tau:.6g}, T_s = "
            f"{fs.slip_tendency:.4f}, margin = {fs.margin:.6g} -> {change}"
        )
    return "\n".join(lines)
