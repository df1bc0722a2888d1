"""The Mohr-Coulomb diagram of the seed paper's Fig. 13 (matplotlib axes).

Drawn tension positive like every xfemslip output: compressive normal
stresses lie left of zero.  A plane at angle beta to sigma_1' sits on the
circle at sigma_n' = C + R cos 2 beta, |tau| = R sin 2 beta, with
C = -(sigma1' + sigma3') / 2 and R = (sigma1' - sigma3') / 2 (sigma1' >=
sigma3' compressive magnitudes).  The failure line is |tau| = c - f sigma_n';
the arc above it is the band of orientations that slip
(:func:`xfemslip.reference.screen.slip_band`).  An inset shows those orientations in
the x-y plane.
"""

from __future__ import annotations

import math

import numpy as np

from xfemslip.reference.closed_form import angle_to_sigma1
from xfemslip.reference.screen import effective_stress, slip_band


def _circle_point(centre: float, radius: float, beta_deg):
    """(sigma_n', |tau|) of planes at beta [deg] to sigma_1'."""
    two_beta = np.radians(2.0 * np.asarray(beta_deg, dtype=float))
    return centre + radius * np.cos(two_beta), radius * np.sin(two_beta)


def draw_mohr(
    ax,
    stress,
    pore_pressure: float = 0.0,
    *,
    fractures=(),
    contact=(),
    color: str = "C0",
    first: bool = True,
    circle: bool = True,
    criterion: bool = True,
    inset_lines=None,
) -> None:
    """Draw the circle of ``stress`` (+ p), the failure line of each distinct
    (f, c) of ``fractures`` = [(label, theta [deg], f, c)], the slip band, the
    fractures' points and the ``contact`` tractions [(p_N (K,), p_T (K,))].

    ``first``: also label the axes and draw the inset, with the fracture
    lines ``inset_lines`` = [(theta [deg], colour)] (default: ``fractures``
    in ``color``); ``circle`` and
    ``criterion`` switch off parts already drawn for an earlier result.  The
    caller adds the legend (:func:`add_legend`) once everything is drawn.
    """
    eff = effective_stress(stress, pore_pressure)
    band0 = slip_band(eff, 0.0)
    s1, s3, dir1 = band0.sigma1, band0.sigma3, band0.dir1
    centre, radius = -(s1 + s3) / 2.0, (s1 - s3) / 2.0
    x_left = mohr_limits(stress, pore_pressure)[0]
    if circle:
        xs, ys = _circle_point(centre, radius, np.linspace(0.0, 90.0, 181))
        ax.plot(
            xs,
            ys,
            color=color,
            lw=1.2,
            label=f"Mohr circle: $\\sigma_1'$ = {s1:.3g} Pa, "
            f"$\\sigma_3'$ = {s3:.3g} Pa (compressive)",
        )
        ax.plot([-s1, -s3], [0, 0], "o", color=color, ms=3)
    seen = set()
    for _, _, f, c in fractures:
        if (f, c) in seen or not criterion:
            continue
        seen.add((f, c))
        phi = math.degrees(math.atan(f))
        xs = np.array([x_left, 0.0])
        ax.plot(
            xs,
            c - f * xs,
            "--",
            color=color,
            lw=1.0,
            label=f"failure line $|\\tau| = c - f\\,\\sigma_n'$ "
            f"(f = {f:g}, c = {c:g} Pa)",
        )
        band = slip_band(eff, f, c)
        if band.beta is not None:
            bx, by = _circle_point(centre, radius, np.linspace(*band.beta, 100))
            ax.fill_between(bx, c - f * bx, by, color=color, alpha=0.18, lw=0)
            ax.plot(
                bx,
                by,
                color="C3",
                lw=3,
                alpha=0.7,
                label=f"slips: $\\beta$ = {band.beta[0]:.1f}..{band.beta[1]:.1f} deg "
                f"from $\\sigma_1'$ (f = {f:g}; most critical "
                f"$45 - \\phi/2$ = {45 - phi / 2:.1f} deg)",
            )
        else:
            ax.plot([], [], " ", label=f"f = {f:g}: no orientation slips")
    for label, theta, _, _ in fractures:
        beta = angle_to_sigma1(theta, dir1)
        px, py = _circle_point(centre, radius, beta)
        ax.plot([centre, px], [0.0, py], color=color, lw=0.6)
        ax.plot(px, py, "o", color=color, mec="k", ms=7, zorder=5)
        if not label:  # annotated with an earlier result at the same point
            continue
        ax.annotate(
            f"{label} ($\\beta$ = {beta:.1f} deg)",
            (px, py),
            textcoords="offset points",
            xytext=(5, 4),
            fontsize=7,
        )
    for k, (pn, pt) in enumerate(contact):
        ax.plot(
            pn,
            np.abs(pt),
            ".",
            color="0.35",
            ms=2.5,
            label="contact points of the run $(p_N, |p_T|)$"
            if first and k == 0
            else None,
        )
    if first:
        ax.set_xlabel("effective normal stress $\\sigma_n'$ [Pa] (tension positive)")
        ax.set_ylabel("shear stress $|\\tau|$ [Pa]")
        ax.axhline(0.0, color="k", lw=0.5)
        ax.axvline(0.0, color="k", lw=0.5)
        ax.set_aspect("equal")
        ax.set_xlim(*mohr_limits(stress, pore_pressure)[:2])
        ax.set_ylim(*mohr_limits(stress, pore_pressure)[2:])
        ax.ticklabel_format(style="sci", scilimits=(-3, 3))
        f0, c0 = (fractures[0][2], fractures[0][3]) if fractures else (0.0, 0.0)
        if inset_lines is None:
            inset_lines = [(theta, color) for _, theta, _, _ in fractures]
        _inset(ax, slip_band(eff, f0, c0), inset_lines)


