"""Figures of fracture networks (matplotlib, imported only here and only when
a figure is drawn; ``matplotlib.figure.Figure``, no pyplot, no GUI backend).

``figure_network``: the fractures of a case in its domain, coloured by
the ``|slip|`` that slid (the plastic slip) at the contact points when a
``result.h5`` is given (slipping
fractures drawn thicker), else by origin; with a sweep's ``summary.csv`` a
second panel shows how many fractures slip over the realizations.
"""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.collections import LineCollection
from matplotlib.colors import Normalize
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from xfemslip.case.specs import CaseSpec
from xfemslip.conventions import SLIP
from xfemslip.errors import OutputError, UsageError
from xfemslip.io.read import read_result

PANEL = 4.2  # inches
# A case holds at most this many fractures: inline ones within the 8 MB of
# a case file, and 5,000 per network source.
MAX_FRACTURE_COUNT = 1_000_000
MAX_BARS = 200  # one histogram bar per count up to this spread


def _domain_frame(ax, spec: CaseSpec) -> None:
    (x0, y0), (w, h) = spec.origin, spec.size
    frame = np.vstack([spec.box.vertices(), spec.box.vertices()[:1]])
    ax.plot(*frame.T, "k-", lw=0.8)
    ax.set_aspect("equal")
    ax.set_xlim(x0 - 0.02 * w, x0 + 1.02 * w)
    ax.set_ylim(y0 - 0.02 * h, y0 + 1.02 * h)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")


def read_result_slip(result: Path, n_fractures: int) -> list[tuple]:
    """[(points (K, 2), slip (K,), state (K,))] per fracture of a result.h5:
    the slip that slid (``FractureFields.slid``)."""
    read = read_result(result)
    fractures = read.fractures if read.steps else []
    if len(fractures) < n_fractures:
        raise UsageError(
            f"{result}: no /fractures/{len(fractures)}: not a result of this case "
            f"({n_fractures} fractures)"
        )
    return [(f.points, f.slid, f.state) for f in fractures[:n_fractures]]


def _draw_slip(fig, ax, fields) -> None:
    """Contact-point polylines coloured by |slip|; slipping fractures thicker."""
    top = max((float(np.abs(s).max()) for _, s, _ in fields if s.size), default=0.0)
    norm = Normalize(0.0, top if top > 0 else 1.0)
    collection = None
    for points, slip, state in fields:
        if len(points) < 2:
            continue
        pieces = np.stack([points[:-1], points[1:]], axis=1)
        value = 0.5 * (np.abs(slip[:-1]) + np.abs(slip[1:]))
        width = 2.6 if np.any(state == SLIP) else 1.0
        collection = LineCollection(
            list(pieces), cmap="viridis", norm=norm, linewidths=width
        )
        collection.set_array(value)
        ax.add_collection(collection)
    if collection is not None:
        fig.colorbar(collection, ax=ax, label="|slip| (m)", shrink=0.8)


def _draw_plain(ax, spec: CaseSpec) -> None:
    """Fractures coloured by where they come from (inline, file, generated)."""
    colours = {"": "tab:red", "network.file": "tab:blue", "network.generate": "k"}
    for fracture in spec.fractures:
        kind = fracture.source.split(" ", 1)[0] if fracture.source else ""
        p = fracture.points
        ax.plot(p[:, 0], p[:, 1], "-", color=colours.get(kind, "k"), lw=1.2)


