"""What the figures share (matplotlib, imported only when a figure is drawn):
the line styles of many curves, the pressure-change axis, the colour range
of a field, tick labels on short log axes, and labels placed where they do
not cover each other or the lines they name.

- :func:`line_styles`: n (colour, dash, marker) whose neighbours differ in
  hue and whose repeats differ in dash, so fifteen fractures stay apart;
- :func:`pressure_change_axis`: one convention for every axis of a
  pore-pressure change: its magnitude increasing to the right, the label
  saying whether it is a drop or a rise;
- :func:`robust_norm`: a field's colour range from its 1st to 99th
  percentile (a tip singularity does not set it), at least
  :data:`MIN_SPAN_FRACTION` of the field's size wide (noise is not magnified
  into colour), centred on zero when the field changes sign;
- :func:`label_log_axis`: plain tick labels on a log axis that spans less
  than two decades (matplotlib labels only the powers of ten below one
  decade, and crowds scientific-notation minor labels from one to two);
- :func:`place_labels`: text labels at anchor points, those at one point
  joined into one ("0, 1, 2"), each moved to the first nearby place where it
  covers no other label and no line to avoid;
- :func:`legend_of_many`: a legend of at most :data:`MAX_LEGEND_ENTRIES`
  inside the axes, over no data (the y range is raised to leave it a free
  band), the curves beyond it numbered where they end.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from matplotlib.colors import Normalize, TwoSlopeNorm
from matplotlib.path import Path as MplPath
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter
from matplotlib.transforms import Bbox

DASHES = ("-", "--", "-.", ":")
MARKERS = ("o", "s", "^", "D", "v", "P", "X")
# a field's colour range spans at least this fraction of its largest
# magnitude (1st-99th percentile), so a nearly uniform field looks uniform
MIN_SPAN_FRACTION = 0.1
PERCENTILES = (1.0, 99.0)
# entries of a legend inside the axes; more curves are numbered on the axes
MAX_LEGEND_ENTRIES = 6


def line_styles(n: int, dashes: bool = False) -> list[dict]:
    """``n`` keyword sets (color, linestyle, marker) for ``ax.plot``: the ten
    hues of matplotlib's cycle in turn, so neighbours always differ in hue,
    solid for the first ten, then dashed, dash-dotted, dotted; the marker
    cycles over seven shapes.  Every set differs from every other up to 280.
    ``dashes``: the dash changes from each curve to the next as well (curves
    that may lie on each other stay visible)."""
    return [
        {
            "color": f"C{i % 10}",
            "linestyle": DASHES[(i + (i // 10) if dashes else i // 10) % len(DASHES)],
            "marker": MARKERS[i % len(MARKERS)],
        }
        for i in range(n)
    ]


def pressure_change_axis(change_pa) -> tuple[np.ndarray, str]:
    """(x [MPa], label) of an axis of pore-pressure changes ``change_pa``
    [Pa]: a depletion (the largest change negative) is drawn as the drop
    -dp, a rise as dp, so the magnitude always grows to the right."""
    change = np.asarray(change_pa, dtype=float)
    drop = change.size > 0 and change[np.argmax(np.abs(change))] < 0.0
    if drop:
        return -change / 1e6, "pore-pressure drop $-\\Delta p$ [MPa] (depletion)"
    return change / 1e6, "pore-pressure rise $\\Delta p$ [MPa]"


@dataclass(frozen=True)
class FieldScale:
    """Colour range of a field: ``norm`` for the mappable, ``cmap``,
    ``extend`` for the colour bar ("neither", "min", "max", "both") and
    ``note`` for its label ("" when nothing is clipped)."""

    norm: Normalize
    cmap: str
    extend: str
    note: str


def robust_norm(values, centre_zero: bool | None = None) -> FieldScale:
    """The colour range of :mod:`this module <xfemslip.plot.style>`'s doc:
    [1st, 99th percentile], widened to MIN_SPAN_FRACTION of the largest
    magnitude; a diverging map with white at zero (TwoSlopeNorm) when the
    range holds zero (or ``centre_zero``), else a sequential map."""
    v = np.asarray(values, dtype=float).ravel()
    v = v[np.isfinite(v)]
    if not v.size:
        return FieldScale(Normalize(-1.0, 1.0), "RdBu_r", "neither", "")
    lo, hi = (float(x) for x in np.percentile(v, PERCENTILES))
    size = max(abs(lo), abs(hi))
    least = MIN_SPAN_FRACTION * size if size > 0.0 else 1.0
    if hi - lo < least:
        mid = 0.5 * (lo + hi)
        lo, hi = mid - 0.5 * least, mid + 0.5 * least
    below, above = float(v.min()) < lo, float(v.max()) > hi
    extend = {
        (False, False): "neither",
        (True, False): "min",
        (False, True): "max",
        (True, True): "both",
    }[below, above]
    note = (
        f"clipped to the {PERCENTILES[0]:g}-{PERCENTILES[1]:g} percentile"
        if below or above
        else ""
    )
    if centre_zero is None:
        centre_zero = lo < 0.0 < hi
    if centre_zero:
        bound = max(abs(lo), abs(hi))
        lo, hi = min(lo, -1e-12 * bound), max(hi, 1e-12 * bound)
        return FieldScale(TwoSlopeNorm(0.0, lo, hi), "RdBu_r", extend, note)
    return FieldScale(Normalize(lo, hi), "viridis", extend, note)


def colourbar_label(label: str, scale: FieldScale) -> str:
    """``label`` with what the colours mean beyond the plain range."""
    words = []
    if isinstance(scale.norm, TwoSlopeNorm):
        words.append("white: 0")
    if scale.note:
        words.append(scale.note)
    return label + (f"\n({'; '.join(words)})" if words else "")


def label_log_axis(axis) -> None:
    """Tick labels on a log ``axis`` (``ax.xaxis``) however short its range:
    spanning two decades or more, the powers of ten as usual; less, ticks at
    1, 2 and 5 x 10^k in plain numbers (matplotlib labels the minor ticks of
    a range of one to two decades in scientific notation, which run into
    each other), and below a factor 2.5 every 1..9 x 10^k."""
    lo, hi = sorted(axis.get_view_interval())
    if lo <= 0.0 or hi / lo >= 100.0:
        return
    axis.set_major_locator(LogLocator(base=10.0, subs=(1.0, 2.0, 5.0)))
    axis.set_minor_locator(LogLocator(base=10.0, subs=[float(k) for k in range(1, 10)]))
    axis.set_major_formatter(FuncFormatter(lambda value, _: f"{value:g}"))
    axis.set_minor_formatter(NullFormatter())
    shown = [t for t in axis.get_majorticklocs() if lo <= t <= hi]
    if len(shown) < 2:  # less than a factor 2.5: every minor tick named
        axis.set_major_locator(
            LogLocator(base=10.0, subs=[float(k) for k in range(1, 10)])
        )


# --------------------------------------------------------------------------- #
# Labels that do not overlap
# --------------------------------------------------------------------------- #


def renderer_of(fig):
    """The figure's renderer (an Agg canvas is attached if it has none)."""
    canvas = fig.canvas
    if not hasattr(canvas, "get_renderer"):
        from matplotlib.backends.backend_agg import FigureCanvasAgg

        canvas = FigureCanvasAgg(fig)
    return canvas.get_renderer()


