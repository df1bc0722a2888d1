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
- pore-pressure change to slip: the first dp at which the plane slips or
  opens along a stress path (:func:`xfemslip.reference.onset.onset`, the
  one law of the screen, the closed forms and the uncertainty screen).
  With the total stress kept (:func:`pressure_to_slip`) sigma_n' grows by dp
  and tau stays, so only a rise of p can reach the limit; ``xfemslip
  screen`` on a case with ``[pore_pressure]`` follows the case's own path
  (:mod:`xfemslip.studies.slip_screen`);
- the band of angles beta to sigma_1 that slip: :func:`closed_form.slip_window`
  on the effective principal stresses.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from xfemslip import display
from xfemslip.reference.closed_form import angle_to_sigma1, principal, slip_window
from xfemslip.reference.onset import (
    INJECTION,
    Onset,
    onset,
    plane_directions,
    plane_tractions,
)


def effective_stress(stress, pore_pressure: float) -> tuple[float, float, float]:
    """sigma' = sigma + p I: (xx, yy, xy) [Pa], tension positive."""
    xx, yy, xy = (float(v) for v in stress)
    return xx + pore_pressure, yy + pore_pressure, xy


def plane_stresses(stress, theta_deg) -> tuple[np.ndarray, np.ndarray]:
    """(sigma_n, tau) [Pa] on planes at theta [deg] (arrays; see module doc)."""
    return plane_tractions(stress, *plane_directions(theta_deg))


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


def pressure_to_slip(
    sigma_n_eff, tau, friction, cohesion=0.0, direction=INJECTION, pore_pressure=None
) -> Onset:
    """The first pore-pressure change [Pa] at which planes slip or open while
    the total stress stays: sigma_n' = sigma_n_eff + dp, tau constant
    (:func:`xfemslip.reference.onset.onset`; ``pore_pressure`` p0 bounds a
    depletion at dp = -p0)."""
    return onset(
        (sigma_n_eff, 1.0), (tau, 0.0), friction, cohesion, direction, pore_pressure
    )


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
    dp_critical: float  # [Pa]: 0 at or beyond the limit, NaN never
    opens: bool  # the limit reached first is opening, not Coulomb


def screen_fracture(
    label, theta, stress, pore_pressure, friction, cohesion=0.0, found=None
):
    """Screen one plane at ``theta`` [deg]: its in-situ numbers, and the
    pore-pressure change ``found`` (an :class:`Onset` of one plane) or, by
    default, the rise of p that reaches its limit at constant total stress."""
    eff = effective_stress(stress, pore_pressure)
    sn, tau = (float(v) for v in plane_stresses(eff, theta))
    if found is None:
        found = pressure_to_slip(sn, tau, friction, cohesion)
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
        dp_critical=float(np.asarray(found.change).reshape(-1)[0]),
        opens=bool(np.asarray(found.opens).reshape(-1)[0]),
    )


def case_fractures(spec):
    """(label, theta [deg], friction, cohesion, (P0, P1) [m]) of every
    straight segment of every fracture of a case."""
    out = []
    for fracture in spec.fractures:
        pts = np.asarray(fracture.points, dtype=float)
        d = np.diff(pts, axis=0)
        for k, (dx, dy) in enumerate(d):
            label = f"fractures[{fracture.index}]"
            if len(d) > 1:
                label += f" segment {k}"
            theta = math.degrees(math.atan2(dy, dx)) % 180.0
            ends = (pts[k], pts[k + 1])
            out.append((label, theta, fracture.friction, fracture.cohesion, ends))
    return out


def format_report(
    stress,
    pore_pressure,
    friction,
    cohesion,
    step,
    fractures,
    path_text,
    compression_positive=False,
) -> str:
    """The text report of ``xfemslip screen``: state, band, table, fractures;
    ``path_text`` the sentence naming the stress path of the dp to slip.
    Stresses in MPa (:mod:`xfemslip.display`), tension positive unless
    ``compression_positive``."""
    cp = compression_positive
    eff = effective_stress(stress, pore_pressure)
    band = slip_band(eff, friction, cohesion)
    phi = math.degrees(math.atan(friction))
    xx, yy, xy = (display.stress(v, cp) for v in stress)
    lines = [
        f"{display.convention(cp)}; effective stress sigma' = sigma + p I.",
        f"total stress xx = {xx}, yy = {yy}, xy = {xy}; pore pressure p = "
        f"{display.pressure(pore_pressure)}",
        "effective principal stresses (compression): sigma1' = "
        f"{display.pressure(band.sigma1)} at {band.dir1:.2f} deg from +x, "
        f"sigma3' = {display.pressure(band.sigma3)}",
        f"friction f = {friction:g} (phi = {phi:.2f} deg), cohesion c = "
        f"{display.pressure(cohesion)}",
        path_text,
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
    lines += ["", _orientation_text(table, cp)]
    if fractures:
        lines += ["", _fracture_text(fractures, cp)]
    return "\n".join(lines)


def _orientation_text(table, cp: bool = False) -> str:
    """The per-orientation table as aligned text (the CSV keeps Pa)."""

    def mpa(value, signed=True) -> str:
        value = display.megapascals(value, cp) if signed else value / 1e6
        return display.number(value, 4)

    return display.table(
        [
            "theta [deg]",
            "beta [deg]",
            "sigma_n' [MPa]",
            "tau [MPa]",
            "T_s",
            "margin [MPa]",
            "slips",
        ],
        [
            [
                f"{table['theta_deg'][i]:.2f}",
                f"{table['beta_deg'][i]:.2f}",
                mpa(table["sigma_n_eff_Pa"][i]),
                mpa(table["tau_Pa"][i]),
                f"{table['slip_tendency'][i]:.4f}",
                mpa(table["margin_Pa"][i], signed=False),
                "yes" if table["slips"][i] else "no",
            ]
            for i in range(table["theta_deg"].size)
        ],
    )


def _fracture_text(fractures: list[FractureScreen], cp: bool = False) -> str:
    """The per-fracture lines, with the pore-pressure change to slip."""
    lines = []
    for fs in fractures:
        limit = "opens" if fs.opens else "slips"
        if fs.dp_critical == 0.0:
            change = f"{limit.upper()} already"
        elif math.isnan(fs.dp_critical):
            change = "stable; neither slips nor opens along the path"
        else:
            at = display.pressure_change(fs.dp_critical, cp)
            change = (
                f"stable; {limit} at a depletion of {at}"
                if cp
                else f"stable; {limit} at a pore-pressure change dp = {at}"
            )
        lines.append(
            f"{fs.label}: theta = {fs.theta:.2f} deg (beta = {fs.beta:.2f} deg), "
            f"f = {fs.friction:g}, c = {display.pressure(fs.cohesion)}: sigma_n' = "
            f"{display.stress(fs.sigma_n_eff, cp)}, tau = "
            f"{display.stress(fs.tau, cp)}, T_s = {fs.slip_tendency:.4f}, margin = "
            f"{display.pressure(fs.margin)} -> {change}"
        )
    return "\n".join(lines)
