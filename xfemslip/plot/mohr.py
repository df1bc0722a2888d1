"""The Mohr-Coulomb diagram of the seed paper's Fig. 13 (matplotlib axes).

Drawn tension positive like every xfemslip output: compressive normal
stresses lie left of zero.  A plane at angle beta to sigma_1' sits on the
circle at sigma_n' = C + R cos 2 beta, |tau| = R sin 2 beta, with
C = -(sigma1' + sigma3') / 2 and R = (sigma1' - sigma3') / 2 (sigma1' >=
sigma3' compressive magnitudes).  The failure line is |tau| = c - f sigma_n';
the arc above it is the band of orientations that slip
(:func:`xfemslip.reference.screen.slip_band`).  An inset shows those orientations in
the x-y plane.  A run's contact points are drawn at their (p_N, |p_T|), red
where they slip; the band's text never says that no orientation slips
without saying how many of those points do.
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.ticker import FuncFormatter

from xfemslip.conventions import SLIP
from xfemslip.plot.style import place_labels
from xfemslip.reference.closed_form import angle_to_sigma1
from xfemslip.reference.screen import effective_stress, slip_band

# From this many labelled points on, numbered labels on leader lines.
NUMBERED_FROM = 5
# Least angle (in 2 beta, degrees) between two numbered labels on their ring.
LABEL_GAP_DEG = 8.0
# Line styles of the failure lines of successive (f, c).
CRITERION_STYLES = ("--", "-.", ":", (0, (6, 2, 1, 2, 1, 2)))


def _mpa(value: float) -> str:
    return f"{value / 1e6:.3g} MPa"


def _circle_point(centre: float, radius: float, beta_deg):
    """(sigma_n', |tau|) of planes at beta [deg] to sigma_1'."""
    two_beta = np.radians(2.0 * np.asarray(beta_deg, dtype=float))
    return centre + radius * np.cos(two_beta), radius * np.sin(two_beta)


def draw_circle(ax, stress_eff, color, label: str, **style) -> tuple[float, float]:
    """The upper half of the Mohr circle of the effective stress
    ``stress_eff`` (xx, yy, xy) [Pa], its principal stresses marked;
    returns (centre, radius) [Pa]."""
    band = slip_band(stress_eff, 0.0)
    s1, s3 = band.sigma1, band.sigma3
    centre, radius = -(s1 + s3) / 2.0, (s1 - s3) / 2.0
    xs, ys = _circle_point(centre, radius, np.linspace(0.0, 90.0, 181))
    ax.plot(
        xs,
        ys,
        color=color,
        lw=style.pop("lw", 1.2),
        label=f"{label}: $\\sigma_1'$ = {_mpa(s1)}, $\\sigma_3'$ = {_mpa(s3)} "
        "(compressive)",
        **style,
    )
    ax.plot([-s1, -s3], [0, 0], "o", color=color, ms=3)
    return centre, radius


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
    markers: bool = True,
    circle_label: str = "Mohr circle",
    limits=None,
    pending: list | None = None,
) -> None:
    """Draw the circle of ``stress`` (+ p), the failure line of each distinct
    (f, c) of ``fractures`` = [(label, theta [deg], f, c)], the slip band, the
    fractures' points on the circle (``markers``) and the ``contact``
    tractions [(p_N (K,), p_T (K,), state (K,))] (red where they slip).

    ``first``: also label the axes (within ``limits``, default
    :func:`mohr_limits`) and draw the inset, with the fracture
    lines ``inset_lines`` = [(theta [deg], colour)] (default: ``fractures``
    in ``color``); ``circle`` and
    ``criterion`` switch off parts already drawn for an earlier result.  The
    caller adds the legend (:func:`add_legend`) once everything is drawn.
    ``pending``: a list to which the points' labels [(anchor, text)] are
    added, for the caller to place (:func:`xfemslip.plot.style.place_labels`)
    once the layout is final; without it they are placed at once.
    """
    eff = effective_stress(stress, pore_pressure)
    dir1 = slip_band(eff, 0.0).dir1
    if circle:
        centre, radius = draw_circle(ax, eff, color, circle_label)
    else:
        band0 = slip_band(eff, 0.0)
        centre, radius = (
            -(band0.sigma1 + band0.sigma3) / 2.0,
            (band0.sigma1 - band0.sigma3) / 2.0,
        )
    if limits is None:
        limits = mohr_limits(stress, pore_pressure)
    slipping = sum(
        int(np.count_nonzero(np.asarray(st) == SLIP)) for _, _, st in contact
    )
    seen = set()
    for _, _, f, c in fractures:
        if (f, c) in seen or not criterion:
            continue
        seen.add((f, c))
        _criterion(
            ax, eff, f, c, color, len(seen) - 1, limits[0], (centre, radius), slipping
        )
    if markers:
        labels = _markers(ax, fractures, dir1, centre, radius, color)
        if pending is None:
            place_labels(ax, labels)
        else:
            pending.extend(labels)
    for k, (pn, pt, state) in enumerate(contact):
        slip = np.asarray(state) == SLIP
        for mask, c, what in (
            (~slip, "0.35", "stuck or open"),
            (slip, "C3", "in slip"),
        ):
            ax.plot(
                np.asarray(pn)[mask],
                np.abs(np.asarray(pt))[mask],
                ".",
                color=c,
                ms=2.5 if c != "C3" else 3.5,
                label=f"contact points {what} $(p_N, |p_T|)$"
                if first and k == 0
                else None,
            )
    if first:
        ax.set_xlabel("effective normal stress $\\sigma_n'$ [MPa] (tension positive)")
        ax.set_ylabel("shear stress $|\\tau|$ [MPa]")
        ax.axhline(0.0, color="k", lw=0.5)
        ax.axvline(0.0, color="k", lw=0.5)
        ax.set_aspect("equal")
        ax.set_xlim(*limits[:2])
        ax.set_ylim(*limits[2:])
        in_mpa = FuncFormatter(lambda value, _: f"{value / 1e6:g}")
        ax.xaxis.set_major_formatter(in_mpa)
        ax.yaxis.set_major_formatter(in_mpa)
        f0, c0 = (fractures[0][2], fractures[0][3]) if fractures else (0.0, 0.0)
        if inset_lines is None:
            inset_lines = [(theta, color) for _, theta, _, _ in fractures]
        _inset(ax, slip_band(eff, f0, c0), inset_lines)


def _criterion(ax, eff, f, c, color, k, x_left, circle, slipping) -> None:
    """The failure line of (f, c), the band of the circle that slips, and the
    legend's words on it (with the run's ``slipping`` contact points)."""
    phi = math.degrees(math.atan(f))
    xs = np.array([x_left, 0.0])
    ax.plot(
        xs,
        c - f * xs,
        linestyle=CRITERION_STYLES[k % len(CRITERION_STYLES)],
        color=color,
        lw=1.0,
        label=f"failure line $|\\tau| = c - f\\,\\sigma_n'$ "
        f"(f = {f:g}, c = {c / 1e6:g} MPa)",
    )
    band = slip_band(eff, f, c)
    if band.beta is None:
        text = f"f = {f:g}: no orientation slips under this circle's stress"
        if slipping:
            text += f"; {slipping} contact points of the run slip (red)"
        ax.plot([], [], " ", label=text)
        return
    centre, radius = circle
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


def _markers(ax, fractures, dir1, centre, radius, color) -> list[tuple]:
    """Each fracture's plane on the circle; numbered labels from
    NUMBERED_FROM on, else returns the labels [(anchor, text)] to place,
    fractures at one point sharing one ("fractures[0], fractures[1] (beta =
    45.0 deg)")."""
    labelled = []
    for label, theta, _, _ in fractures:
        beta = angle_to_sigma1(theta, dir1)
        px, py = _circle_point(centre, radius, beta)
        ax.plot([centre, px], [0.0, py], color=color, lw=0.6)
        ax.plot(px, py, "o", color=color, mec="k", ms=7, zorder=5)
        if label:  # else annotated with an earlier result at the same point
            labelled.append((label, theta, beta))
    if len(labelled) >= NUMBERED_FROM:
        _numbered_labels(ax, centre, radius, labelled, color)
        return []
    groups: dict[float, list[str]] = {}
    for label, _, beta in labelled:
        groups.setdefault(round(beta, 6), []).append(label)
    return [
        (
            tuple(float(v) for v in _circle_point(centre, radius, beta)),
            f"{', '.join(names)} ($\\beta$ = {beta:.1f} deg)",
        )
        for beta, names in groups.items()
    ]