def _candidates(direction, gap: float) -> list[tuple[float, float]]:
    """Offsets [points] to try around an anchor: beside a line of unit
    ``direction`` (display), on either side and slid along it; else the
    eight compass points, nearest first."""
    out: list[tuple[float, float]] = []
    for scale in (1.0, 2.0, 3.5, 5.0):
        d = gap * scale
        if direction is not None:
            tx, ty = direction
            nx, ny = -ty, tx
            out.extend(
                (side * d * nx + slide * gap * tx, side * d * ny + slide * gap * ty)
                for slide in (0.0, 1.5, -1.5, 3.0, -3.0)
                for side in (1.0, -1.0)
            )
        else:
            for k in range(8):
                a = math.radians(45.0 + 45.0 * k)
                out.append((d * math.cos(a), d * math.sin(a)))
    return out


def _covers(box: Bbox, points_px: np.ndarray, pad: float = 4.0) -> bool:
    """Whether the box (grown by ``pad`` pixels) holds one of the points."""
    x, y = points_px[:, 0], points_px[:, 1]
    inside = (
        (x >= box.x0 - pad)
        & (x <= box.x1 + pad)
        & (y >= box.y0 - pad)
        & (y <= box.y1 + pad)
    )
    return bool(np.any(inside))


def _hits_lines(box: Bbox, lines_px: Sequence[MplPath]) -> bool:
    return any(path.intersects_bbox(box, filled=False) for path in lines_px)