def mohr_limits(stress, pore_pressure: float = 0.0) -> tuple[float, ...]:
    """(x0, x1, y0, y1) of the diagram [Pa]: the circle, zero and room above."""
    band = slip_band(effective_stress(stress, pore_pressure), 0.0)
    s1, radius = max(band.sigma1, 1.0), (band.sigma1 - band.sigma3) / 2.0
    return -1.08 * s1, 0.25 * s1, 0.0, max(1.5 * radius, 0.3 * s1)


def mohr_figsize(stress, pore_pressure: float = 0.0, width: float = 8.0):
    """Figure size that fits the equal-aspect diagram, its title and legend."""
    x0, x1, y0, y1 = mohr_limits(stress, pore_pressure)
    return width, (width - 0.8) * (y1 - y0) / (x1 - x0) + 2.0


def add_legend(fig) -> None:
    """One legend below the diagram for everything drawn on it."""
    fig.legend(loc="outside lower center", ncol=2, fontsize=7)


def _inset(ax, band, lines) -> None:
    """Plane orientations that slip, drawn in the x-y plane (sigma_1' arrows)."""
    ins = ax.inset_axes([0.78, 0.40, 0.21, 0.50])
    ins.set_aspect("equal")
    ins.set_xlim(-1.3, 1.3)
    ins.set_ylim(-1.3, 1.3)
    ins.set_xticks([])
    ins.set_yticks([])
    ins.set_xlabel("planes that slip (red)", fontsize=6.5, labelpad=2)
    for lo, hi in band.theta:
        for turn in (0.0, 180.0):
            t = np.radians(np.linspace(lo, hi, 30) + turn)
            ins.fill(
                np.r_[0, np.cos(t), 0],
                np.r_[0, np.sin(t), 0],
                color="C3",
                alpha=0.3,
                lw=0,
            )
    d = np.radians(band.dir1)
    for sign in (1, -1):
        tip = sign * 1.25 * np.array([np.cos(d), np.sin(d)])
        ins.annotate(
            "", xy=0.8 * tip, xytext=tip, arrowprops={"arrowstyle": "->", "lw": 1.0}
        )
    ins.text(
        *(1.0 * np.array([np.cos(d + 0.45), np.sin(d + 0.45)])),
        "$\\sigma_1'$",
        fontsize=7,
    )
    for theta, color in lines:
        t = math.radians(theta)
        ins.plot(
            [-math.cos(t), math.cos(t)],
            [-math.sin(t), math.sin(t)],
            color=color,
            lw=1.5,
        )
