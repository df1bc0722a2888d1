"""Figures of fracture networks (matplotlib, imported only here and only when
a figure is drawn; ``matplotlib.figure.Figure``, no pyplot, no GUI backend).

``figure_network``: the fractures of a case in its domain, coloured by
the ``|slip|`` that slid (the plastic slip) [mm] at the contact points when
a ``result.h5`` is given (slipping fractures drawn thicker), else by origin;
beside it a rose diagram of the fractures' orientations and a histogram of
their lengths; with a sweep's ``summary.csv`` a last panel shows how many
fractures slip over the realizations.
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
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")


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
    norm = Normalize(0.0, 1e3 * top if top > 0 else 1.0)
    collection = None
    for points, slip, state in fields:
        if len(points) < 2:
            continue
        pieces = np.stack([points[:-1], points[1:]], axis=1)
        value = 0.5e3 * (np.abs(slip[:-1]) + np.abs(slip[1:]))  # [mm]
        width = 2.6 if np.any(state == SLIP) else 1.0
        collection = LineCollection(
            list(pieces), cmap="viridis", norm=norm, linewidths=width
        )
        collection.set_array(value)
        ax.add_collection(collection)
    if collection is not None:
        fig.colorbar(collection, ax=ax, label="|slip| that slid [mm]", shrink=0.8)


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


ROSE_BIN_DEG = 10.0


def orientations_and_lengths(spec: CaseSpec) -> tuple[np.ndarray, np.ndarray]:
    """(angle of each fracture's chord in [0, 180) deg, length along its
    polyline [m])."""
    angles, lengths = [], []
    for fracture in spec.fractures:
        p = np.asarray(fracture.points, dtype=float)
        d = p[-1] - p[0]
        angles.append(np.degrees(np.arctan2(d[1], d[0])) % 180.0)
        lengths.append(float(np.sum(np.linalg.norm(np.diff(p, axis=0), axis=1))))
    return np.array(angles), np.array(lengths)


def _draw_rose(ax, angles: np.ndarray) -> None:
    """Rose diagram: how many fractures per ROSE_BIN_DEG of orientation,
    drawn at theta and theta + 180 (a line has no direction)."""
    edges = np.arange(0.0, 180.0 + ROSE_BIN_DEG, ROSE_BIN_DEG)
    counts, _ = np.histogram(angles, bins=edges)
    width = np.radians(ROSE_BIN_DEG)
    for turn in (0.0, np.pi):
        ax.bar(
            np.radians(edges[:-1]) + turn,
            counts,
            width=width,
            align="edge",
            color="tab:blue",
            edgecolor="k",
            lw=0.5,
        )
    ax.set_theta_zero_location("E")
    ax.set_theta_direction(1)
    ax.set_thetagrids(range(0, 360, 45), fontsize=7)
    ax.yaxis.set_major_locator(MaxNLocator(3, integer=True))
    ax.tick_params(axis="y", labelsize=7)
    ax.set_title(
        f"orientations ({ROSE_BIN_DEG:g} deg bins, count;\nangle from x, "
        "counter-clockwise)",
        fontsize=9,
    )


def _draw_lengths(ax, lengths: np.ndarray) -> None:
    """Histogram of the fracture lengths [m]: about sqrt(n) bins (at most
    30); lengths all equal (to rounding) make one bar 10 % wide."""
    lengths = lengths[np.isfinite(lengths)]
    lo, hi = (float(lengths.min()), float(lengths.max())) if lengths.size else (0, 1)
    if hi - lo <= 1e-6 * max(abs(hi), 1e-300):
        pad = 0.05 * abs(hi) or 0.5
        lo, hi, bins = lo - pad, hi + pad, 1
    else:
        bins = int(np.clip(np.ceil(np.sqrt(lengths.size)), 1, 30))
    ax.hist(lengths, bins=bins, range=(lo, hi), color="tab:blue", edgecolor="k")
    ax.set_xlabel("fracture length [m]")
    ax.set_ylabel("fractures")
    ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    if lengths.size:
        ax.set_title(
            f"{lengths.size} lengths: {lengths.min():.3g} to {lengths.max():.3g} m",
            fontsize=9,
        )


def figure_network(
    spec: CaseSpec, result: Path | None = None, summary: Path | None = None
):
    """The network of ``spec`` (slip from ``result``), the rose diagram of
    its orientations, the histogram of its lengths, and the slipping-count
    histogram of a sweep ``summary`` when given."""
    n = 4 if summary is not None else 3
    width = PANEL * (1.0 + 0.75 * (n - 1)) + 1.0 * (result is not None)
    fig = Figure(figsize=(width, PANEL), layout="constrained")
    grid = fig.add_gridspec(1, n, width_ratios=[1.35] + [1.0] * (n - 1))
    ax_net = fig.add_subplot(grid[0])
    _domain_frame(ax_net, spec)
    if result is not None:
        _draw_slip(fig, ax_net, read_result_slip(result, len(spec.fractures)))
        ax_net.set_title(f"{spec.name}: |slip| (thick: slipping)", fontsize=9)
    else:
        _draw_plain(ax_net, spec)
        ax_net.set_title(f"{spec.name}: {len(spec.fractures)} fractures", fontsize=9)
    angles, lengths = orientations_and_lengths(spec)
    _draw_rose(fig.add_subplot(grid[1], projection="polar"), angles)
    _draw_lengths(fig.add_subplot(grid[2]), lengths)
    if summary is not None:
        _draw_counts(fig.add_subplot(grid[3]), *read_slipping_counts(summary))
    return fig


def save(fig, path: Path, dpi: int = 110) -> None:
    """Write the figure; OutputError if the file cannot be written."""
    try:
        fig.savefig(path, dpi=dpi, bbox_inches="tight")
    except (OSError, ValueError) as exc:
        raise OutputError(f"{path}: cannot write the figure: {exc}") from None