def read_slipping_counts(summary: Path) -> tuple[np.ndarray, np.ndarray]:
    """(slipping_fractures, fractures) of the ok/skipped rows of a summary.csv
    (read with the size cap of every CSV input; a bad row names its line)."""
    from xfemslip.case.files import MAX_CSV_BYTES, UnreadableInput, read_input

    try:
        lines = read_input(summary, MAX_CSV_BYTES).splitlines()
    except UnreadableInput as exc:
        raise UsageError(f"{summary}: cannot read: {exc}") from None
    reader = csv.DictReader(lines)
    try:
        rows = list(reader)
    except csv.Error as exc:  # a cell over csv's field limit, a NUL byte
        raise UsageError(
            f"{summary} line {reader.line_num}: not a CSV row of a summary: {exc}"
        ) from None
    needed = ("status", "slipping_fractures", "fractures")
    if rows and any(name not in rows[0] for name in needed):
        raise UsageError(
            f"{summary}: expected the columns {', '.join(needed)} of a sweep's "
            "summary.csv (an older sweep?)"
        )
    counts, totals = [], []
    for line, row in enumerate(rows, start=2):
        if row["status"] not in ("ok", "skipped"):
            continue
        try:
            slipping, total = int(row["slipping_fractures"]), int(row["fractures"])
        except (TypeError, ValueError):
            raise UsageError(
                f"{summary} line {line}: slipping_fractures and fractures must be "
                "integers"
            ) from None
        if not 0 <= slipping <= total <= MAX_FRACTURE_COUNT:
            raise UsageError(
                f"{summary} line {line}: slipping_fractures = {_short(slipping)} "
                f"and fractures = {_short(total)} are not the counts of a case: "
                f"expected 0 <= slipping_fractures <= fractures <= "
                f"{MAX_FRACTURE_COUNT}"
            )
        counts.append(slipping)
        totals.append(total)
    return np.array(counts, dtype=np.int64), np.array(totals, dtype=np.int64)


def _short(n: int) -> str:
    """An integer for a message: its digits, or its size when very long."""
    text = str(n)
    return text if len(text) <= 20 else f"a number of {len(text)} digits"


def _draw_counts(ax, counts: np.ndarray, totals: np.ndarray) -> None:
    """Histogram of the slipping count over the realizations: one bar per
    count up to MAX_BARS counts apart, else numpy's automatic bins."""
    bins: Any
    if counts.size and counts.max() - counts.min() < MAX_BARS:
        bins = np.arange(counts.min(), counts.max() + 2) - 0.5
    else:
        bins = "auto" if counts.size else 1
    ax.hist(counts, bins=bins, color="tab:blue", edgecolor="k")
    total = f"{int(totals[0])}" if totals.size and np.ptp(totals) == 0 else "varies"
    ax.set_xlabel(f"slipping fractures (of {total})")
    ax.set_ylabel("realizations")
    # both axes count: no fractional ticks
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    if counts.size:
        ax.set_title(
            f"{counts.size} realizations: mean {counts.mean():.1f}, "
            f"std {counts.std(ddof=1) if counts.size > 1 else 0.0:.1f}",
            fontsize=9,
        )


def figure_network(
    spec: CaseSpec, result: Path | None = None, summary: Path | None = None
):
    """The network of ``spec`` (slip from ``result``), plus the slipping-count
    histogram of a sweep ``summary`` when given."""
    n = 2 if summary is not None else 1
    fig = Figure(figsize=(PANEL * n + 1.0 * (result is not None), PANEL))
    axes = fig.subplots(1, n, squeeze=False)[0]
    _domain_frame(axes[0], spec)
    if result is not None:
        _draw_slip(fig, axes[0], read_result_slip(result, len(spec.fractures)))
        axes[0].set_title(f"{spec.name}: |slip| (thick: slipping)", fontsize=9)
    else:
        _draw_plain(axes[0], spec)
        axes[0].set_title(f"{spec.name}: {len(spec.fractures)} fractures", fontsize=9)
    if summary is not None:
        _draw_counts(axes[1], *read_slipping_counts(summary))
    fig.tight_layout()
    return fig


def save(fig, path: Path, dpi: int = 110) -> None:
    """Write the figure; OutputError if the file cannot be written."""
    try:
        fig.savefig(path, dpi=dpi, bbox_inches="tight")
    except (OSError, ValueError) as exc:
        raise OutputError(f"{path}: cannot write the figure: {exc}") from None
