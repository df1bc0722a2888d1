"""The picture of a case before it runs (the seed paper's Fig. 5): the
domain and its mesh, the fractures numbered as in the case file, the
rock units, the boundary conditions of each edge and the loads.

``figure_case(spec)`` draws a validated :class:`~xfemslip.case.specs.CaseSpec`
(nothing is solved); ``plot_case`` writes it (``xfemslip plot --case``).

Edges, as the solver reads them (``xfemslip.fem.boundary``):

- a prescribed displacement component of zero is drawn as rollers (a fixed
  ux: small triangles pointing at the edge along x), both components as a
  clamped edge;
- a non-zero prescribed displacement as arrows of the final displacement,
  with its value in mm;
- a traction edge, and the free component of a displacement edge that
  carries the traction, as arrows of the final traction sigma . n (outward
  normal n, tension positive), with its value in MPa; a free edge is marked
  "free".
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle

from xfemslip.case.specs import CaseSpec
from xfemslip.fem.zones import build_zones
from xfemslip.geometry.regions import edges
from xfemslip.plot.style import line_styles, place_labels

__all__ = ["figure_case", "plot_case"]

OUTWARD = {
    "bottom": (0.0, -1.0),
    "top": (0.0, 1.0),
    "left": (-1.0, 0.0),
    "right": (1.0, 0.0),
}
SYMBOLS = 9  # rollers or arrows per edge
MAX_MESH_LINES = 160  # per direction; more are thinned (every k-th drawn)


def _edge_points(spec: CaseSpec, name: str, n: int) -> np.ndarray:
    """n points spread along an edge (not at the corners)."""
    box, (w, h) = spec.box, spec.size
    t = (np.arange(n) + 0.5) / n
    if name in ("bottom", "top"):
        y = box.y0 if name == "bottom" else box.y1
        return np.column_stack([box.x0 + t * w, np.full(n, y)])
    x = box.x0 if name == "left" else box.x1
    return np.column_stack([np.full(n, x), box.y0 + t * h])


def _mesh_lines(ax, spec: CaseSpec) -> str:
    """The mesh lines (every k-th beyond MAX_MESH_LINES); returns a note."""
    x, y = spec.mesh.x, spec.mesh.y
    step = max(1, int(np.ceil(max(len(x), len(y)) / MAX_MESH_LINES)))
    xs, ys = x[::step], y[::step]
    segments = [[(v, y[0]), (v, y[-1])] for v in xs]
    segments += [[(x[0], v), (x[-1], v)] for v in ys]
    ax.add_collection(LineCollection(segments, colors="0.75", linewidths=0.3))
    cells = f"{len(x) - 1} x {len(y) - 1} elements"
    return cells if step == 1 else f"{cells} (every {step}th line drawn)"


# raster of the zone picture (cells per side) in the case figure
ZONE_RASTER = 400


def _regions(ax, spec: CaseSpec) -> list[str]:
    """The rock units (filled by zone, edges drawn) and where the pore
    pressure changes; legend notes."""
    notes = []
    pore = spec.pore_pressure
    if spec.units:
        zones = build_zones(spec)
        box = spec.box
        gx = np.linspace(box.x0, box.x1, ZONE_RASTER)
        gy = np.linspace(box.y0, box.y1, ZONE_RASTER)
        X, Y = np.meshgrid(gx, gy)
        Z = zones.at(np.column_stack([X.ravel(), Y.ravel()])).reshape(X.shape)
        colours = matplotlib.colormaps["Pastel1"](np.arange(zones.n) % 9)
        colours[0] = (1.0, 1.0, 1.0, 0.0)  # the host: not filled
        ax.imshow(
            colours[Z],
            origin="lower",
            extent=box,
            interpolation="nearest",
            aspect="auto",
            zorder=0,
        )
        for k in range(1, zones.n):
            label = (
                f"{zones.names[k]}: E = {zones.E[k] / 1e9:g} GPa, "
                f"\u03bd = {zones.nu[k]:g}"
            )
            if pore is not None and zones.change[k] != 0.0:
                label += f"; \u0394p = {zones.change[k] / 1e6:g} MPa"
            ax.add_patch(Rectangle((0, 0), 0, 0, fc=colours[k], label=label))
        for unit in spec.units:
            for _, p, q in edges(unit.region, box):
                ax.plot([p[0], q[0]], [p[1], q[1]], color="0.35", lw=0.8)
    if pore is not None:
        where = "everywhere" if pore.region == "all" else f"in {pore.region}"
        if pore.field is not None:
            change = f"\u0394p from {pore.field.file.name}"
        else:
            assert pore.change is not None  # without a field, a uniform change
            change = f"\u0394p = {pore.change / 1e6:g} MPa {where}"
        notes.append(
            f"pore pressure p0 = {pore.initial / 1e6:g} MPa, change "
            + change
            + f" (Biot {pore.biot:g})"
        )
    return notes


def _fractures(ax, spec: CaseSpec) -> None:
    """Each fracture in its own style (:func:`xfemslip.plot.style.line_styles`:
    neighbours in different hues, repeated hues in different dashes)."""
    styles = line_styles(len(spec.fractures))
    for k, fr in enumerate(spec.fractures):
        p = np.asarray(fr.points)
        style = styles[k]
        ax.plot(
            p[:, 0],
            p[:, 1],
            color=style["color"],
            ls=style["linestyle"],
            lw=2.0,
            solid_capstyle="round",
        )
    if spec.fractures:
        frictions = sorted({fr.friction for fr in spec.fractures})
        text = ", ".join(f"{f:g}" for f in frictions)
        ax.plot(
            [],
            [],
            color=styles[0]["color"],
            lw=2.0,
            label=f"fractures (numbered), f = {text}",
        )


def _number_fractures(ax, spec: CaseSpec) -> None:
    """Each fracture's number beside its line, a third of the way along it
    (crossing fractures often meet at their middles), on no other line or
    number (:func:`xfemslip.plot.style.place_labels`)."""
    lines = [np.asarray(fr.points, dtype=float) for fr in spec.fractures]
    place_labels(
        ax,
        [
            (p[0] + (p[-1] - p[0]) / 3.0, str(fr.index))
            for p, fr in zip(lines, spec.fractures, strict=True)
        ],
        directions=[p[-1] - p[0] for p in lines],
        avoid=lines,
        join_within=0.0,
        fontsize=7 if len(lines) > 10 else 8,
    )


def _arrows(ax, points, vectors, colour, label: str | None) -> None:
    ax.quiver(
        points[:, 0],
        points[:, 1],
        vectors[:, 0],
        vectors[:, 1],
        color=colour,
        angles="xy",
        scale_units="xy",
        scale=1.0,
        width=0.004,
        label=label,
        zorder=4,
    )


# marker pointing at each edge from outside
TOWARDS = {"bottom": "^", "top": "v", "left": ">", "right": "<"}


def _boundary(ax, spec: CaseSpec) -> list[str]:
    """Symbols of each edge's condition; returns one note per edge."""
    notes, size = [], 0.07 * max(spec.size)
    stress = spec.loading.stress
    S = None
    if stress is not None:
        S = np.array([[stress[0], stress[2]], [stress[2], stress[1]]])
    tractions, used = {}, set()
    for name, outward in OUTWARD.items():
        edge = getattr(spec.boundary, name)
        normal = np.array(outward)
        points = _edge_points(spec, name, SYMBOLS)
        loaded = np.zeros(2, bool)  # components that carry sigma . n
        words = []
        if edge.kind == "displacement":
            values = np.asarray(edge.values, float)
            fixed = ~np.isnan(values).all(axis=0)
            final = np.where(fixed, np.nanmean(np.nan_to_num(values), axis=0), 0.0)
            zero = fixed & np.all(np.nan_to_num(values) == 0.0, axis=0)
            for comp in np.nonzero(fixed)[0]:
                value = "0" if zero[comp] else f"{1e3 * final[comp]:.3g} mm"
                words.append(f"u{'xy'[comp]} = {value}")
            if zero.any():
                clamped = zero.all()
                ax.plot(
                    *(points + 0.025 * max(spec.size) * normal).T,
                    TOWARDS[name],
                    ls="",
                    ms=6,
                    color="k",
                    mfc="k" if clamped else "white",
                    zorder=5,
                )
                used.add("fixed" if clamped else "rollers")
            moved = fixed & ~zero
            if moved.any():
                vec = np.where(moved, final, 0.0)
                arrow = size * vec / np.linalg.norm(vec)
                _arrows(ax, points, np.tile(arrow, (SYMBOLS, 1)), "tab:green", None)
                used.add("moved")
            if edge.traction:
                loaded = ~fixed
        elif edge.kind == "traction":
            loaded[:] = True
        if loaded.any() and S is not None:
            t = (S @ normal) * loaded
            tractions[name] = t
            words.append(
                f"traction \u03c3\u00b7n = ({t[0] / 1e6:.3g}, {t[1] / 1e6:.3g}) MPa"
            )
        notes.append(f"{name:>6}: " + (", ".join(words) or "free"))
    top = max((np.linalg.norm(t) for t in tractions.values()), default=0.0)
    label: str | None = "traction \u03c3\u00b7n of loading.stress"
    for name, t in tractions.items():
        if top == 0.0 or not np.any(t):
            continue
        arrow = size * t / top
        points = _edge_points(spec, name, SYMBOLS)
        # compression (t . n < 0) pushes on the edge: the arrow ends on it
        base = points - arrow if t @ np.array(OUTWARD[name]) < 0 else points
        _arrows(ax, base, np.tile(arrow, (SYMBOLS, 1)), "tab:red", label)
        label = None
    if "rollers" in used:
        ax.plot([], [], "^", ls="", color="k", mfc="white", label="rollers (u = 0)")
    if "fixed" in used:
        ax.plot([], [], "^", ls="", color="k", label="fixed (ux = uy = 0)")
    if "moved" in used:
        ax.plot([], [], "-", color="tab:green", label="prescribed displacement")
    return notes