def place_labels(
    ax,
    labels: Sequence[tuple[tuple[float, float], str]],
    *,
    directions: Sequence | None = None,
    avoid: Sequence[np.ndarray] = (),
    gap: float = 5.0,
    join_within: float = 3.0,
    prefix: tuple[str, str] = ("", ""),
    **text_style,
) -> list:
    """Annotate ``labels`` = [((x, y) data, text)] on ``ax`` so that no two
    overlap and none covers a polyline of ``avoid`` [(K, 2) data]; returns
    the annotations.

    Labels whose anchors lie within ``join_within`` pixels of each other
    become one ("0, 1, 2"; ``prefix`` = (one, several) is put before them,
    e.g. ("fracture ", "fractures ")).  ``directions`` (one (dx, dy) in data
    coordinates per label, or None): the label goes beside that direction (a
    fracture's line), not on it.  Each label takes the first of the nearby
    places (:func:`_candidates`) where it fits; if none does, the one that
    overlaps least.  The figure is laid out first, and the labels take no
    part in the layout, so the places found are where they are drawn."""
    fig = ax.figure
    renderer = renderer_of(fig)
    fig.draw_without_rendering()
    to_px = ax.transData.transform
    groups: list[tuple[np.ndarray, list[str], object]] = []
    for k, (at, text) in enumerate(labels):
        p = to_px(np.asarray(at, dtype=float).reshape(1, 2))[0]
        direction = directions[k] if directions is not None else None
        for q, texts, _ in groups:
            if np.hypot(*(q - p)) <= join_within:
                if text not in texts:
                    texts.append(text)
                break
        else:
            groups.append((p, [text], direction))
    lines_px = [MplPath(to_px(np.asarray(line, dtype=float))) for line in avoid]
    anchors_px = np.array([p for p, _, _ in groups]).reshape(-1, 2)
    # the axes' legend is in the way as much as a placed label
    legend = ax.get_legend()
    placed: list[Bbox] = [] if legend is None else [legend.get_window_extent(renderer)]
    notes = []
    style = {
        "fontsize": 7,
        "bbox": {
            "boxstyle": "round,pad=0.1",
            "fc": "white",
            "ec": "none",
            "alpha": 0.7,
        },
        **text_style,
    }
    for p, texts, direction in groups:
        text = (prefix[0] if len(texts) == 1 else prefix[1]) + ", ".join(texts)
        unit = None
        if direction is not None:
            a = to_px(np.array([[0.0, 0.0], direction], dtype=float))
            d = a[1] - a[0]
            norm = float(np.hypot(*d))
            unit = tuple(d / norm) if norm > 0.0 else None
        anchor = ax.transData.inverted().transform(p)
        best, best_cost = None, math.inf
        for dx, dy in _candidates(unit, gap):
            ha = "left" if dx > 0.5 else "right" if dx < -0.5 else "center"
            va = "bottom" if dy > 0.5 else "top" if dy < -0.5 else "center"
            note = ax.annotate(
                text,
                anchor,
                xytext=(dx, dy),
                textcoords="offset points",
                ha=ha,
                va=va,
                **style,
            )
            note.set_in_layout(False)
            box = note.get_window_extent(renderer)
            cost = 2 * sum(box.overlaps(other) for other in placed)
            cost += _hits_lines(box, lines_px) + _covers(box, anchors_px)
            inside = ax.bbox.contains(box.x0, box.y0) and ax.bbox.contains(
                box.x1, box.y1
            )
            cost += 0 if inside else 1
            if cost < best_cost:
                if best is not None:
                    best.remove()
                best, best_cost = note, cost
            else:
                note.remove()
            if cost == 0:
                break
        assert best is not None
        placed.append(best.get_window_extent(renderer))
        notes.append(best)
    return notes


