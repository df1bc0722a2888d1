"""Figures of ``xfemslip deplete``: slip vs depletion and a field picture.

Imported only when plotting (matplotlib is not a dependency of a run;
``matplotlib.figure.Figure``, no pyplot).  The pressure change runs as its
magnitude to the right (:func:`xfemslip.plot.style.pressure_change_axis`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from xfemslip.conventions import SLIP
from xfemslip.geometry.regions import edges
from xfemslip.plot.style import (
    colourbar_label,
    legend_of_many,
    line_styles,
    pressure_change_axis,
    robust_norm,
)

# critical depletions closer than this fraction of the axis are one line
COINCIDENT = 0.005
CRITICAL_DASHES = (":", "--", "-.", (0, (1, 3)))
# the fractures fill less than this fraction of the section: a zoom row
ZOOM_BELOW = 0.4


def step_line(x, y, jump_at: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The points of a step line through the samples (x_k, y_k): each value
    held until the next sample, where it changes (what samples of a length
    support: it does not grow between them as a ramp); when ``jump_at`` lies
    strictly between the two samples of the first change, the change is
    drawn there instead (a fracture's critical depletion)."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    xs, ys = [x[:1]], [y[:1]]
    first = True
    for k in range(1, len(x)):
        at = x[k]
        if y[k] != y[k - 1]:
            if first and jump_at is not None and x[k - 1] < jump_at < x[k]:
                at = jump_at
            first = False
        xs.append(np.array([at, at, x[k]]))
        ys.append(np.array([y[k - 1], y[k], y[k]]))
    return np.concatenate(xs), np.concatenate(ys)


def critical_groups(onsets, sign: float, span: float) -> list[tuple[float, list]]:
    """[(x of the critical depletion on the axis, [fracture indices])]:
    fractures whose critical depletions lie within COINCIDENT of the axis
    ``span`` of each other share one line."""
    groups: list[tuple[float, list]] = []
    for onset in onsets:
        if not np.isfinite(onset.dp_upper):
            continue
        x = sign * onset.dp_critical / 1e6
        for at, members in groups:
            if abs(at - x) <= COINCIDENT * span:
                members.append(onset.fracture)
                break
        else:
            groups.append((x, [onset.fracture]))
    return groups


def plot_slip_vs_depletion(
    report, out_dir: Path, dpi: float = 110.0, name: str | None = None
) -> Path:
    """:func:`figure_slip_vs_depletion` into ``<out_dir>/slip_vs_depletion.png``."""
    path = out_dir / "slip_vs_depletion.png"
    figure_slip_vs_depletion(report, name).savefig(path, dpi=dpi)
    return path


def figure_slip_vs_depletion(report, name: str | None = None) -> Figure:
    """Max |slip| that slid and slipping length of each fracture against the
    pressure change (``report.rows``, the event sizes), its magnitude
    growing to the right; the slipping length as steps; each fracture's
    critical depletion a vertical line, fractures at one depletion sharing
    one, labelled with their numbers and value; ``name`` (the case's)
    titles the figure."""
    rows = report.rows
    change = np.array([r[2] for r in rows])
    x, xlabel = pressure_change_axis(change)
    sign = -1.0 if np.any(x * change < 0.0) else 1.0
    span = float(np.ptp(x)) or 1.0
    fig = Figure(figsize=(9.0, 4.0), layout="constrained")
    a1, a2 = fig.subplots(1, 2)
    styles = line_styles(len(report.onsets), dashes=True)
    seismic = False
    curves = []  # (handle, label, largest slip, its point on a1, number)
    for i, onset in enumerate(report.onsets):
        style = {**styles[i], "ms": 3}
        slip = np.array([r[3][i][0] for r in rows]) * 1e3
        length = np.array([r[3][i][1] for r in rows])
        if np.isfinite(onset.dp_seismic):
            seismic = True
            _mark_nucleation(a1, a2, sign * onset.dp_seismic / 1e6, slip, length, style)
        (line,) = a1.plot(x, slip, label=f"fracture {onset.fracture}", **style)
        top = int(np.argmax(slip))
        peak = (x[top], slip[top])
        curves.append((line, line.get_label(), slip[top], peak, f"{onset.fracture}"))
        jump = sign * onset.dp_critical / 1e6 if np.isfinite(onset.dp_upper) else None
        a2.plot(
            *step_line(x, length, jump), color=style["color"], ls=style["linestyle"]
        )
        a2.plot(x, length, ls="", marker=style["marker"], ms=3, color=style["color"])
    for g, (at, members) in enumerate(critical_groups(report.onsets, sign, span)):
        colour = styles[report.onsets.index(_onset(report, members[0]))]["color"]
        colour = colour if len(members) == 1 else "k"
        who = ("fracture " if len(members) == 1 else "fractures ") + ", ".join(
            str(m) for m in members
        )
        for ax in (a1, a2):
            ax.axvline(at, color=colour, lw=1.0, ls=CRITICAL_DASHES[g % 4])
        singular = all(_onset(report, m).at_singularity for m in members)
        a1.annotate(
            f"{who}: {at:.3g} MPa" + (" (singular point)" if singular else ""),
            (at, 1.0),
            xycoords=("data", "axes fraction"),
            xytext=(-3, -4),
            textcoords="offset points",
            rotation=90,
            ha="right",
            va="top",
            fontsize=7,
            color=colour,
        )
    a1.set_xlabel(xlabel)
    a1.set_ylabel("max |slip| that slid [mm]")
    a2.set_xlabel(xlabel)
    a2.set_ylabel("slipping length [m]")
    a1.set_title(
        "vertical lines: critical depletion (bisection)"
        + ("\nstars: loss of equilibrium, slip turns seismic" if seismic else ""),
        fontsize=9,
    )
    a2.set_title("steps: each length held until the next sample", fontsize=9)
    # a star at the last sample needs room beside it
    right = float(x.max()) + (0.04 * span if seismic else 0.0)
    for ax in (a1, a2):
        ax.set_xlim(min(0.0, float(x.min())), right)
        ax.grid(alpha=0.3)
    # in the length panel (the critical depletions are annotated along the
    # top of the slip panel), over no point; beyond six entries the smaller
    # fractures are numbered on their slip curves
    legend_of_many(a2, curves, fontsize=7, label_ax=a1)
    if name:
        fig.suptitle(f"{name}: slip against depletion", fontsize=10)
    return fig


def _mark_nucleation(a1, a2, at, slip, length, style) -> None:
    """A star where the slip of a fracture turns seismic (the last state of
    the path, at the depletion ``at`` on the axis) on both panels, the
    value written beside it."""
    colour = style["color"]
    for ax, values in ((a1, slip), (a2, length)):
        ax.plot(
            [at],
            [values[-1]],
            ls="",
            marker="*",
            ms=12,
            color=colour,
            mec="k",
            mew=0.5,
            zorder=5,
        )
    a2.annotate(
        f"seismic at {at:.3g} MPa",
        (at, length[-1]),
        xytext=(-8, 0),
        textcoords="offset points",
        ha="right",
        va="center",
        fontsize=7,
        color=colour,
    )


def _onset(report, fracture: int):
    return next(o for o in report.onsets if o.fracture == fracture)


def _field_colourbar(fig, ax, mappable, label: str, scale) -> None:
    """A colour bar the height of ``ax`` (an inset beside it: an equal-aspect
    panel is often lower than the space the layout gives it)."""
    cax = ax.inset_axes([1.03, 0.0, 0.04, 1.0])
    fig.colorbar(
        mappable, cax=cax, label=colourbar_label(label, scale), extend=scale.extend
    )


def _zoom_window(fractures, box) -> tuple[float, float, float, float] | None:
    """(x0, x1, y0, y1) around the fractures when they fill less than
    ZOOM_BELOW of the section's width and height, else None."""
    pts = [np.asarray(fr.points, float) for fr in fractures if len(fr.points)]
    if not pts:
        return None
    p = np.concatenate(pts)
    lo, hi = p.min(axis=0), p.max(axis=0)
    width, height = box[1] - box[0], box[3] - box[2]
    extent = hi - lo
    if extent[0] >= ZOOM_BELOW * width or extent[1] >= ZOOM_BELOW * height:
        return None
    pad = 0.25 * max(extent.max(), 1e-9)
    lo, hi = lo - pad, hi + pad
    return (
        max(lo[0], box[0]),
        min(hi[0], box[1]),
        max(lo[1], box[2]),
        min(hi[1], box[3]),
    )


def plot_field(model, result, out_dir: Path, dpi: float = 110.0) -> Path:
    """:func:`figure_field` into ``<out_dir>/depletion_field.png``."""
    path = out_dir / "depletion_field.png"
    figure_field(model, result).savefig(path, dpi=dpi, bbox_inches="tight")
    return path


def figure_field(model, result) -> Figure:
    """Shear stress change and effective horizontal stress at the last step,
    reservoir outline, fractures coloured stick / slip; colour ranges from
    the 1st to the 99th percentile (:func:`xfemslip.plot.style.robust_norm`),
    the change white at zero; a second row zoomed on the fractures when they
    are small in the section."""
    from xfemslip.post.fields import cell_in_situ, step_fields

    f = step_fields(model, result)
    mesh = model.mesh
    s0 = cell_in_situ(model)
    s0 = np.zeros(3) if s0 is None else np.atleast_2d(np.asarray(s0, float))
    shape = (mesh.ny, mesh.nx)
    stress = f.stress
    assert stress is not None  # step_fields computes the stresses
    panels = [
        (
            "shear stress change $\\Delta\\sigma_{xy}$ [MPa]",
            stress[:, 2] - np.broadcast_to(s0, stress.shape)[:, 2],
            True,
        ),
        (
            "effective stress $\\sigma'_{xx}$ [MPa], tension positive",
            f.effective_stress[:, 0]
            if f.effective_stress is not None
            else stress[:, 0],
            None,
        ),
    ]
    box = (mesh.x[0], mesh.x[-1], mesh.y[0], mesh.y[-1])
    zoom = _zoom_window(f.fractures, box)
    rows = 1 if zoom is None else 2
    # rows as high as the equal-aspect panels need (4 inches wide each)
    heights = [(box[3] - box[2]) / (box[1] - box[0])]
    if zoom is not None:
        heights.append((zoom[3] - zoom[2]) / (zoom[1] - zoom[0]))
    fig = Figure(
        figsize=(10.0, sum(4.0 * min(h, 1.5) + 1.0 for h in heights)),
        layout="constrained",
    )
    axes = fig.subplots(
        rows, 2, squeeze=False, height_ratios=[min(h, 1.5) + 0.25 for h in heights]
    )
    for col, (title, value, centre) in enumerate(panels):
        v = value.reshape(shape) / 1e6
        scale = robust_norm(v, centre_zero=centre)
        for row in range(rows):
            ax = axes[row, col]
            im = ax.pcolormesh(mesh.x, mesh.y, v, cmap=scale.cmap, norm=scale.norm)
            for unit in model.spec.units:
                for _, p, q in edges(unit.region, mesh.box):
                    ax.plot([p[0], q[0]], [p[1], q[1]], "k--", lw=0.8)
            for fr in f.fractures:
                slip = fr.state == SLIP
                ax.plot(fr.points[:, 0], fr.points[:, 1], "-", color="0.3", lw=1.0)
                ax.plot(
                    fr.points[slip, 0], fr.points[slip, 1], ".", color="orange", ms=3
                )
            ax.set_aspect("equal")
            ax.set_xlabel("x [m]")
            ax.set_ylabel("y [m]")
            if row == 0:
                ax.set_xlim(box[0], box[1])
                ax.set_ylim(box[2], box[3])
                ax.set_title(title, fontsize=9)
            else:
                assert zoom is not None
                ax.set_xlim(zoom[0], zoom[1])
                ax.set_ylim(zoom[2], zoom[3])
                ax.set_title("zoom on the fractures", fontsize=9)
            _field_colourbar(fig, ax, im, title.split(" [")[0] + " [MPa]", scale)
    fig.suptitle(
        f"{model.spec.name}: pore-pressure change "
        f"{result.load_factor * model.pore.change / 1e6:.3g} MPa "
        "(orange: slipping contact points)",
        fontsize=10,
    )
    return fig
