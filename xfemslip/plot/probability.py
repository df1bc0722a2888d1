"""Figure of an uncertainty study: probability of slip against depletion.

Imported only when plotting (matplotlib is not a dependency of a run;
``matplotlib.figure.Figure``, no pyplot).  The probability that a fracture
has slipped by a pore-pressure change is known at the study's levels, so it
is drawn as steps between them; curves that lie on each other get different
dashes and markers and the legend says so; the y axis spans the data; the
Wilson bands are drawn when they are wider than a line, and the title says
when they are not.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from xfemslip.plot.style import DASHES, MARKERS, pressure_change_axis

# curves closer than this fraction of the y range lie on each other
COINCIDENT = 0.02
# bands narrower than this fraction of the y range hide under their line
VISIBLE_BAND = 0.015


def _coincident_with(probability: np.ndarray, span: float) -> list[int | None]:
    """For each curve, the first earlier curve it lies on (None if none)."""
    out: list[int | None] = []
    for j, p in enumerate(probability):
        near = [
            i
            for i in range(j)
            if np.max(np.abs(probability[i] - p)) <= COINCIDENT * span
        ]
        out.append(near[0] if near else None)
    return out


def figure_probability(result) -> Figure:
    """P that each fracture has slipped against the pore-pressure change
    [MPa] (its magnitude to the right), with its Wilson band."""
    spec = result.spec
    x, xlabel = pressure_change_axis(np.asarray(spec.levels, float))
    probability = np.asarray(result.probability, float)
    low, high = np.asarray(result.ci_low, float), np.asarray(result.ci_high, float)
    top = min(1.0, 1.1 * float(np.max(high))) if high.size else 1.0
    top = max(top, 0.05)
    fig = Figure(figsize=(7.4, 4.2), layout="constrained")
    ax = fig.subplots()
    half = float(np.max(high - low)) / 2.0 if high.size else 0.0
    bands = 2.0 * half >= VISIBLE_BAND * top
    under = _coincident_with(probability, top)
    for j, fi in enumerate(result.fractures):
        colour = f"C{j % 10}"
        if bands:
            ax.fill_between(
                x, low[j], high[j], step="post", color=colour, alpha=0.2, lw=0
            )
        label = f"fracture {fi}"
        if under[j] is not None:
            label += f" (on fracture {result.fractures[under[j]]}'s curve)"
        ax.plot(
            x,
            probability[j],
            drawstyle="steps-post",
            ls=DASHES[j % len(DASHES)],
            marker=MARKERS[j % len(MARKERS)],
            ms=3.5 + 1.5 * (under[j] is None),
            mfc="white" if under[j] is not None else colour,
            color=colour,
            label=label,
        )
    ax.set_xlabel(xlabel)
    ax.set_ylabel("probability of slip")
    ax.set_ylim(0.0, top)
    ax.set_xlim(min(float(x.min()), 0.0), float(x.max()))
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small")
    confidence = f"{spec.confidence:.0%}"
    if bands:
        what = f"shaded: {confidence} Wilson bands"
    else:
        what = (
            f"{confidence} Wilson bands narrower than the lines "
            f"(half-width at most {half:.2g})"
        )
    ax.set_title(
        f"{spec.base_spec.name}: {result.evaluated} samples ({spec.evaluate})\n"
        f"steps: P at each level; {what}",
        fontsize="medium",
    )
    return fig


def plot_probability(result, path: Path, dpi: float = 110.0) -> Path:
    """:func:`figure_probability` written to ``path`` (PNG)."""
    figure_probability(result).savefig(path, dpi=dpi, format="png", bbox_inches="tight")
    return Path(path)
