"""Checks of a drawn figure that a reader makes by eye, as assertions: labels
that do not overlap, ticks that are labelled, axis limits that span the data
(and not much more), legends over no data point.  Each works on the figure
as drawn (an Agg renderer, the layout done), so it sees what the PNG shows.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.lines import Line2D
from matplotlib.path import Path as MplPath


def drawn(fig):
    """Draw ``fig`` (layout included) on an Agg canvas; returns the renderer."""
    if not isinstance(fig.canvas, FigureCanvasAgg):
        FigureCanvasAgg(fig)
    fig.canvas.draw()
    return fig.canvas.get_renderer()


def boxes(texts, renderer) -> list:
    """Window extents of the visible, non-empty texts."""
    return [
        t.get_window_extent(renderer)
        for t in texts
        if t.get_visible() and t.get_text().strip()
    ]


def assert_no_overlap(texts, renderer, what: str = "labels") -> None:
    """No two of ``texts`` overlap on the canvas."""
    shown = [t for t in texts if t.get_visible() and t.get_text().strip()]
    extents = boxes(shown, renderer)
    for i, a in enumerate(extents):
        for j in range(i + 1, len(extents)):
            assert not a.overlaps(extents[j]), (
                f"{what} overlap: {shown[i].get_text()!r} and {shown[j].get_text()!r}"
            )


def assert_off_lines(texts, lines: Iterable[np.ndarray], ax, renderer) -> None:
    """None of ``texts`` lies on one of the polylines ``lines`` (data
    coordinates of ``ax``)."""
    paths = [MplPath(ax.transData.transform(np.asarray(p, float))) for p in lines]
    for t in texts:
        box = t.get_window_extent(renderer)
        for path in paths:
            assert not path.intersects_bbox(box, filled=False), (
                f"label {t.get_text()!r} lies on a line"
            )


def tick_labels(axis) -> list[str]:
    """The non-empty tick labels, major and minor, within the axis' view."""
    lo, hi = sorted(axis.get_view_interval())
    span = hi - lo
    out = []
    for locs, formatter in (
        (axis.get_majorticklocs(), axis.get_major_formatter()),
        (axis.get_minorticklocs(), axis.get_minor_formatter()),
    ):
        inside = [v for v in locs if lo - 1e-9 * span <= v <= hi + 1e-9 * span]
        formatter.set_locs(inside)
        out += [formatter(v, i) for i, v in enumerate(inside)]
    return [text for text in out if text.strip()]


def assert_ticks_labelled(ax, axes: str = "xy", least: int = 2) -> None:
    """Each of ``axes`` ("x", "y") of ``ax`` has at least ``least``
    labelled ticks in view."""
    for name in axes:
        axis = getattr(ax, f"{name}axis")
        labels = tick_labels(axis)
        assert len(labels) >= least, (
            f"{name} axis of {ax.get_title()!r} ({axis.get_label_text()!r}): "
            f"tick labels {labels}"
        )


def assert_limits_span(
    ax, axis: str, values, slack: float = 1.35, include: Sequence[float] = ()
) -> None:
    """The ``axis`` ("x" or "y") limits of ``ax`` hold every value, and are no
    wider than ``slack`` times the range of the values and ``include`` (a
    limit set by hand at, say, 0)."""
    v = np.concatenate([np.ravel(values), np.asarray(include, float)])
    v = v[np.isfinite(v)]
    lo, hi = sorted(getattr(ax, f"get_{axis}lim")())
    tol = 1e-9 * max(abs(lo), abs(hi), 1.0)
    assert lo <= v.min() + tol and v.max() - tol <= hi, (
        f"{axis} limits [{lo:g}, {hi:g}] miss data in [{v.min():g}, {v.max():g}]"
    )
    assert hi - lo <= slack * max(v.max() - v.min(), tol), (
        f"{axis} limits [{lo:g}, {hi:g}] much wider than the data "
        f"[{v.min():g}, {v.max():g}]"
    )


def data_points(ax) -> np.ndarray:
    """(N, 2) display coordinates of the data points of the lines of ``ax``
    inside its box (a line's vertices; axvline/axhline excluded)."""
    pts = []
    for line in ax.get_lines():
        if not isinstance(line, Line2D) or not line.get_visible():
            continue
        if line.get_transform() is not ax.transData:  # axhline, axvline
            continue
        xy = np.column_stack(line.get_data()).astype(float)
        if xy.size:
            pts.append(ax.transData.transform(xy))
    if not pts:
        return np.zeros((0, 2))
    p = np.concatenate(pts)
    box = ax.bbox
    inside = (p[:, 0] >= box.x0) & (p[:, 0] <= box.x1)
    inside &= (p[:, 1] >= box.y0) & (p[:, 1] <= box.y1)
    return p[inside]


def assert_legend_covers_no_point(legend, axes, renderer) -> None:
    """No data point of ``axes`` (:func:`data_points`) lies under the legend."""
    box = legend.get_window_extent(renderer)
    for ax in axes:
        p = data_points(ax)
        under = (p[:, 0] >= box.x0) & (p[:, 0] <= box.x1)
        under &= (p[:, 1] >= box.y0) & (p[:, 1] <= box.y1)
        assert not under.any(), (
            f"the legend covers {int(under.sum())} data points of {ax.get_title()!r}"
        )


def assert_legend_inside(legend, ax, renderer, most: int = 6) -> None:
    """The legend lies within the box of ``ax``, has at most ``most``
    entries, and covers no data point of ``ax``."""
    box, frame = legend.get_window_extent(renderer), ax.bbox
    assert frame.x0 - 0.5 <= box.x0 and box.x1 <= frame.x1 + 0.5, "legend beside"
    assert frame.y0 - 0.5 <= box.y0 and box.y1 <= frame.y1 + 0.5, "legend above/below"
    assert len(legend.get_texts()) <= most, [t.get_text() for t in legend.get_texts()]
    assert_legend_covers_no_point(legend, [ax], renderer)
