"""Figures as the seed paper shows them (matplotlib, imported only here).

``plot_results(paths, out_dir)`` writes, for one result or several side by
side (one column per result):

- ``displacement``: u_x and u_y contours (paper Figs. 4, 6, 7, 10, 11, 14, 15);
- ``principal_stress``: the two principal stresses per element, tension
  positive, colour bar in Pa (Figs. 8, 9, 16, 17);
- ``deformed_mesh``: the mesh with magnified displacement; cut elements are
  drawn split along the fracture (result.vtu), so the jump shows (Fig. 3);
- ``slip``: |slip| along each fracture against the distance from its first
  point, every result overlaid (Fig. 12);
- ``mohr``: the Mohr-Coulomb diagram of the far-field stress with each
  fracture's point, the failure line and the band of orientations that slip
  (Fig. 13); the contact points of the run are drawn too, red where they
  slip; with a pore-pressure change, the effective stress where it changed
  at the final step, beside the in-situ circle;
- ``network`` (only when asked for, first result only): |slip| along every
  fracture of a network over the deformed split mesh, and the contact state.
- ``permeability`` (only when asked for, first result only, a case with
  ``[permeability]``): aperture and transmissivity along each fracture and
  the block's permeability ratio against the load (:mod:`xfemslip.plot.permeability`).

Every figure is saved as PNG and PDF.  Only the object-oriented API
(``matplotlib.figure.Figure``) is used: no pyplot, no GUI backend.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.collections import LineCollection, PolyCollection
from matplotlib.colors import Normalize
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator
from matplotlib.tri import Triangulation

from xfemslip.conventions import SLIP
from xfemslip.errors import UsageError
from xfemslip.plot.data import ResultData, distinct_labels, figure_data
from xfemslip.plot.mohr import (
    NUMBERED_FROM,
    add_legend,
    draw_circle,
    draw_mohr,
    mohr_figsize,
    mohr_limits,
)
from xfemslip.plot.permeability import figure_permeability
from xfemslip.plot.profile import figure_profile
from xfemslip.plot.style import (
    colourbar_label,
    legend_of_many,
    line_styles,
    place_labels,
    robust_norm,
)

logger = logging.getLogger(__name__)
# one line per figure written; ``xfemslip plot`` shows it even when quiet
progress = logging.getLogger("xfemslip.plot.figures.progress")

KINDS = (
    "displacement",
    "principal_stress",
    "deformed_mesh",
    "slip",
    "mohr",
    "profile",
)
FORMATS = ("png", "pdf")
PANEL = 3.6  # inches per panel
DPI = 110


# --------------------------------------------------------------------------- #
# Helpers
# --------------------------------------------------------------------------- #


def _grid(n_rows: int, n_cols: int, height: float = PANEL):
    """A figure and its (n_rows, n_cols) array of axes; with one column (one
    result) the rows are laid out side by side instead."""
    shape = (n_cols, n_rows) if n_cols == 1 else (n_rows, n_cols)
    fig = Figure(
        figsize=(PANEL * shape[1] + 0.9, height * shape[0] + 0.4), layout="constrained"
    )
    axes = fig.subplots(*shape, squeeze=False)
    return fig, (axes.T if n_cols == 1 else axes)


def _frame(ax, data: ResultData, title: str, fractures: bool = True) -> None:
    """Equal axes in metres, the fractures drawn, a title."""
    for fr in data.fractures if fractures else ():
        if fr.points.size:
            ax.plot(fr.points[:, 0], fr.points[:, 1], color="k", lw=0.6)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title, fontsize=9)


def _case_title(fig, results: Sequence[ResultData]) -> None:
    """The case name(s) above the panels, when the panels are labelled by
    something else (a sweep's parameters, or --label)."""
    names = list(dict.fromkeys(data.name for data in results if data.name))
    if names and any(data.label != data.name for data in results):
        fig.suptitle(", ".join(names), fontsize=10)


def _row_colorbar(fig, mappable, axes_row, label: str, extend="neither") -> None:
    """One colour bar for a row of panels that share a colour scale (beside
    the single panel of a row of one); ``extend``: arrows at the ends whose
    values lie beyond the range."""
    if len(axes_row) > 1:
        fig.colorbar(
            mappable,
            ax=list(axes_row),
            label=label,
            shrink=0.85,
            aspect=25,
            extend=extend,
        )
    else:
        fig.colorbar(mappable, ax=axes_row[0], label=label, shrink=0.8, extend=extend)


def _triangulation(data: ResultData):
    """(Triangulation, displacement (P, 2)): the split mesh when available."""
    if (
        data.vis_triangles is not None
        and data.vis_points is not None
        and data.vis_displacement is not None
    ):
        pts, tri, u = data.vis_points, data.vis_triangles, data.vis_displacement
    else:
        c = data.cells
        pts, u = data.points, data.displacement
        tri = np.concatenate([c[:, [0, 1, 2]], c[:, [0, 2, 3]]])
    return Triangulation(pts[:, 0], pts[:, 1], tri), u


# --------------------------------------------------------------------------- #
# Figures
# --------------------------------------------------------------------------- #


def figure_displacement(results: Sequence[ResultData]) -> Figure:
    """u_x (top row) and u_y (bottom row) contours [mm], one column per
    result; each row shares one colour scale, so the columns of a study
    compare by colour."""
    fig, axes = _grid(2, len(results))
    fields = [_triangulation(data) for data in results]
    for i, (comp, word) in enumerate(((0, "horizontal"), (1, "vertical"))):
        values = [1e3 * u[:, comp] for _, u in fields]
        lo = min(float(v.min()) for v in values)
        hi = max(float(v.max()) for v in values)
        levels = MaxNLocator(nbins=20).tick_values(lo, hi) if hi > lo else 20
        for j, data in enumerate(results):
            ax = axes[i, j]
            cs = ax.tricontourf(fields[j][0], values[j], levels=levels, cmap="viridis")
            # Filled contours are polygons side by side; anti-aliased, their
            # shared edges let the white background through as specks, most
            # along the fracture, where the split cells' triangles are
            # small.  An outline in the polygon's own colour closes them.
            cs.set_edgecolor("face")
            cs.set_linewidth(0.35)
            _frame(ax, data, f"{data.label}\n{word} displacement $u_{'xy'[comp]}$")
        label = f"{word} displacement $u_{'xy'[comp]}$ [mm]"
        _row_colorbar(fig, cs, axes[i, :], label)
    _case_title(fig, results)
    return fig


def figure_principal(results: Sequence[ResultData]) -> Figure:
    """Principal stresses per element [MPa], tension positive; each row
    shares one colour scale across the results, from the 1st to the 99th
    percentile of its values (:func:`xfemslip.plot.style.robust_norm`: the
    stress singularity at a tip does not set it, a nearly uniform field is
    not magnified into colour), white at zero when the range holds it."""
    fig, axes = _grid(2, len(results))
    rows = (
        (1, r"$\sigma_{min}$ (most compressive)"),
        (0, r"$\sigma_{max}$ (least compressive)"),
    )
    for i, (col, title) in enumerate(rows):
        values = [1e-6 * data.principal[:, col] for data in results]
        scale = robust_norm(np.concatenate(values))
        for j, data in enumerate(results):
            coll = PolyCollection(
                data.points[data.cells],
                array=values[j],
                cmap=scale.cmap,
                norm=scale.norm,
                edgecolors="face",
                linewidths=0.1,
            )
            ax = axes[i, j]
            ax.add_collection(coll)
            ax.margins(0.0)
            ax.autoscale_view()
            _frame(ax, data, f"{data.label}\n{title}")
        label = colourbar_label(f"{title} [MPa], tension positive", scale)
        _row_colorbar(fig, coll, axes[i, :], label, scale.extend)
    _case_title(fig, results)
    return fig


def auto_scale(data: ResultData) -> float:
    """Magnification: the largest slip drawn as 5 % of the domain, but no
    displacement larger than 15 % of it (and never below 1)."""
    size = float(np.ptp(data.points, axis=0).max())
    u_max = float(np.abs(data.displacement).max()) or 1.0
    slip = max(
        (float(np.abs(f.slip).max()) for f in data.fractures if f.slip.size),
        default=0.0,
    )
    scale = 0.05 * size / slip if slip > 0.0 else 0.05 * size / u_max
    return max(1.0, min(scale, 0.15 * size / u_max))


# Mesh lines closer than this many pixels (at DPI, on a panel PANEL wide)
# beat with the pixel grid into moire: the overview draws every k-th line.
MESH_LINE_PIXELS = 10.0


def _cell_size(data: ResultData) -> float:
    """The median edge length of the (undeformed) elements [m]."""
    c = data.points[data.cells]
    return float(np.median(np.linalg.norm(c[:, 1] - c[:, 0], axis=1)))


def _line_stride(data: ResultData) -> int:
    """Every how many grid lines the overview draws (1: all)."""
    size = float(np.ptp(data.points, axis=0).max())
    spacing = PANEL * DPI * _cell_size(data) / size
    return max(1, math.ceil(MESH_LINE_PIXELS / spacing))


def _thinned_edges(points: np.ndarray, edges: np.ndarray, h: float, every: int):
    """The edges of ``edges`` (E, 2) to draw with every ``every``-th grid
    line: an edge along x or y is kept when it lies on a kept grid line
    (grid spacing ``h``); the edges of the pieces of cut elements along a
    fracture are never axis-aligned and are all kept."""
    if every == 1:
        return edges
    a, b = points[edges[:, 0]], points[edges[:, 1]]
    tol = 1e-6 * h
    origin = points.min(axis=0)

    def on_kept(coord: np.ndarray, axis: int) -> np.ndarray:
        k = (coord - origin[axis]) / h
        return (np.abs(k - np.round(k)) < 1e-6) & (np.round(k) % every == 0)

    horizontal = np.abs(a[:, 1] - b[:, 1]) < tol
    vertical = np.abs(a[:, 0] - b[:, 0]) < tol
    keep = (horizontal & on_kept(a[:, 1], 1)) | (vertical & on_kept(a[:, 0], 0))
    keep |= ~horizontal & ~vertical
    return edges[keep]


def _draw_mesh(ax, data: ResultData, factor: float, every: int = 1) -> str:
    """The deformed element outlines (every ``every``-th grid line); returns
    a note for the title."""
    if (
        data.vis_edges is None
        or data.vis_points is None
        or data.vis_displacement is None
    ):
        moved = data.points + factor * data.displacement
        h = _cell_size(data)
        cells = data.cells
        edges = np.concatenate([cells[:, [k, (k + 1) % 4]] for k in range(4)])
        edges = _thinned_edges(data.points, np.unique(np.sort(edges), axis=0), h, every)
        ax.add_collection(
            LineCollection(list(moved[edges]), colors="0.25", linewidths=0.3)
        )
        return "no result.vtu: the jump is not shown"
    moved = data.vis_points + factor * data.vis_displacement
    edges = _thinned_edges(data.vis_points, data.vis_edges, _cell_size(data), every)
    ax.add_collection(LineCollection(list(moved[edges]), colors="0.2", linewidths=0.35))
    return "cut elements split along the fracture"


def _zoom_box(data: ResultData, factor: float):
    """(x0, x1, y0, y1) around the first fracture's middle, deformed, its
    edges half-way between grid lines (a mesh line along the frame would
    look like a second frame)."""
    fr = next((f for f in data.fractures if f.points.size), None)
    size = float(np.ptp(data.points, axis=0).max())
    centre = fr.points[len(fr.points) // 2] if fr is not None else data.points.mean(0)
    near = np.argmin(np.linalg.norm(data.points - centre, axis=1))
    h = _cell_size(data)
    origin = data.points.min(axis=0)
    half = max(0.1 * size, 2.0 * h)
    lo = origin + (np.floor((centre - half - origin) / h) + 0.5) * h
    hi = origin + (np.ceil((centre + half - origin) / h) - 0.5) * h
    shift = factor * data.displacement[near]
    (x0, y0), (x1, y1) = lo + shift, hi + shift
    return x0, x1, y0, y1


def _every(k: int) -> str:
    """The words for every k-th: "every other", "every 3rd", "every 4th"."""
    if k == 2:
        return "every other"
    teen = k % 100 in (11, 12, 13)
    suffix = "th" if teen else {1: "st", 2: "nd", 3: "rd"}.get(k % 10, "th")
    return f"every {k}{suffix}"


def figure_deformed(
    results: Sequence[ResultData], scale: float | None = None
) -> Figure:
    """The deformed mesh, displacement magnified, and a zoom on the fracture's
    middle; cut elements are drawn split so the jump shows (paper Fig. 3).
    The overview draws every k-th grid line when the lines would lie closer
    than MESH_LINE_PIXELS (moire); the zoom draws them all."""
    fig, axes = _grid(2, len(results), height=PANEL + 0.3)
    for j, data in enumerate(results):
        factor = scale if scale is not None else auto_scale(data)
        for i, zoom in enumerate((False, True)):
            ax = axes[i, j]
            every = 1 if zoom else _line_stride(data)
            note = _draw_mesh(ax, data, factor, every)
            if zoom:
                x0, x1, y0, y1 = _zoom_box(data, factor)
                ax.set_xlim(x0, x1)
                ax.set_ylim(y0, y1)
                ax.locator_params(nbins=4)
                title = f"{data.label}\nzoom on the middle of the fracture"
            else:
                ax.autoscale_view()
                lines = "" if every == 1 else f", {_every(every)} mesh line"
                title = (
                    f"{data.label}\ndeformed mesh, displacement x {factor:.3g}"
                    f"\n({note}{lines})"
                )
            _frame(ax, data, title, fractures=False)
    return fig


def figure_slip(results: Sequence[ResultData]) -> Figure:
    """The |slip| that slid [mm] along every fracture against arc length
    (solid; dashed: the tangential jump, which adds the elastic give of the
    penalty), results overlaid; one style per result (or per fracture of a
    single result): :func:`xfemslip.plot.style.line_styles`, neighbours in
    different hues, repeated hues in different dashes."""
    fig = Figure(figsize=(6.4, 4.2), layout="constrained")
    ax = fig.subplots()
    many = len(results) if len(results) > 1 else max(len(results[0].fractures), 1)
    styles = line_styles(many)
    curves = []  # (line, label, largest slip, its point, number) per curve
    for k, data in enumerate(results):
        for fr in data.fractures:
            # the title names the case: one result's fractures by number
            if len(data.fractures) == 1:
                label = data.label
            elif len(results) == 1:
                label = f"fracture {fr.index}"
            else:
                label = f"{data.label}, fracture {fr.index}"
            s = fr.s - fr.s.min() if fr.s.size else fr.s
            # one result with several fractures (a network): one style each
            style = styles[(k if len(results) > 1 else fr.index) % len(styles)]
            colour = style["color"]
            mm = 1e3 * np.abs(fr.slid)
            (line,) = ax.plot(
                s, mm, lw=1.4, color=colour, ls=style["linestyle"], label=label
            )
            if mm.size:
                top = int(np.argmax(mm))
                number = f"{fr.index}" if len(results) == 1 else f"{k}:{fr.index}"
                curves.append((line, label, mm[top], (s[top], mm[top]), number))
            ax.plot(s, 1e3 * np.abs(fr.slip), lw=0.7, ls=(0, (2, 2)), color=colour)
            in_slip = fr.state == SLIP
            ax.plot(s[in_slip], mm[in_slip], ".", ms=3, color=line.get_color())
    ax.set_xlabel("distance from the first tip along the fracture x_0 [m]")
    ax.set_ylabel("slip that slid [mm] (thin dotted: jump |[[u]] . t|)")
    names = ", ".join(dict.fromkeys(data.name for data in results if data.name))
    ax.set_title(
        f"{names}\nslip along the fracture (dots: points in slip)", fontsize=10
    )
    ax.grid(alpha=0.3)
    # inside the axes, over no curve; beyond six entries the smaller curves
    # are numbered at their largest slip
    legend_of_many(ax, curves, fontsize=7 if len(curves) > 3 else 8)
    return fig


STATE_COLOURS = {0: "0.6", 1: "tab:blue", 2: "tab:red"}  # open, stick, slip


def fracture_pieces(fr) -> tuple[np.ndarray, np.ndarray]:
    """Segments (S, 2, 2) covering a fracture's line point by point, and the
    contact point (S,) each one belongs to: point k owns the line from the
    midpoint towards its previous point to the midpoint towards its next, so
    consecutive pieces meet end to end (no gap shows the background) and a
    point's colour covers its share of the line.  The line is broken where
    two points lie more than 4 times the usual spacing apart (the 90th
    percentile: a small spacing near a junction or a tip does not count)."""
    p = np.asarray(fr.points, dtype=float).reshape(-1, 2)
    if len(p) < 2:
        return np.zeros((0, 2, 2)), np.zeros(0, np.int64)
    gap = np.linalg.norm(p[1:] - p[:-1], axis=1)
    joined = gap <= 4.0 * np.percentile(gap, 90)
    mid = 0.5 * (p[1:] + p[:-1])
    left = np.vstack([p[:1], np.where(joined[:, None], mid, p[1:])])
    right = np.vstack([np.where(joined[:, None], mid, p[:-1]), p[-1:]])
    pieces = np.concatenate([np.stack([left, p], axis=1), np.stack([p, right], axis=1)])
    owner = np.concatenate([np.arange(len(p)), np.arange(len(p))])
    keep = np.linalg.norm(pieces[:, 1] - pieces[:, 0], axis=1) > 0.0
    return pieces[keep], owner[keep]


def figure_network(data: ResultData, scale: float | None = None) -> Figure:
    """A fracture network: the |slip| that slid [mm] along every fracture over
    the deformed, split mesh (left) and the contact state of every point (right),
    each fracture numbered as in the case file."""
    fig, axes = _grid(1, 2)
    ax_slip, ax_state = axes[0]
    factor = scale if scale is not None else auto_scale(data)
    _draw_mesh(ax_slip, data, factor, _line_stride(data))
    slips = [np.abs(f.slid) for f in data.fractures if f.slid.size]
    top = max((float(v.max()) for v in slips), default=0.0) or 1.0
    norm = Normalize(0.0, 1e3 * top)
    mappable = None
    numbers = []
    for fr in data.fractures:
        pieces, owner = fracture_pieces(fr)
        if not pieces.size:
            continue
        # drawn where the deformed mesh has moved it (nearest node)
        ends = pieces.reshape(-1, 2)
        near = np.argmin(
            np.linalg.norm(ends[:, None, :] - data.points[None], axis=2), axis=1
        )
        moved = pieces + factor * data.displacement[near].reshape(pieces.shape)
        mappable = LineCollection(
            list(moved),
            array=1e3 * np.abs(fr.slid[owner]),
            cmap="plasma",
            norm=norm,
            linewidths=2.2,
            capstyle="round",
        )
        ax_slip.add_collection(mappable)
        colours = [STATE_COLOURS.get(int(c), "k") for c in fr.state[owner]]
        ax_state.add_collection(
            LineCollection(
                list(pieces), colors=colours, linewidths=2.2, capstyle="butt"
            )
        )
        numbers.append(_number_label(fr))
    fig.colorbar(mappable, ax=ax_slip, label="|slip| that slid [mm]", shrink=0.8)
    ax_slip.autoscale_view()
    _frame(
        ax_slip,
        data,
        f"{data.label}\n|slip| that slid, on the deformed, split mesh (x {factor:.3g})",
        fractures=False,
    )
    b = data.points
    ax_state.set_xlim(b[:, 0].min(), b[:, 0].max())
    ax_state.set_ylim(b[:, 1].min(), b[:, 1].max())
    for code, name in ((2, "slip"), (1, "stick"), (0, "open")):
        ax_state.plot([], [], color=STATE_COLOURS[code], lw=2.2, label=name)
    ax_state.legend(fontsize=7, loc="lower right")
    _frame(ax_state, data, f"{data.label}\ncontact state", fractures=False)
    lines = [fr.points for fr in data.fractures if len(fr.points) > 1]
    place_labels(
        ax_state,
        [(at, text) for at, text, _ in numbers],
        directions=[d for _, _, d in numbers],
        avoid=lines,
        join_within=0.0,
    )
    return fig


def _number_label(fr) -> tuple:
    """(anchor, number, direction) of a fracture's number: a third of the
    way along it (crossing fractures often meet at their middles), beside
    its line."""
    p = np.asarray(fr.points, dtype=float)
    k = len(p) // 3
    direction = p[-1] - p[0]
    return p[k], str(fr.index), direction


def _point_labels(results: Sequence[ResultData]) -> dict:
    """Label of each (result, fracture) point on the Mohr circle; results whose
    points coincide (same stress and angle) share one label, on the first."""
    labels: dict[tuple[int, int], str] = {}
    first: dict[tuple, tuple[int, int]] = {}  # key -> the label's owner
    for k, data in enumerate(results):
        for f in data.fractures:
            if len(results) == 1:
                # a network is numbered on the diagram, with a key
                labels[k, f.index] = (
                    str(f.index)
                    if len(data.fractures) >= NUMBERED_FROM
                    else f"fracture {f.index}, $\\theta$ = {f.theta:.1f} deg"
                )
                continue
            key = (data.stress_state, round(f.theta % 180.0, 9))
            if key in first:
                labels[k, f.index] = ""
                labels[first[key]] += f", {data.label}"
            else:
                first[key] = (k, f.index)
                labels[k, f.index] = data.label
    return labels


def _mohr_state(data: ResultData) -> tuple[tuple, float]:
    """(stress, pore pressure) of a result's circle: with a pore-pressure
    change the effective stress where it changed at the final step (the
    state its fractures' Coulomb law sees), else the far field."""
    if data.changed_stress is not None:
        return data.changed_stress, 0.0
    return data.stress_state, data.pore_pressure


def _slipped_text(results: Sequence[ResultData]) -> str:
    """Which fractures (of one result) or results (of several) have contact
    points in slip at the final step."""
    slipped = [
        [f.index for f in data.fractures if np.any(f.state == SLIP)] for data in results
    ]
    if len(results) > 1:
        who = [data.label for data, s in zip(results, slipped, strict=True) if s]
        return "slip in: " + ", ".join(who) if who else "no result slips"
    (mine,) = slipped
    if len(mine) > 1:
        return "fractures " + ", ".join(str(i) for i in mine) + " slip"
    return f"fracture {mine[0]} slips" if mine else "no fracture slips"


def figure_mohr(results: Sequence[ResultData]) -> Figure:
    """The Mohr-Coulomb diagram of every result's stress and fractures; a
    circle per distinct stress state, a failure line per distinct (f, c),
    every contact point of the final step (red where it slips).

    A result with a pore-pressure change is drawn at the end: its circle is
    sigma + p I where the pressure changed (:func:`_mohr_state`), the
    in-situ circle beside it in grey, and its fractures are their contact
    points (a plane on the circle is not where a fracture outside that
    region is)."""
    contact = [
        [(f.normal_traction, f.shear_traction, f.state) for f in data.fractures]
        for data in results
    ]
    limits = mohr_limits(
        *_mohr_state(results[0]),
        points=[(pn, pt) for each in contact for pn, pt, _ in each],
    )
    fig = Figure(figsize=mohr_figsize(limits), layout="constrained")
    ax = fig.subplots()
    circles: set[tuple] = set()
    criteria: set[tuple] = set()
    labels = _point_labels(results)
    pending: list = []  # point labels, placed once the layout is final
    cloud: list = []  # fractures' numbers at their contact points
    for k, data in enumerate(results):
        stress, pore = _mohr_state(data)
        changed = data.changed_stress is not None
        fractures = [
            (labels[k, f.index], f.theta, f.friction, f.cohesion)
            for f in data.fractures
        ]
        keys = {(stress, f, c) for _, _, f, c in fractures}
        if (
            changed
            and data.in_situ_stress is not None
            and data.in_situ_stress not in circles
        ):
            draw_circle(ax, data.in_situ_stress, "0.6", "in situ", lw=0.9, ls=":")
            circles.add(data.in_situ_stress)
        draw_mohr(
            ax,
            stress,
            pore,
            fractures=fractures,
            contact=contact[k],
            color=f"C{k % 10}",
            first=k == 0,
            circle=stress not in circles,
            criterion=not keys <= criteria,
            inset_lines=[
                (f.theta, f"C{j % 10}")
                for j, other in enumerate(results)
                for f in other.fractures
            ],
            markers=not changed,
            circle_label=(
                f"where the pore pressure changed, final step (median of "
                f"{data.changed_cells} cells)"
                if changed
                else "Mohr circle"
            ),
            limits=limits,
            pending=pending,
        )
        if changed and len(results) == 1 and len(fractures) < NUMBERED_FROM:
            cloud = _cloud_labels(data)
        circles.add(stress)
        criteria |= keys
    names = ", ".join(dict.fromkeys(data.name for data in results if data.name))
    if results[0].changed_stress is not None:
        what = "final step, effective stresses sigma + p I"
    else:
        what = (
            f"far field: {results[0].stress_source}; pore pressure "
            f"{results[0].pore_pressure / 1e6:g} MPa"
        )
    ax.set_title(
        f"{names}\nMohr-Coulomb diagram ({what}; tension positive)\n"
        f"{_slipped_text(results)}",
        fontsize=9,
    )
    add_legend(fig)
    place_labels(ax, pending)
    place_labels(
        ax, cloud, prefix=("fracture ", "fractures "), join_within=CLOUD_JOIN_PIXELS
    )
    return fig


# fractures whose most-sheared contact points lie this close share a label
CLOUD_JOIN_PIXELS = 12.0


def _cloud_labels(data: ResultData) -> list[tuple]:
    """[(anchor, text)]: each fracture's name at its contact point of
    largest |p_T| (fractures whose points lie together share one label,
    :func:`xfemslip.plot.style.place_labels`)."""
    out = []
    for f in data.fractures:
        if not f.shear_traction.size:
            continue
        k = int(np.argmax(np.abs(f.shear_traction)))
        at = (float(f.normal_traction[k]), float(abs(f.shear_traction[k])))
        out.append((at, str(f.index)))
    return out


# --------------------------------------------------------------------------- #
# Entry point
# --------------------------------------------------------------------------- #


def _save_all(out_dir: Path, makers: dict, formats, dpi=DPI) -> list[Path]:
    """Write ``<out_dir>/<name>.<fmt>`` for each figure ``makers[name]()`` and
    format, as one set (:func:`xfemslip.io.fileset.replace_files`: no
    figure of an earlier command is left beside the new ones half-replaced);
    returns the paths in the order of ``makers`` and ``formats``."""
    from xfemslip.io.fileset import replace_files

    figures: dict[str, Figure] = {}
    count = len(makers) * len(formats)
    done: list[str] = []

    def writer(name: str, fmt: str):
        def write(tmp: Path) -> None:
            start = time.perf_counter()
            if name not in figures:
                figures[name] = makers[name]()
            figures[name].savefig(tmp, format=fmt, dpi=dpi, bbox_inches="tight")
            done.append(name)
            # a large result takes seconds per figure
            progress.info(
                "figure %d/%d: %s.%s (%.1f s)",
                len(done),
                count,
                name,
                fmt,
                time.perf_counter() - start,
            )

        return write

    paths = {
        Path(out_dir) / f"{name}.{fmt}": writer(name, fmt)
        for name in makers
        for fmt in formats
    }
    written = set(replace_files(paths))
    return [path for path in paths if path in written]


def plot_screen(
    out_dir,
    stress,
    pore_pressure,
    friction,
    cohesion,
    fractures,
    formats: Sequence[str] = FORMATS,
) -> list[Path]:
    """The Mohr diagram of ``xfemslip screen``: ``<out_dir>/mohr.<fmt>``;
    ``fractures`` = [(label, theta [deg], f, c)]."""
    return _save_all(
        Path(out_dir),
        {
            "mohr": lambda: figure_screen(
                stress, pore_pressure, friction, cohesion, fractures
            )
        },
        formats,
    )


def figure_screen(stress, pore_pressure, friction, cohesion, fractures) -> Figure:
    """The Mohr diagram of :func:`plot_screen`."""
    fig = Figure(
        figsize=mohr_figsize(mohr_limits(stress, pore_pressure)), layout="constrained"
    )
    ax = fig.subplots()
    if not fractures:
        fractures = [("", 0.0, friction, cohesion)]
        draw_mohr(ax, stress, pore_pressure, fractures=[], first=True)
        draw_mohr(
            ax, stress, pore_pressure, fractures=fractures, first=False, circle=False
        )
    else:
        pending: list = []
        draw_mohr(ax, stress, pore_pressure, fractures=fractures, pending=pending)
    ax.set_title(
        f"Mohr-Coulomb screening (pore pressure {pore_pressure / 1e6:g} MPa; "
        "tension positive)",
        fontsize=9,
    )
    add_legend(fig)
    if fractures and pending:
        place_labels(ax, pending)
    return fig


def plot_results(
    paths: Sequence[str | Path],
    out_dir: str | Path,
    *,
    kinds: Sequence[str] = KINDS,
    formats: Sequence[str] = FORMATS,
    labels: Sequence[str] | None = None,
    scale: float | None = None,
    dpi: float = DPI,
) -> list[Path]:
    """Read the results and write the figures; returns the files written.

    ``kinds`` from KINDS, ``formats`` "png" / "pdf", ``labels`` one per result
    (default: the case's name, or a sweep case's parameters; runs of one case
    in several folders are told apart by their folders), ``scale`` the
    deformed mesh's magnification (default :func:`auto_scale`), ``dpi`` of
    the PNG files."""
    if labels and len(labels) != len(paths):
        raise UsageError(f"got {len(labels)} labels for {len(paths)} results")
    results = [
        figure_data(p, labels[i] if labels else None) for i, p in enumerate(paths)
    ]
    if not labels:
        distinct_labels(results)
    makers = {
        "displacement": lambda: figure_displacement(results),
        "principal_stress": lambda: figure_principal(results),
        "deformed_mesh": lambda: figure_deformed(results, scale),
        "slip": lambda: figure_slip(results),
        "mohr": lambda: figure_mohr(results),
        # not in KINDS (asked for by name): one figure per result
        "network": lambda: figure_network(results[0], scale),
    }
    if "profile" in kinds:  # of one result: the first
        makers["profile"] = lambda: figure_profile(paths[0], results[0].label)
    if "permeability" in kinds:  # drawn now: a result without one is refused
        figure = figure_permeability(paths[0], results[0].label)
        makers["permeability"] = lambda: figure
    drawn = {}
    for kind in kinds:
        if kind == "profile" and len(results) > 1:
            logger.info("profile figure: drawn for one result at a time")
            continue
        if kind in ("slip", "mohr", "profile") and not any(
            r.fractures for r in results
        ):
            logger.info("no fracture: %s figure skipped", kind)
            continue
        drawn[kind] = makers[kind]
    return _save_all(Path(out_dir), drawn, formats, dpi)