def mohr_limits(stress, pore_pressure: float = 0.0, points=()) -> tuple[float, ...]:
    """(x0, x1, y0, y1) of the diagram [Pa]: the circle, zero and room above,
    and the (p_N, p_T) arrays of ``points``."""
    band = slip_band(effective_stress(stress, pore_pressure), 0.0)
    s1, radius = max(band.sigma1, 1.0), (band.sigma1 - band.sigma3) / 2.0
    centre = -(band.sigma1 + band.sigma3) / 2.0
    # room for the ring of numbered labels (1.25 R) left of the circle
    x0 = min(-1.08 * s1, centre - 1.35 * radius)
    x1, y1 = 0.25 * s1, max(1.5 * radius, 0.3 * s1)
    for pn, pt in points:
        if np.size(pn):
            x0 = min(x0, 1.05 * float(np.min(pn)))
            x1 = max(x1, 1.05 * float(np.max(pn)))
            y1 = max(y1, 1.1 * float(np.max(np.abs(pt))))
    return x0, x1, 0.0, y1


def mohr_figsize(limits, width: float = 8.0):
    """Figure size that fits the equal-aspect diagram of ``limits``
    (:func:`mohr_limits`), its title and legend."""
    x0, x1, y0, y1 = limits
    return width, (width - 0.8) * (y1 - y0) / (x1 - x0) + 2.0


