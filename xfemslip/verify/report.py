"""Output of ``xfemslip verify``: the table, the CSV file and the plot.

The rows, the window sweep and the missed targets come from
``xfemslip.verify.problems.run_verification``; nothing here computes an error.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from xfemslip import display
from xfemslip.io.csv import write_rows
from xfemslip.io.fileset import replace_files
from xfemslip.verify.problems import (
    HALF_LENGTH,
    SLIP_TARGET,
    TARGET_H,
    WINDOW_FRICTION,
    WINDOW_MESH,
    Report,
    window_edges,
)


def _pct(x: float) -> str:
    return "-" if not math.isfinite(x) else f"{100 * x:.3g}"


def format_table(report: Report) -> str:
    """The table printed by ``xfemslip verify``."""
    head = [
        "problem",
        "mesh",
        "dofs",
        "slip L2 %",
        "K_II err %",
        "|K_I|/K %",
        "osc t_N %",
        "order",
        "Newton",
        "wall s",
        "note",
    ]
    rows = [
        [
            r.problem,
            f"a/{r.a_over_h}",
            str(r.dofs),
            _pct(r.slip_error),
            _pct(r.kii_error),
            _pct(r.ki_ratio),
            _pct(r.oscillation),
            "-" if not math.isfinite(r.order) else f"{r.order:.2f}",
            str(r.newton),
            f"{r.wall_s:.2f}",
            r.note,
        ]
        for r in report.rows
    ]
    table = display.table(head, rows, left=(0, 10)).splitlines()
    lines = [table[0], "-" * len(table[0]), *table[1:]]
    if report.window:
        (lo, hi), _ = window_edges()
        bad = [w for w in report.window if w.misclassified]
        worst = max((w.distance for w in bad), default=0.0)
        lines += [
            "",
            f"slip window (f = {WINDOW_FRICTION}, h = a/{WINDOW_MESH}): exact "
            f"beta in ({lo:.2f}, {hi:.2f}) deg; {len(report.window)} orientations, "
            f"{len(bad)} misclassified, farthest {worst:.2f} deg from an edge",
        ]
        lines += [
            f"  beta {w.beta:6.2f}  exact {'slip ' if w.slips_exact else 'stick'}  "
            f"slipping points {100 * w.slip_share:5.1f} %"
            + ("  MISCLASSIFIED" if w.misclassified else "")
            for w in report.window
        ]
    lines.append("")
    if not any(r.a_over_h == 40 for r in report.rows):
        lines.append("observed-order target not checked: it needs h = a/40 (full run)")
    if report.failures:
        lines.append("targets missed:")
        lines += [f"  - {f}" for f in report.failures]
    else:
        lines.append("all targets met")
    return "\n".join(lines)


CSV_FIELDS = (
    "problem",
    "a_over_h",
    "dofs",
    "slip_error",
    "kii_error",
    "ki_ratio",
    "oscillation",
    "order",
    "newton",
    "wall_s",
)


def write_outputs(report: Report, csv_path: Path | None, plot: Path | None) -> None:
    """``--csv`` and ``--plot``, written as one set (``replace_files``)."""
    writes = {}
    if csv_path is not None:
        writes[Path(csv_path)] = lambda tmp: write_csv(report, tmp)
    if plot is not None:
        fmt = Path(plot).suffix.lower().lstrip(".")
        writes[Path(plot)] = lambda tmp: write_plot(report, tmp, fmt)
    replace_files(writes)


def write_csv(report: Report, path: Path) -> None:
    """The table as CSV (one row per problem and mesh) into ``path``."""
    tip = report.tip or "default"
    rows = ([getattr(r, k) for k in CSV_FIELDS] + [tip] for r in report.rows)
    write_rows(path, [*CSV_FIELDS, "tip"], rows)


def figure_verify(report: Report):
    """Error against h and against wall time (a matplotlib Figure): log axes
    with their ticks labelled however short their range, the legends below
    the panels, over no data."""
    from matplotlib.figure import Figure

    from xfemslip.plot.style import label_log_axis

    fig = Figure(figsize=(11, 5.2), layout="constrained")
    ax1, ax2 = fig.subplots(1, 2)
    by: dict[str, list] = {}
    for r in report.rows:
        if r.problem.startswith("stick"):
            continue
        by.setdefault(r.problem, []).append(r)
    for k, (name, seq) in enumerate(by.items()):
        seq.sort(key=lambda r: r.a_over_h)
        color = f"C{k % 10}"
        h = [HALF_LENGTH / r.a_over_h for r in seq]
        e = [r.slip_error for r in seq]
        kk = [max(r.kii_error, 1e-6) for r in seq]
        t = [r.wall_s for r in seq]
        ax1.loglog(h, e, "o-", color=color, label=f"{name} slip")
        ax1.loglog(h, kk, "s--", color=color, alpha=0.6, label=f"{name} K_II")
        ax2.loglog(t, e, "o-", color=color, label=name)
    if by:
        h_all = np.array(sorted({HALF_LENGTH / r.a_over_h for r in report.rows}))
        e_ref = max(
            r.slip_error
            for r in report.rows
            if r.a_over_h == min(r.a_over_h for r in report.rows)
        )
        ax1.loglog(h_all, e_ref * (h_all / h_all.max()), "k:", label="order 1")
    ax1.axvline(HALF_LENGTH / TARGET_H, color="grey", lw=0.8)
    for ax in (ax1, ax2):
        ax.axhline(SLIP_TARGET, color="grey", lw=0.8)
        ax.grid(True, which="both", alpha=0.3)
        ax.set_ylabel("relative error")
        ax.autoscale_view()
        label_log_axis(ax.xaxis)
        label_log_axis(ax.yaxis)
    ax1.set_xlabel("h [m] (a = 0.5 m; grey: h = a/20, 1 %)")
    ax2.set_xlabel("wall time per run [s] (build + solve, in-process)")
    ax1.set_title("error against mesh size")
    ax2.set_title("slip error against wall time")
    for ax, ncol in ((ax1, 3), (ax2, 3)):
        ax.legend(
            loc="upper center",
            bbox_to_anchor=(0.5, -0.16),
            ncol=ncol,
            fontsize=7,
        )
    fig.suptitle(f"xfemslip verify (tip = {report.tip or 'default'})")
    return fig


def write_plot(report: Report, path: Path, fmt: str | None = None) -> None:
    """:func:`figure_verify` into ``path`` (``fmt`` png or pdf; default: by
    the suffix of ``path``)."""
    figure_verify(report).savefig(path, dpi=110, format=fmt, bbox_inches="tight")