def _line_data(ax) -> np.ndarray:
    """(N, 2) data coordinates of the vertices of the lines drawn in data
    coordinates (axvline and axhline left out)."""
    pts = [
        np.column_stack(line.get_data()).astype(float)
        for line in ax.get_lines()
        if line.get_visible() and line.get_transform() is ax.transData
    ]
    pts = [p for p in pts if p.size]
    return np.concatenate(pts) if pts else np.zeros((0, 2))


def legend_inside(ax, handles, labels, *, loc: str = "upper left", **kwargs):
    """A legend inside ``ax`` at ``loc`` (an upper corner) that covers no data
    point: after the layout, the top of the y range is raised until the
    highest point of every line lies below the legend's lower edge."""
    legend = ax.legend(handles, labels, loc=loc, **kwargs)
    fig = ax.figure
    renderer = renderer_of(fig)
    for _ in range(4):  # the layout moves a little with the tick labels
        fig.draw_without_rendering()
        box, frame = legend.get_window_extent(renderer), ax.bbox
        data = _line_data(ax)
        if data.size == 0:
            break
        px = ax.transData.transform(data)
        under = (px[:, 0] >= box.x0 - 2.0) & (px[:, 0] <= box.x1 + 2.0)
        under &= (px[:, 1] >= box.y0 - 2.0) & (px[:, 1] <= box.y1 + 2.0)
        if not under.any():
            break
        # the data below the legend: their top at this share of the height
        free = (box.y0 - frame.y0) / frame.height - 0.03
        y0, y1 = ax.get_ylim()
        top = float(np.nanmax(data[:, 1]))
        if free <= 0.1 or not math.isfinite(top) or top <= y0:
            break
        ax.set_ylim(y0, max(y0 + (top - y0) / free, y1 * (1.0 + 1e-6)))
    return legend


def legend_of_many(
    ax,
    curves: Sequence[tuple[object, str, float, tuple[float, float], str]],
    *,
    fontsize: float = 8,
    loc: str = "upper left",
    label_ax=None,
):
    """A legend for many curves: at most :data:`MAX_LEGEND_ENTRIES` entries
    inside ``ax`` over no data (:func:`legend_inside`).

    ``curves``: (handle, label, size, end, number) per curve; ``size`` ranks
    them (e.g. the largest slip), ``end`` is a point (data) of the curve on
    ``label_ax`` (default ``ax``) where its ``number`` is written when the
    curve has no legend entry.  With more curves than entries, the largest
    MAX_LEGEND_ENTRIES - 1 keep theirs (in their order) and the last entry
    says how many more are numbered on their curves (:func:`place_labels`,
    in the axes, off each other and the legend)."""
    from matplotlib.lines import Line2D

    if len(curves) <= MAX_LEGEND_ENTRIES:
        keep, rest = list(range(len(curves))), []
    else:
        ranked = sorted(range(len(curves)), key=lambda i: -curves[i][2])
        keep = sorted(ranked[: MAX_LEGEND_ENTRIES - 1])
        rest = sorted(ranked[MAX_LEGEND_ENTRIES - 1 :])
    handles = [curves[i][0] for i in keep]
    labels = [curves[i][1] for i in keep]
    if rest:
        handles.append(Line2D([], [], color="none"))
        labels.append(f"{len(rest)} more: numbered on their curves")
    legend = legend_inside(ax, handles, labels, loc=loc, fontsize=fontsize)
    if rest:
        target = label_ax if label_ax is not None else ax
        place_labels(
            target,
            [(curves[i][3], curves[i][4]) for i in rest],
            join_within=6.0,
            fontsize=7,
        )
    return legend