def add_legend(fig) -> None:
    """One legend below the diagram for everything drawn on it."""
    fig.legend(loc="outside lower center", ncol=2, fontsize=7)


def spread(angles, gap: float, lo: float, hi: float) -> np.ndarray:
    """Angles moved apart to at least ``gap`` from each other, within [lo,
    hi], each as near its own as that allows (in the given order, which
    must be increasing).  When they cannot all fit, they are evenly spaced
    over [lo, hi]."""
    a = np.asarray(angles, dtype=float)
    n = a.size
    if n == 0:
        return a
    if (n - 1) * gap > hi - lo:
        return np.linspace(lo, hi, n)
    # positions relative to the minimum spacing: out[i] = b[i] + i * gap with
    # b non-decreasing, the nearest such b to a - i * gap (pool adjacent
    # violators), then clipped into the range
    target = a - gap * np.arange(n)
    blocks: list[list[float]] = []
    for value in target:
        blocks.append([value, 1.0])
        while len(blocks) > 1 and blocks[-2][0] > blocks[-1][0]:
            v2, w2 = blocks.pop()
            v1, w1 = blocks.pop()
            blocks.append([(v1 * w1 + v2 * w2) / (w1 + w2), w1 + w2])
    b = np.concatenate([[v] * int(w) for v, w in blocks])
    b = np.clip(b, lo, hi - gap * (n - 1))
    return b + gap * np.arange(n)


def _numbered_labels(ax, centre, radius, labelled, color) -> None:
    """Number the points on a ring outside the circle (leader lines to the
    points, numbers spread apart) and list the numbers in a key beside the
    diagram.  Points at one place share their number label ("3, 7")."""
    groups: dict[float, list] = {}
    for label, theta, beta in labelled:
        groups.setdefault(round(beta, 6), []).append((label, theta))
    betas = sorted(groups)  # right to left along the circle
    at = [2.0 * b for b in betas]  # polar angle of each point [deg]
    ring = spread(at, LABEL_GAP_DEG, 4.0, 176.0)
    for beta, angle, ring_angle in zip(betas, at, ring, strict=True):
        tag = ", ".join(label for label, _ in groups[beta])
        point = (
            centre + radius * math.cos(math.radians(angle)),
            radius * math.sin(math.radians(angle)),
        )
        place = (
            centre + 1.22 * radius * math.cos(math.radians(ring_angle)),
            1.22 * radius * math.sin(math.radians(ring_angle)),
        )
        ax.annotate(
            tag,
            point,
            xytext=place,
            fontsize=7.5,
            ha="center",
            va="center",
            bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": color, "lw": 0.6},
            arrowprops={"arrowstyle": "-", "color": "0.3", "lw": 0.6},
            zorder=6,
        )
    key = [
        f"{label}: $\\theta$ = {theta:.1f}, $\\beta$ = {beta:.1f} deg"
        for beta in betas
        for label, theta in groups[beta]
    ]
    ax.figure.legend(
        [ax.plot([], [], " ")[0]] * len(key),
        key,
        loc="outside right upper",
        fontsize=6.5,
        title="fracture: angle, to $\\sigma_1'$",
        title_fontsize=7,
        handlelength=0,
        handletextpad=0,
    )


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
        angle = math.radians(theta)
        ins.plot(
            [-math.cos(angle), math.cos(angle)],
            [-math.sin(angle), math.sin(angle)],
            color=color,
            lw=1.5,
        )