def figure_case(spec: CaseSpec) -> Figure:
    """The geometry, mesh, fractures, boundary conditions and loads of a case."""
    fig = Figure(figsize=(9.6, 7.0), layout="constrained")
    ax = fig.subplots()
    (x0, y0), (w, h) = spec.origin, spec.size
    mesh_note = _mesh_lines(ax, spec)
    ax.add_patch(Rectangle((x0, y0), w, h, fc="none", ec="k", lw=1.2))
    notes = _regions(ax, spec)
    _fractures(ax, spec)
    notes = _boundary(ax, spec) + notes
    loading = spec.loading
    if loading.initial_stress is not None:
        notes.append(
            "initial stress (xx, yy, xy) = ("
            + ", ".join(f"{v / 1e6:g}" for v in loading.initial_stress)
            + ") MPa"
        )
    if loading.stress is not None:
        notes.append(
            "far-field stress (xx, yy, xy) = ("
            + ", ".join(f"{v / 1e6:g}" for v in loading.stress)
            + f") MPa, reached in {loading.steps} load step(s); tension positive"
        )
    mat = spec.material
    notes.append(
        f"E = {mat.E / 1e9:g} GPa, \u03bd = {mat.nu:g}, "
        f"{mat.model.replace('_', ' ')}; {mesh_note}"
    )
    margin = 0.12 * max(w, h)
    ax.set_xlim(x0 - margin, x0 + w + margin)
    ax.set_ylim(y0 - margin, y0 + h + margin)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(
        f"{spec.name}\ngeometry, mesh, boundary conditions and loads", fontsize=10
    )
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7)
    # below the axes; savefig(bbox_inches="tight") takes it in
    ax.text(
        0.0,
        -0.09,
        "\n".join(notes),
        transform=ax.transAxes,
        fontsize=7,
        va="top",
        family="monospace",
    )
    _number_fractures(ax, spec)
    return fig


def plot_case(
    spec, out_dir: Path, formats: Sequence[str] = ("png", "pdf"), dpi: float = 110.0
) -> list[Path]:
    """Write ``<out_dir>/<case file stem>.<fmt>`` for each format, as one set."""
    from xfemslip.io.fileset import replace_files

    fig = figure_case(spec)
    stem = Path(spec.path).stem

    def writer(fmt):
        return lambda tmp: fig.savefig(tmp, format=fmt, dpi=dpi, bbox_inches="tight")

    paths = {Path(out_dir) / f"{stem}.{fmt}": writer(fmt) for fmt in formats}
    written = set(replace_files(paths))
    return [path for path in paths if path in written]
